"""The sensitivity model CasADi generates from the reference model, against finite differences of the model
re-simulated with perturbed parameters (the independent route: no Jacobian, no sensitivity equation)."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from designkit.families import synthesize
from designkit.families.mrac.model import model_function, sensitivity_function
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from tests.families.mrac.numpy_mrac import simulate
from tests.tolerances import TOL

A = (20.0, 9.0)  # poles -4, -5 1/s
REL_STEP = 1e-5  # central differences: truncation ~ 1e-10, rounding ~ 1e-13 / 1e-5


def _piecewise(fun, s0, t, period, amplitude):
    """Integrate ``fun(t, s, r)`` under a square wave, restarting at every jump (DOP853, rtol 1e-13)."""
    out = np.empty((t.size, s0.size))
    edges = [k * 0.5 * period for k in range(int(t[-1] / (0.5 * period)) + 1)] + [t[-1]]
    s = s0
    for k, (lo, hi) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        r = amplitude if k % 2 == 0 else -amplitude
        inside = (t >= lo - 1e-12) & (t <= hi + 1e-12)
        sol = solve_ivp(lambda tt, z, r=r: fun(z, r), (lo, hi), s, method="DOP853", rtol=1e-13, atol=1e-15,
                        dense_output=True)
        out[inside] = sol.sol(t[inside]).T
        s = sol.y[:, -1]
    return out


def _model_output(a, t, period=2.0, amplitude=0.5):
    """The reference model y1'' + a2 y1' + a1 y1 = a1 r, written here in NumPy, re-simulated at ``a``."""
    a1, a2 = a
    return _piecewise(lambda z, r: np.array([z[1], -a1 * z[0] - a2 * z[1] + a1 * r]), np.zeros(2), t, period,
                      amplitude)


def test_casadi_reference_model_is_the_second_order_loop():
    f = model_function()
    y, r = np.array([0.3, -1.2]), 0.7
    assert np.allclose(np.asarray(f(y, A, r)).ravel(), [-1.2, -20 * 0.3 + 9 * 1.2 + 20 * 0.7], rtol=0, atol=1e-14)


def test_casadi_sensitivity_model_matches_finite_differences_of_the_reference_model():
    t = np.linspace(0.0, 6.0, 601)
    sens = sensitivity_function()

    def joint(z, r):
        y_dot, s_dot = sens(z[:2], z[2:], A, r)
        return np.concatenate([np.asarray(y_dot).ravel(), np.asarray(s_dot).ravel()])

    S = _piecewise(joint, np.zeros(6), t, 2.0, 0.5)[:, 2:]
    for j in range(2):
        h = REL_STEP * A[j]
        up, down = np.array(A), np.array(A)
        up[j] += h
        down[j] -= h
        fd = (_model_output(up, t) - _model_output(down, t)) / (2 * h)
        ours = S[:, 2 * j:2 * j + 2]  # dy1/da_j, dy2/da_j
        rel = np.abs(ours - fd).max(axis=0) / np.abs(fd).max(axis=0)
        assert np.all(rel <= TOL["finite_difference"]), (j, rel)


def test_the_simulated_sensitivity_states_are_the_model_s_derivatives_in_a():
    """The pipeline's own run (RK4, 1 ms, a step from rest) records S = dym/da: against finite differences of the
    model re-simulated by scipy with a1 and a2 perturbed."""
    spec = parse_spec("name: s\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
                      "controller: {kind: mrac, poles: [-4, -5], gamma: 1.0}\n"
                      "simulation: {duration: 5, dt: 0.001, step: 0.5}\n").spec
    sim = build(spec, synthesize(spec)).run()
    assert sim.settings["start"]["at_rest"]
    names = list(sim.controller_state_names)
    assert names == ["ym1", "ym2", "dym1_da1", "dym2_da1", "dym1_da2", "dym2_da2", "a1", "a2"]
    t, S = sim.time, sim.controller_state[:, 2:6]

    def model(a):
        return simulate(t, Km=2.0, tau=0.5, nominal=(2.0, 0.5), a=a, gamma=(0.0, 0.0), Q=np.eye(2), initial=A,
                        amplitude=0.5, period=None, rtol=1e-13, atol=1e-15)[:, 2:4]

    for j in range(2):
        h = REL_STEP * A[j]
        up, down = np.array(A), np.array(A)
        up[j] += h
        down[j] -= h
        fd = (model(up) - model(down)) / (2 * h)
        rel = np.abs(S[:, 2 * j:2 * j + 2] - fd).max(axis=0) / np.abs(fd).max(axis=0)
        assert np.all(rel <= TOL["finite_difference"]), (j, rel)
