"""The ideal linear responses: the step response, and the exact first-order-hold response against
python-control's ``forced_response`` and a closed form."""

from __future__ import annotations

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.simulation.linear import forced_response, linear_step
from tests.simulation.helpers import TRACKING, design_of, make_spec


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 4), m=st.integers(1, 2), p=st.integers(1, 2))
def test_forced_response_matches_python_control(seed, n, m, p):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n)) - 1.5 * np.eye(n)
    B, C, D = rng.normal(size=(n, m)), rng.normal(size=(p, n)), rng.normal(size=(p, m))
    t = np.linspace(0.0, 4.0, 401)
    U = np.vstack([np.sin((k + 1) * t) + (t > 1.0) for k in range(m)])  # a step on a sample, and a smooth input
    x0 = rng.normal(size=n)
    ref = control.forced_response(control.ss(A, B, C, D), T=t, U=U, X0=x0).outputs
    np.testing.assert_allclose(forced_response(A, B, C, D, t, U, x0), np.reshape(ref, (p, t.size)),
                               rtol=1e-9, atol=1e-10)


def test_forced_response_of_a_ramp_is_exact():
    """x' = -x + u, u = t (linear, so first-order hold is exact): x = t - 1 + e^-t."""
    t = np.linspace(0.0, 3.0, 7)
    y = forced_response([[-1.0]], [[1.0]], [[1.0]], [[0.0]], t, t[None, :])
    np.testing.assert_allclose(y[0], t - 1.0 + np.exp(-t), rtol=1e-13, atol=1e-14)


def test_forced_response_refuses_uneven_time():
    with pytest.raises(ValueError, match="evenly spaced"):
        forced_response([[-1.0]], [[1.0]], [[1.0]], [[0.0]], np.array([0.0, 0.1, 0.3]), np.zeros((1, 3)))


def test_servo_step_has_unit_dc_gain_and_starts_at_the_feedforward_control():
    design = design_of(make_spec())
    t, x1, u = linear_step(design, 5.0, n=1001)
    assert t.shape == (1001,) and x1.shape == u.shape == (1001, 1)
    x1, u = x1[:, 0], u[:, 0]
    assert x1[0] == 0.0 and x1[-1] == pytest.approx(1.0, abs=1e-6)
    g = design.gains
    assert u[0] == pytest.approx(g["K1"] + g["K3"] * g["K4"])  # D of the closed loop
    assert u[-1] == pytest.approx(0.0, abs=1e-5)


def test_tracking_step_and_amplitude():
    design = design_of(make_spec(TRACKING))
    _, x1, _ = linear_step(design, 3.0, amplitude=2.0)
    assert x1[-1, 0] == pytest.approx(2.0, abs=1e-4)
    assert np.all(np.isfinite(x1))
