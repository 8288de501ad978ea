"""References per joint: analytic derivatives, boundary conditions, limits, dispatch."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.errors import SpecError
from designkit.simulation.reference import (
    quintic,
    reference_for,
    sine,
    step_reference,
    trapezoid_timing,
    trapezoidal,
    via_points,
)
from designkit.spec.sections import Simulation

REFERENCES = {
    "quintic": quintic([0.8, -0.3], 1.5, start=[0.1, 0.2]),
    "sine": sine(0.3, 0.7),
    "trapezoidal": trapezoidal([1.0, -0.5], [2.0, 1.0], [4.0, 3.0], start=[0.0, 1.0]),
    "via_points": via_points([0.5, 1.2, 1.6], [[0.3, 0.0], [0.1, -0.4], [0.6, 0.2]]),
}


@pytest.mark.parametrize("name", list(REFERENCES))
def test_derivatives_match_finite_differences(name):
    ref = REFERENCES[name]
    t = np.linspace(0.05, 1.4, 50)
    h = 1e-6
    fwd, bwd, mid = ref.evaluate(t + h), ref.evaluate(t - h), ref.evaluate(t)
    np.testing.assert_allclose((fwd[..., 0] - bwd[..., 0]) / (2 * h), mid[..., 1], rtol=1e-5, atol=1e-6)
    if name != "trapezoidal":  # its acceleration jumps at the corners of the trapezoid
        np.testing.assert_allclose((fwd[..., 1] - bwd[..., 1]) / (2 * h), mid[..., 2], rtol=1e-5, atol=1e-5)


def test_quintic_is_rest_to_rest_from_the_start():
    ref = quintic([2.0, -1.0], 1.0, start=[0.5, 0.0]).evaluate(np.array([0.0, 1.0, 3.0]))
    np.testing.assert_allclose(ref[:, 0], [[0.5, 0, 0], [2.5, 0, 0], [2.5, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(ref[:, 1], [[0, 0, 0], [-1, 0, 0], [-1, 0, 0]], atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(amp=st.lists(st.floats(-3.0, 3.0), min_size=1, max_size=4),
       vmax=st.floats(0.1, 5.0), amax=st.floats(0.1, 20.0), stretch=st.floats(1.0, 3.0))
def test_trapezoid_respects_the_limits_and_synchronises(amp, vmax, amax, stretch):
    amp = np.array(amp)
    if np.max(np.abs(amp)) < 1e-6:
        return
    T, ta = trapezoid_timing(amp, vmax, amax)
    ref = trapezoidal(amp, vmax, amax, duration=T * stretch)
    t = np.linspace(0.0, T * stretch * 1.1, 4001)
    x = ref.evaluate(t)
    assert np.all(np.abs(x[..., 1]) <= vmax * (1 + 1e-9))
    assert np.all(np.abs(x[..., 2]) <= amax * (1 + 1e-9))
    np.testing.assert_allclose(x[-1, :, 0], amp, atol=1e-12)  # every joint arrives, together, at rest
    np.testing.assert_allclose(x[-1, :, 1:], 0.0, atol=1e-12)
    # the position is the integral of the velocity (trapezoid rule on a fine grid)
    steps = 0.5 * (x[1:, :, 1] + x[:-1, :, 1]) * np.diff(t)[:, None]
    integral = np.vstack([np.zeros((1, amp.size)), np.cumsum(steps, axis=0)])
    np.testing.assert_allclose(integral, x[:, :, 0], atol=1e-4 * max(1.0, float(np.max(np.abs(amp)))))


def test_minimum_time_trapezoid_touches_a_limit():
    # one joint limited by velocity (cruise), which makes T = Tv + Ka/Tv
    T, ta = trapezoid_timing([1.0], 1.0, 10.0)
    assert pytest.approx(1.0 + 0.1) == T and ta == pytest.approx(0.1)
    # triangular when the acceleration limit binds first
    T, ta = trapezoid_timing([1.0], 10.0, 1.0)
    assert pytest.approx(2.0) == T and ta == pytest.approx(1.0)
    with pytest.raises(ValueError, match="minimum is 2"):
        trapezoid_timing([1.0], 10.0, 1.0, duration=1.5)


def test_via_points_pass_through_their_points_and_end_at_rest():
    ref = REFERENCES["via_points"]
    x = ref.evaluate(np.array([0.0, 0.5, 1.2, 1.6, 2.5]))
    np.testing.assert_allclose(x[[1, 2, 3], :, 0], [[0.3, 0.0], [0.1, -0.4], [0.6, 0.2]], atol=1e-12)
    np.testing.assert_allclose(x[0, :, :2], 0.0, atol=1e-12)
    np.testing.assert_allclose(x[-1, :, 1:], 0.0, atol=1e-12)


def test_flat_layout_is_positions_then_velocities_then_accelerations():
    ref = REFERENCES["quintic"]
    t = np.array([0.3])
    full, flat = ref.evaluate(t), ref.flat(t)
    np.testing.assert_array_equal(flat[0], np.concatenate([full[0, :, 0], full[0, :, 1], full[0, :, 2]]))


def test_dispatch_and_per_joint_lengths():
    sim = Simulation(step=0.4)
    assert reference_for("step", sim).evaluate(np.zeros(2))[:, 0, 0].tolist() == [0.4, 0.4]
    assert step_reference(1.0).horizon == 0.0
    assert dict(reference_for("trajectory", sim).settings) == {"kind": "quintic", "amplitude": 1.0, "duration": 1.0}
    two = reference_for("step", Simulation(step=[0.1, 0.2], initial_position=[1.0, 2.0]), n=2)
    np.testing.assert_allclose(two.evaluate(np.zeros(1))[0, :, 0], [1.1, 2.2])
    assert two.start == (1.0, 2.0)
    with pytest.raises(SpecError, match="simulation.step"):
        reference_for("step", Simulation(step=[0.1, 0.2, 0.3]), n=2)
    with pytest.raises(SpecError, match="controller.kind"):
        reference_for("ramp", sim)


def test_sine_with_offset_and_phase_is_one_minus_cosine_against_numpy():
    """``30 deg (1 - cos 2 pi t)`` and ``45 deg (1 - cos 2 pi t)`` as a sine with offset and phase, from a spec."""
    a = np.radians([30.0, 45.0])
    traj = {"kind": "sine", "amplitude": a.tolist(), "frequency": 1.0, "offset": a.tolist(),
            "phase": -np.pi / 2}
    ref = reference_for("trajectory", Simulation(trajectory=traj), n=2)
    t = np.linspace(0.0, 2.0, 401)
    x = ref.evaluate(t)
    w = 2 * np.pi
    np.testing.assert_allclose(x[..., 0], a[None, :] * (1 - np.cos(w * t))[:, None], atol=1e-14)
    np.testing.assert_allclose(x[..., 1], a[None, :] * (w * np.sin(w * t))[:, None], atol=1e-12)
    np.testing.assert_allclose(x[..., 2], a[None, :] * (w**2 * np.cos(w * t))[:, None], atol=1e-10)
    np.testing.assert_allclose(x[0], np.stack([np.zeros(2), np.zeros(2), a * w**2], axis=1), atol=1e-12)  # at rest
    assert list(dict(ref.settings)["phase"]) == [-np.pi / 2] * 2
    assert "offset" not in dict(reference_for("trajectory", Simulation(
        trajectory={"kind": "sine", "amplitude": 0.3}), n=1).settings)


def test_sine_phase_per_joint_and_its_range():
    ref = sine([0.2, 0.4], 0.5, start=[0.1, -0.1], offset=[0.0, 0.3], phase=[0.25, -1.0])
    t = np.linspace(0.0, 3.0, 7)
    q = ref.evaluate(t)[..., 0]
    np.testing.assert_allclose(q[:, 0], 0.1 + 0.2 * np.sin(np.pi * t + 0.25), atol=1e-14)
    np.testing.assert_allclose(q[:, 1], -0.1 + 0.3 + 0.4 * np.sin(np.pi * t - 1.0), atol=1e-14)
    with pytest.raises(ValueError, match="phase"):
        Simulation(trajectory={"kind": "sine", "phase": 7.0})
