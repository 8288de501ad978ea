"""The sampled link and the design on it, against independent routes: scipy's ZOH model, python-control's
discrete loops, the ARX equations on an exactly sampled trajectory."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from designkit.families.self_tuning.model import (
    desired_polynomial,
    diophantine,
    discretize,
    link_of,
    position_model,
    sylvester,
    theta_of,
)
from tests.families.self_tuning.oracles import closed_loop_poles, position_tf, theta_scipy, zoh

LINKS = [(2.0, 0.5, 0.01), (1.0, 0.8, 0.01), (2.0, 0.5, 0.001), (0.3, 3.0, 0.2), (5.0, 0.05, 0.1)]


@pytest.mark.parametrize(("Km", "tau", "Ts"), LINKS)
def test_zoh_model_is_scipys(Km, tau, Ts):
    A, B = discretize(Km, tau, Ts)
    Ad, Bd = zoh(Km, tau, Ts)
    np.testing.assert_allclose(A, Ad, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(B, Bd, rtol=1e-9, atol=1e-18)


@pytest.mark.parametrize("form", ["speed", "position"])
@pytest.mark.parametrize(("Km", "tau", "Ts"), LINKS)
def test_both_forms_parameters_from_scipy(Km, tau, Ts, form):
    np.testing.assert_allclose(theta_of(Km, tau, Ts, form), theta_scipy(Km, tau, Ts, form), rtol=1e-8, atol=1e-18)


@pytest.mark.parametrize(("Km", "tau", "Ts"), LINKS)
def test_both_regressions_hold_exactly_on_an_exactly_sampled_trajectory(Km, tau, Ts):
    """x(k+1) = Ad x(k) + Bd u(k) from scipy with random inputs: the speed equation (fig. 4.1) and the
    position-difference equation (fig. 4.2, re-derived) hold to rounding."""
    Ad, Bd = zoh(Km, tau, Ts)
    rng = np.random.default_rng(1)
    u = rng.normal(size=60)
    x = np.zeros((61, 2))
    x[0] = [0.3, -0.2]
    for k in range(60):
        x[k + 1] = Ad @ x[k] + Bd * u[k]
    A22, B2 = theta_of(Km, tau, Ts, "speed")
    np.testing.assert_allclose(x[1:, 1], A22 * x[:-1, 1] + B2 * u, rtol=0, atol=1e-12 * (1 + np.abs(x).max()))
    th = theta_of(Km, tau, Ts, "position")
    d = np.diff(x[:, 0])  # d(k) = x1(k+1) - x1(k)
    pred = th[0] * d[:-1] + th[1] * u[1:] + th[2] * u[:-1]  # d(k+1) = A22 d(k) + B1 u(k+1) + c u(k)
    np.testing.assert_allclose(d[1:], pred, rtol=0, atol=1e-12 * (1 + np.abs(x).max()))


@pytest.mark.parametrize("form", ["speed", "position"])
@pytest.mark.parametrize(("Km", "tau", "Ts"), LINKS)
def test_position_transfer_function_is_python_controls_c2d(Km, tau, Ts, form):
    a1, a2, b0, b1 = position_model(theta_of(Km, tau, Ts, form), Ts, form)
    num, den = position_tf(Km, tau, Ts)
    num = num / den[0]
    den = den / den[0]
    np.testing.assert_allclose([1.0, a1, a2], den, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose([b0, b1], num[-2:], rtol=1e-6, atol=1e-16)


@pytest.mark.parametrize(("Km", "tau", "Ts"), LINKS)
def test_link_recovered_from_the_speed_parameters(Km, tau, Ts):
    A22, B2 = theta_scipy(Km, tau, Ts, "speed")
    np.testing.assert_allclose(link_of(A22, B2, Ts), (Km, tau), rtol=1e-9)


def test_sylvester_determinant_is_the_resultant_and_vanishes_on_a_common_factor():
    a1, a2, b0, b1 = -1.7, 0.72, 0.5, -0.45  # A = (z - 0.8)(z - 0.9), B = 0.5 (z - 0.9): common factor
    assert abs(np.linalg.det(sylvester(a1, a2, b0, b1))) < 1e-14
    # away from it, the determinant is b0^2 A(-b1/b0) (numpy's polynomial value)
    b1 = 0.1
    np.testing.assert_allclose(np.linalg.det(sylvester(a1, a2, b0, b1)), b0**2 * np.polyval([1, a1, a2], -b1 / b0))
    assert np.linalg.cond(sylvester(a1, a2, b0, -0.4499)) > 1e3 * np.linalg.cond(sylvester(a1, a2, b0, 0.1))


@pytest.mark.parametrize(("Km", "tau", "Ts"), LINKS[:4])
def test_diophantine_places_the_poles_of_the_discrete_loop(Km, tau, Ts):
    poles, observer = (-4.0, -5.0), -10.0
    model = position_model(theta_of(Km, tau, Ts, "position"), Ts, "position")
    r1, s0, s1 = diophantine(model, desired_polynomial(poles, observer, Ts))
    got = closed_loop_poles(np.array(model[2:]), np.array([1.0, *model[:2]]), np.array([1.0, r1]),
                            np.array([s0, s1]), Ts)
    want = np.sort_complex(np.exp(np.array([*poles, observer], dtype=complex) * Ts))
    np.testing.assert_allclose(got, want, atol=1e-6)


@settings(max_examples=60, deadline=None)
@given(a=st.floats(0.05, 0.995), b0=st.floats(0.01, 2.0), zb=st.floats(-3.0, 0.9),
       p=st.lists(st.floats(-0.9, 0.95), min_size=3, max_size=3))
def test_diophantine_for_random_coprime_models(a, b0, zb, p):
    """A = (z - 1)(z - a), B = b0 (z - zb) with zb away from the roots of A; random real desired poles."""
    assume(min(abs(zb - 1.0), abs(zb - a)) > 0.05)
    a1, a2, b1 = -(1 + a), a, -b0 * zb
    c = np.real(np.poly(p))[1:]
    r1, s0, s1 = diophantine((a1, a2, b0, b1), c)
    got = np.polyadd(np.polymul([1, a1, a2], [1, r1]), np.polymul([b0, b1], [s0, s1]))
    np.testing.assert_allclose(got, np.poly(p), atol=1e-8 * np.linalg.cond(sylvester(a1, a2, b0, b1)))
    poles = closed_loop_poles(np.array([b0, b1]), np.array([1.0, a1, a2]), np.array([1.0, r1]), np.array([s0, s1]),
                              1.0)
    assert np.max(np.abs(np.sort(poles.real) - np.sort(p))) < 1e-4 + 1e-9 * np.linalg.cond(sylvester(a1, a2, b0, b1))


def test_designed_response_is_python_controls_forced_response(speed_result):
    """The designed response ym = (Am(1)/B(1)) B(z)/Am(z) xD of runs.designed_response, against python-control's
    forced response of the same discrete transfer function (B of scipy's ZOH model) before the link changes."""
    import control

    from designkit.families.self_tuning.runs import designed_response

    res = speed_result
    t, x1, ym = designed_response(res.simulation, res.design, res.loaded.spec, res.plant)
    Ts = 0.01
    A, B = zoh(2.0, 0.5, Ts)
    b = [B[0], A[0, 1] * B[1] - A[1, 1] * B[0]]
    am = np.real(np.poly(np.exp(np.array([-4.0, -5.0]) * Ts)))
    G = control.tf(np.polymul([sum(am) / sum(b)], b), am, Ts)
    before = t < 12.0 - 1e-9
    r = np.asarray(res.simulation.desired)[np.searchsorted(np.asarray(res.simulation.time), t), 0]
    out = control.forced_response(G, T=t[before], U=r[before]).outputs
    np.testing.assert_allclose(ym[before], out, atol=1e-9)
    # and the regulator follows it once the estimates have converged (before the change)
    assert np.max(np.abs(x1 - ym)[(t > 8.0) & before]) < 1e-5
