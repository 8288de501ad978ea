"""The derivation of the sliding-mode conditions, checked by SymPy and by integrating the plant (scipy).

Nothing here reads the family's formulas to get an expected value: SymPy differentiates ``s`` along the plant's
flow, solves for the equivalent control and expands the angle of the phase point; scipy integrates the link
ODE under each structure.  The family's functions are then compared with those results.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from designkit.families.sliding_mode.conditions import (
    SlidingGains,
    condition_sets,
    existence_bound,
    focus_bound,
    strip_width,
)

x1, x2, xD, c, a, b, u, xi, M, psi, al, be, sig = sp.symbols("x1 x2 xD c a b u xi M psi alpha beta sigma", real=True)
Km, tau = sp.symbols("Km tau", positive=True)
E = x1 - xD
S = x2 + c * E
SDOT = sp.diff(S, x1) * x2 + sp.diff(S, x2) * (-a * x2 + b * (u + xi))  # xD' = 0 between reference jumps


def test_s_dot_along_the_link():
    assert sp.expand(SDOT - ((c - a) * x2 + b * (u + xi))) == 0
    law = SDOT.subs(u, -psi * E - M * sig)  # sig = sign(s)
    K = c * (c - a) + b * psi
    assert sp.expand(law - ((c - a) * S - K * E - b * M * sig + b * xi)) == 0
    # s s' = (c - a) s^2 - K e s - b M sig s + b xi s, and sig s = |s|: (c - a) s^2 - K e s - b (M - xi sig)|s|
    assert sp.expand(S * law - ((c - a) * S**2 - K * E * S - b * M * sig * S + b * xi * S)) == 0


def test_equivalent_control_and_the_existence_bound():
    u_eq = sp.solve(sp.Eq(SDOT.subs(x2, -c * E), 0), u)[0]  # on s = 0: x2 = -c e
    k = (a - c) * c / b
    assert sp.simplify(u_eq - (-k * E - xi)) == 0
    k_link = sp.simplify(k.subs({a: 1 / tau, b: Km / tau}))
    assert sp.simplify(k_link - c * (1 - c * tau) / Km) == 0
    rng = np.random.default_rng(1)
    for _ in range(20):
        cv, kmv, tv = rng.uniform(0.1, 20), rng.uniform(0.1, 5), rng.uniform(0.05, 2)
        assert float(existence_bound(cv, kmv, tv)) == pytest.approx(float(k_link.subs({c: cv, Km: kmv, tau: tv})))
        assert float(focus_bound(kmv, tv)) == pytest.approx(float((a**2 / (4 * b)).subs({a: 1 / tv, b: kmv / tv})))


def test_utkin_existence_is_alpha_above_k_beta_below_k_and_M_above_xi():
    """u_eq strictly between u+ (s > 0) and u- (s < 0) for every e, sampled, iff the three printed conditions."""
    rng = np.random.default_rng(7)
    e = np.concatenate([-np.logspace(-3, 4, 200), np.logspace(-3, 4, 200)])
    agree = 0
    for _ in range(400):
        av, bv, cv = rng.uniform(0.2, 5), rng.uniform(0.2, 10), rng.uniform(0.2, 10)
        k = (av - cv) * cv / bv
        alpha = k + rng.choice([-1, 1]) * rng.uniform(0.05, 2)
        beta = k + rng.choice([-1, 1]) * rng.uniform(0.05, 2)
        Mv, xiv = rng.uniform(0.1, 2), rng.uniform(-2, 2)
        u_eq = -k * e - xiv
        psi_plus = np.where(e > 0, alpha, beta)  # s > 0: psi = alpha where e > 0
        psi_minus = np.where(e > 0, beta, alpha)
        u_plus, u_minus = -psi_plus * e - Mv, -psi_minus * e + Mv
        between = bool(np.all((u_plus < u_eq) & (u_eq < u_minus)))
        predicted = bool(alpha >= k and beta <= k and Mv > abs(xiv))
        assert between is predicted
        agree += 1
    assert agree == 400


def test_s_sdot_bound_from_the_plant_ode():
    """With the existence conditions, s s' <= (c - a) s^2 - b (M - |xi|)|s| at random states (s' from the ODE)."""
    rng = np.random.default_rng(3)
    for _ in range(2000):
        av, bv, cv = rng.uniform(0.2, 5), rng.uniform(0.2, 10), rng.uniform(0.2, 10)
        k = (av - cv) * cv / bv
        alpha, beta = k + rng.uniform(0, 2), k - rng.uniform(0, 2)
        Mv = rng.uniform(0.1, 2)
        xiv = rng.uniform(-Mv, Mv)
        e, v = rng.normal(0, 3), rng.normal(0, 10)
        s = v + cv * e
        p = alpha if e * s > 0 else beta
        uv = -p * e - Mv * np.sign(s)
        sdot = v * cv + (-av * v + bv * (uv + xiv))  # d/dt (x2 + c e) with e' = x2
        assert s * sdot <= (cv - av) * s**2 - bv * (Mv - abs(xiv)) * abs(s) + 1e-9 * (1 + s**2)


def test_the_printed_max_is_always_the_focus_bound():
    assert sp.expand((a - c) * c - a**2 / 4 + (c - a / 2) ** 2) == 0  # (a - c) c <= a^2/4, equal at c = a/2


def test_focus_is_the_positive_definite_angle_form():
    e, v, f = sp.symbols("e v f", real=True)
    theta_dot = (e * (-a * v - b * al * e + f) - v * v) / (e**2 + v**2)  # d/dt atan2(v, e), e' = v
    Q = b * al * e**2 + a * e * v + v**2
    assert sp.simplify(theta_dot - (-Q + e * f) / (e**2 + v**2)) == 0
    mat = sp.Matrix([[b * al, a / 2], [a / 2, 1]])
    assert sp.expand(mat.det() - (b * al - a**2 / 4)) == 0  # PD iff a^2 < 4 b alpha
    mu = sp.Symbol("mu")
    disc = sp.discriminant(mu**2 + a * mu + b * al, mu)
    assert sp.expand(disc - (a**2 - 4 * b * al)) == 0  # complex roots (a focus) iff the same


def _alpha_structure(av, bv, alpha, z0, T):
    """The link under u = -alpha e (M = 0, xi = 0) from z0 = (e, e') until s = e' + c e = 0 or T."""
    def rhs(_t, z):
        return [z[1], -av * z[1] - bv * alpha * z[0]]

    def hit(_t, z):
        return z[1] + CV * z[0]

    hit.terminal = True
    return solve_ivp(rhs, (0, T), z0, events=hit, rtol=1e-10, atol=1e-12)


CV = 5.0


def test_without_the_focus_a_trajectory_reaches_the_origin_inside_e_s_positive():
    """c > a/2, k < alpha < a^2/(4b): the slow eigenvector e' = mu e lies in e s > 0 and the pure variable
    structure (M = 0) never meets s = 0 from it; above the focus bound the same start meets it."""
    av, bv = 2.0, 4.0  # the POSSPEED link
    k = (av - CV) * CV / bv
    alpha = 0.5 * av**2 / (4 * bv)  # real roots
    assert k < alpha < av**2 / (4 * bv)
    mu = max(np.roots([1, av, bv * alpha]).real)
    assert mu > -CV  # the eigenvector line is inside e s > 0: s = (mu + c) e has the sign of e
    # 18 time constants of the slow mode (to 1.5e-8): far enough to be at the origin, not so far that the integrator
    # meets s = 0 in the rounding of a 1e-13 state
    stay = _alpha_structure(av, bv, alpha, [-1.0, -mu], 18.0 / abs(mu))
    assert stay.t_events[0].size == 0 and abs(stay.y[0, -1]) < 1e-6  # to the origin, never sliding
    focus = _alpha_structure(av, bv, 1.2 * av**2 / (4 * bv), [-1.0, -mu], 40.0 / abs(mu))
    assert focus.t_events[0].size == 1


def test_condition_expressions_are_the_multiplied_bounds():
    import casadi as ca

    g = SlidingGains(alpha=0.7, beta=-9.0, M=1.3, c=CV)
    sets = condition_sets(g, 1.0)
    rng = np.random.default_rng(5)
    for _ in range(10):
        kmv, tv = rng.uniform(0.5, 3), rng.uniform(0.1, 1)
        p = {"Km": ca.SX(kmv), "tau": ca.SX(tv)}
        ea, eb = (float(ca.DM(cond.expression(p))) for cond in sets["existence"].conditions)
        (fo,) = (float(ca.DM(cond.expression(p))) for cond in sets["reaching"].conditions)
        (pe,) = (float(ca.DM(cond.expression(p))) for cond in sets["perturbation"].conditions)
        k = CV * (1 - CV * tv) / kmv
        assert ea == pytest.approx(kmv * (g.alpha - k))
        assert eb == pytest.approx(kmv * (k - g.beta))
        assert fo == pytest.approx(4 * kmv * tv * (g.alpha - 1 / (4 * kmv * tv)))
        assert pe == pytest.approx(g.M - 1.0)


def test_strip_width_against_a_dense_grid():
    """Inside the strip the bound (c - a) s^2 - b (M - xi)|s| is negative on the whole box; just outside it is not."""
    box = {"Km": (1.4, 2.6), "tau": (0.35, 0.65)}
    width = strip_width(1.2, 1.0, CV, box)
    Kg, Tg = np.meshgrid(np.linspace(*box["Km"], 101), np.linspace(*box["tau"], 101))
    A, B = 1 / Tg, Kg / Tg

    def worst(s):
        return np.max((CV - A) * s**2 - B * 0.2 * s)

    assert worst(0.999 * width) < 0 < worst(1.001 * width)
    assert strip_width(1.2, 1.0, 1.0, box) == np.inf  # c tau_hi <= 1: everywhere
    assert strip_width(0.8, 1.0, CV, box) == 0.0
