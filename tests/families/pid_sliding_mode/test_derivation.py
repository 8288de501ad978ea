"""The sliding variable's transfer function and the §5.4 perturbation, by routes independent of the family's code:
SymPy on the state equations, python-control on the closed loop, and a direct simulation of the true link."""

from __future__ import annotations

import control
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from designkit.families.pid_sliding_mode.surface import l1_norm, perturbation_of_change, surface
from designkit.models.link import LinkPlant
from designkit.synthesis import pid


def test_slm_dot_is_p3_slm_plus_a2_Km_over_tau_times_the_input_symbolically():
    """With the PID zero on p3, slm' = p3 slm + (a2 Km/tau) w for every state and reference (SymPy)."""
    p1, p2, p3, Km, tau = sp.symbols("p1 p2 p3 Km tau")
    x1, x2, x3, xD, w = sp.symbols("x1 x2 x3 xD w")
    S1, S2, S3 = p1 + p2 + p3, p1 * p2 + p1 * p3 + p2 * p3, p1 * p2 * p3
    K1, K2, K3 = tau * S2 / Km, -(tau * S1 + 1) / Km, -tau * S3 / Km
    K4 = -(K3 + K1 * p3) / (K3 * p3)
    a1, a2 = -(1 / p1 + 1 / p2), 1 / (p1 * p2)
    u0 = -K1 * (x1 - xD) - K2 * x2 - K3 * x3 + K3 * K4 * xD
    x2dot = -x2 / tau + Km / tau * (u0 + w)
    slm = a1 * x1 + a2 * x2 + x3
    slm_dot = a1 * x2 + a2 * x2dot + (x1 - xD)
    assert sp.simplify(slm_dot - (p3 * slm + a2 * Km / tau * w)) == 0
    assert sp.simplify(K4 + a1) == 0  # so slm(0) = (a1 + K4) q0 = 0 from rest with x3(0) = K4 q0


def test_tracking_form_has_the_same_sliding_dynamics():
    p1, p2, p3, Km, tau = sp.symbols("p1 p2 p3 Km tau")
    d1, d2, x3, w = sp.symbols("d1 d2 x3 w")
    S1, S2, S3 = p1 + p2 + p3, p1 * p2 + p1 * p3 + p2 * p3, p1 * p2 * p3
    K1, K2, K3 = tau * S2 / Km, -tau * S1 / Km, -tau * S3 / Km
    a1, a2 = -(1 / p1 + 1 / p2), 1 / (p1 * p2)
    # dx2' = x2' - xD'' with u0 = (tau/Km) xD'' + x2/Km - K1 d1 - K2 d2 - K3 x3: the x2 and xD'' terms cancel
    d2dot = Km / tau * (-K1 * d1 - K2 * d2 - K3 * x3 + w)
    slm = a1 * d1 + a2 * d2 + x3
    assert sp.simplify(a1 * d2 + a2 * d2dot + d1 - (p3 * slm + a2 * Km / tau * w)) == 0


@pytest.mark.parametrize("poles", [(-4, -5, -20), (-3 + 2j, -3 - 2j, -15), (-6, -6, -30)])
def test_transfer_from_input_to_slm_against_python_control(poles):
    """slm(s)/w(s) = Km/(tau p1 p2 (s - p3)) and slm(s)/xD(s) = 0 on the closed loop built by python-control;
    the notes' Km/tau lacks the 1/(p1 p2)."""
    plant = LinkPlant(Km=2.0, tau=0.5)
    sf = surface(poles)
    g = pid.servo_gains(plant, poles, sf.p3)
    Km, tau = 2.0, 0.5
    # states x1, x2, x3; inputs xD, w; output slm
    A = np.array([[0, 1, 0], [-Km / tau * g["K1"], -1 / tau - Km / tau * g["K2"], -Km / tau * g["K3"]], [1, 0, 0]])
    B = np.array([[0, 0], [Km / tau * (g["K1"] + g["K3"] * g["K4"]), Km / tau], [-1, 0]])
    C = np.array([[sf.a1, sf.a2, 1.0]])
    sys = control.ss(A, B, C, np.zeros((1, 2)))
    w_to_slm = control.minreal(control.tf(sys[0, 1]), verbose=False)
    expected = control.tf([Km / (tau * (sf.p1 * sf.p2).real)], [1, -sf.p3])
    for s in (0.3j, 1.0 + 2j, 7.0):
        assert complex(w_to_slm(s)) == pytest.approx(complex(expected(s)), rel=1e-9)
        assert abs(complex(control.tf(sys[0, 0])(s))) < 1e-9
        assert abs(complex(w_to_slm(s)) - Km / tau / (s - sf.p3)) > 0.1 * abs(Km / tau / (s - sf.p3))


def test_l1_norm_of_s_over_N_against_python_control():
    sf = surface((-4, -5, -20))
    t = np.linspace(0, 12, 240001)
    resp = control.impulse_response(control.tf([1, 0], [sf.a2, sf.a1, 1]), t)
    assert l1_norm(sf) == pytest.approx(float(np.trapezoid(np.abs(resp.y[0, 0]), t)), rel=1e-5)


@pytest.mark.parametrize(("Km", "tau"), [(1.3, 0.7), (2.6, 0.35), (1.6, 0.45)])
def test_section_5_4_perturbation_reproduces_the_true_link(Km, tau):
    """The nominal link driven by u0 plus (Km/tau) xi (xi of section 5.4 on its own state) moves exactly as the true
    link under the same PID: two independent simulations coincide."""
    Km0, tau0 = 2.0, 0.5
    g = pid.servo_gains(LinkPlant(Km=Km0, tau=tau0), (-4, -5, -20), -20.0)

    def u0(x):
        return -g["K1"] * (x[0] - 1.0) - g["K2"] * x[1] - g["K3"] * x[2] + g["K3"] * g["K4"] * 1.0

    def true(_, x):
        return [x[1], -x[1] / tau + Km / tau * u0(x), x[0] - 1.0]

    def nominal(_, x):
        xi = perturbation_of_change(x[1], u0(x), Km, tau, Km0, tau0)
        return [x[1], -x[1] / tau0 + Km0 / tau0 * u0(x) + Km / tau * xi, x[0] - 1.0]

    t = np.linspace(0, 3, 301)
    a = solve_ivp(true, (0, 3), [0, 0, 0], t_eval=t, rtol=1e-11, atol=1e-12).y
    b = solve_ivp(nominal, (0, 3), [0, 0, 0], t_eval=t, rtol=1e-11, atol=1e-12).y
    assert np.max(np.abs(a - b)) < 1e-8
    # the notes' printed expression (tau/Km)[(1/tau0 - 1/tau) x2 + (Km/tau - Km0/(Km tau0)) u0] does not
    x = a[:, 0]
    printed = (tau / Km) * ((1 / tau0 - 1 / tau) * x[1] + (Km / tau - Km0 / (Km * tau0)) * u0(x))
    assert abs(printed - perturbation_of_change(x[1], u0(x), Km, tau, Km0, tau0)) > 1e-3
