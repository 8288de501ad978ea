"""End-effector paths (``designkit.simulation.cartesian``) against geometry and finite differences.

The reference's formulas are not re-typed: a line must join its ends along the segment, a circle must keep
its distance from the axis and its height along the normal, close after whole turns, reach the antipode
after half a turn, turn counter-clockwise about ``normal`` and have arc length ``2 pi r turns``; the
velocity and acceleration columns must be the central first and second differences of the position column;
both paths start and end at rest and hold their end point afterwards.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from designkit.errors import SpecError
from designkit.models.task import TaskSpace
from designkit.simulation.cartesian import cartesian_reference
from designkit.spec.sections import CircleTrajectory, LineTrajectory
from tests.models.support import scaled_error

SPACE_XYZ = TaskSpace((0, 1, 2))
SPACE_6 = TaskSpace((0, 1, 2, 3, 4, 5))
SPACE_PLANAR = TaskSpace((0, 1))
Q0 = (0.1, 0.2, 0.3)


def _line(**fields) -> LineTrajectory:
    return LineTrajectory.model_validate({"kind": "line", **fields})


def _circle(**fields) -> CircleTrajectory:
    return CircleTrajectory.model_validate({"kind": "circle", **fields})


def _differences(ref, t: np.ndarray, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """Central first (h = 1e-5 s) and second (h = 1e-4 s) differences of the position column."""
    h1, h2 = 1e-5, 1e-4

    def p(s: np.ndarray) -> np.ndarray:
        return ref.evaluate(s)[:, :rows, 0]

    vel = (p(t + h1) - p(t - h1)) / (2 * h1)
    acc = (p(t + h2) - 2 * p(t) + p(t - h2)) / h2**2
    return vel, acc


def _interior(T: float, N: int = 37) -> np.ndarray:
    return np.linspace(0.0, T, N)[1:-1]  # the quintic's third derivative jumps at 0 and T


# ----------------------------------------------------------------------------- line


def test_line_joins_its_ends_along_the_segment_at_rest():
    p0, p1, T = np.array([0.4, -0.2, 0.7]), np.array([0.1, 0.3, 0.5]), 1.5
    ref = cartesian_reference(_line(to=p1.tolist(), duration=T), p0, SPACE_XYZ, Q0)
    assert ref.n == 3 and ref.horizon == T and ref.start == Q0
    ends = ref.evaluate(np.array([0.0, T, T + 0.7]))
    assert ends[0, :, 0] == pytest.approx(p0, abs=1e-15)
    assert ends[1, :, 0] == pytest.approx(p1, abs=1e-15) and ends[2, :, 0] == pytest.approx(p1, abs=1e-15)
    assert np.all(ends[:, :, 1:] == 0.0)  # rest at both ends and after
    t = np.linspace(0.0, T, 301)
    X = ref.evaluate(t)
    d = (p1 - p0) / np.linalg.norm(p1 - p0)
    off = (X[:, :, 0] - p0) - np.outer((X[:, :, 0] - p0) @ d, d)
    assert np.max(np.abs(off)) < 1e-15  # on the line through p0 and p1
    progress = (X[:, :, 0] - p0) @ d / np.linalg.norm(p1 - p0)
    assert np.all(np.diff(progress) >= 0) and progress.min() >= 0 and progress.max() <= 1 + 1e-15
    assert np.max(np.abs(np.cross(X[:, :, 1], d))) < 1e-14  # velocity and acceleration along it too
    assert np.max(np.abs(np.cross(X[:, :, 2], d))) < 1e-13


def test_line_velocity_and_acceleration_are_the_differences_of_its_position():
    p0, T = np.array([0.4, -0.2, 0.7]), 0.8
    ref = cartesian_reference(_line(displacement=[-0.3, 0.25, 0.1], duration=T), p0, SPACE_XYZ, Q0)
    t = _interior(T)
    X = ref.evaluate(t)
    vel, acc = _differences(ref, t, 3)
    assert scaled_error(X[:, :, 1], vel) < 1e-8
    assert scaled_error(X[:, :, 2], acc) < 1e-5


def test_line_by_displacement_equals_line_to_its_end():
    p0, disp = np.array([0.4, -0.2, 0.7]), np.array([-0.3, 0.25, 0.1])
    a = cartesian_reference(_line(displacement=disp.tolist(), duration=1.0), p0, SPACE_XYZ, Q0)
    b = cartesian_reference(_line(to=(p0 + disp).tolist(), duration=1.0), p0, SPACE_XYZ, Q0)
    t = np.linspace(0.0, 1.2, 50)
    assert a.evaluate(t) == pytest.approx(b.evaluate(t), abs=1e-15)


def test_held_orientation_rows_have_a_zero_reference():
    p0 = np.array([0.4, -0.2, 0.7])
    ref = cartesian_reference(_line(displacement=[0.0, 0.0, 0.15], duration=2.0), p0, SPACE_6, Q0 * 2)
    X = ref.evaluate(np.linspace(0.0, 2.0, 41))
    assert X.shape == (41, 6, 3) and ref.n == 6
    assert np.all(X[:, 3:, :] == 0.0)
    assert X[-1, :3, 0] == pytest.approx(p0 + [0.0, 0.0, 0.15], abs=1e-15)


# ----------------------------------------------------------------------------- circle


CENTER = np.array([0.2, 0.1, 0.3])
NORMAL = np.array([1.0, 2.0, 2.0])  # |normal| = 3
P0 = np.array([0.45, -0.05, 0.6])


def test_circle_keeps_its_radius_in_the_plane_normal_to_its_axis():
    T = 2.0
    ref = cartesian_reference(_circle(center=CENTER.tolist(), normal=NORMAL.tolist(), turns=1.25, duration=T),
                              P0, SPACE_XYZ, Q0)
    k = NORMAL / 3.0
    height = (P0 - CENTER) @ k
    radius = np.linalg.norm((P0 - CENTER) - height * k)
    t = np.linspace(0.0, T, 801)
    X = ref.evaluate(t)
    rel = X[:, :, 0] - CENTER
    assert np.max(np.abs(rel @ k - height)) < 1e-14  # in the plane through p0 normal to the axis
    assert np.max(np.abs(np.linalg.norm(rel - np.outer(rel @ k, k), axis=1) - radius)) < 1e-14
    assert ref.settings["radius_m"] == pytest.approx(radius, rel=1e-14)
    assert np.max(np.abs(X[:, :, 1] @ k)) < 1e-14 and np.max(np.abs(X[:, :, 2] @ k)) < 1e-13
    # counter-clockwise about the normal: (p - axis point) x p' along +k wherever it moves
    axis_point = CENTER + height * k
    spin = np.cross(X[:, :, 0] - axis_point, X[:, :, 1]) @ k
    assert np.all(spin >= 0) and spin[len(t) // 2] > 0
    # arc length 2 pi r turns (trapezoidal rule of |p'| on a fine grid)
    speed = np.linalg.norm(X[:, :, 1], axis=1)
    arc = float(np.sum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t)))
    assert arc == pytest.approx(2 * math.pi * radius * 1.25, rel=1e-5)
    # at rest at both ends
    assert np.all(np.abs(X[[0, -1], :, 1:]) < 1e-13)


@pytest.mark.parametrize(("turns", "end"), [(1.0, P0), (2.0, P0), (0.5, None), (-0.5, None)])
def test_circle_ends_after_whole_turns_at_its_start_and_after_half_a_turn_opposite(turns, end):
    ref = cartesian_reference(_circle(center=CENTER.tolist(), normal=NORMAL.tolist(), turns=turns, duration=1.0),
                              P0, SPACE_XYZ, Q0)
    k = NORMAL / 3.0
    axis_point = CENTER + ((P0 - CENTER) @ k) * k
    want = P0 if end is not None else 2 * axis_point - P0  # antipode: reflect through the axis
    assert ref.evaluate(np.array([1.0, 1.5]))[:, :, 0] == pytest.approx(np.vstack([want, want]), abs=1e-14)


def test_circle_velocity_and_acceleration_are_the_differences_of_its_position():
    T = 1.3
    ref = cartesian_reference(_circle(center=CENTER.tolist(), normal=NORMAL.tolist(), turns=-0.8, duration=T),
                              P0, SPACE_XYZ, Q0)
    t = _interior(T)
    X = ref.evaluate(t)
    vel, acc = _differences(ref, t, 3)
    assert scaled_error(X[:, :, 1], vel) < 1e-8
    assert scaled_error(X[:, :, 2], acc) < 1e-5


def test_planar_circle_has_only_the_arm_s_coordinates():
    p0 = np.array([0.50596313, 0.5467581, 0.0])
    ref = cartesian_reference(_circle(center=[0.4, 0.55, 0.0], duration=1.0), p0, SPACE_PLANAR, (0.3, 1.2))
    X = ref.evaluate(np.linspace(0.0, 1.0, 101))
    assert X.shape == (101, 2, 3) and ref.start == (0.3, 1.2)
    r = np.linalg.norm(X[:, :, 0] - [0.4, 0.55], axis=1)
    assert np.max(np.abs(r - np.linalg.norm(p0[:2] - [0.4, 0.55]))) < 1e-14


# ----------------------------------------------------------------------------- refused paths


def test_circle_starting_on_its_axis_is_refused_at_center():
    p0 = np.array([0.3, 0.4, 0.5])
    with pytest.raises(SpecError) as info:  # axis through the start, along the tilted normal
        cartesian_reference(_circle(center=(p0 - 0.2 * NORMAL).tolist(), normal=NORMAL.tolist()), p0, SPACE_XYZ, Q0)
    assert info.value.path == "simulation.trajectory.center"


@pytest.mark.parametrize("traj", [
    _line(displacement=[-0.1, 0.1, 0.05]),  # along z
    _line(to=[0.4, 0.5, -0.01]),  # ends off the plane
    _circle(center=[0.4, 0.55, 0.0], normal=[1.0, 0.0, 0.0]),  # a vertical circle
], ids=["line-displacement-z", "line-to-z", "circle-vertical"])
def test_planar_arm_refuses_a_path_along_z(traj):
    p0 = np.array([0.50596313, 0.5467581, 0.0])
    with pytest.raises(SpecError, match="moves along z") as info:
        cartesian_reference(traj, p0, SPACE_PLANAR, (0.3, 1.2))
    assert info.value.path == "simulation.trajectory"
