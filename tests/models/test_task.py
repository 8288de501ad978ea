"""Task-space coordinates (``designkit.models.task``) against independent routes.

* ``orientation_error``: SciPy's rotations build ``R_D = Rot(k, theta) R`` from an axis and an angle; the
  error must be ``sin(theta) k`` (a property over random rotations), and ``-e_o`` must move with the angular
  velocity at ``R = R_D`` (central differences along ``R(t) = exp([w] t) R_D``).
* ``task_space``: which rows a planar arm, the PUMA 560 and the SCARA keep, from what those arms can move.
* ``task_functions``: the planar 2R's closed-form kinematics written here (``x = d1 c1 + d2 c12``, its
  Jacobian, ``Jdot qd`` as the centripetal part of the end effector's acceleration), finite differences of
  ``J`` along ``qd``, and on the PUMA the Jacobian against finite differences of ``tracked`` at the held
  orientation.
* ``joint_path``: the planar 2R's closed-form inverse kinematics (elbow branch of ``q0``), joint velocities
  ``J^-1 xD'``, and the conditioning against the closed-form 2 x 2 Jacobian (``det J = d1 d2 sin q2``).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from designkit.errors import ModelError
from designkit.models.robots import robot
from designkit.models.task import TaskSpace, check_path, joint_path, orientation_error, task_functions, task_space
from tests.models.support import central_difference, scaled_error
from tests.tolerances import TOL

D1, D2 = 0.5, 0.4  # planar2r link lengths (m), src/designkit/models/robots/planar2r.py
PUMA_Q0 = np.array([0.0, 0.785, -3.14, 0.2, 0.15, 0.2])


# ----------------------------------------------------------------------------- planar 2R in closed form


def planar_position(q: np.ndarray) -> np.ndarray:
    """End-effector ``(x, y)`` of the planar 2R: ``x = d1 c1 + d2 c12``, ``y = d1 s1 + d2 s12``."""
    q1, q12 = q[0], q[0] + q[1]
    return np.array([D1 * math.cos(q1) + D2 * math.cos(q12), D1 * math.sin(q1) + D2 * math.sin(q12)])


def planar_jacobian(q: np.ndarray) -> np.ndarray:
    """``d(x, y)/dq`` of :func:`planar_position`, differentiated by hand."""
    q1, q12 = q[0], q[0] + q[1]
    return np.array([[-D1 * math.sin(q1) - D2 * math.sin(q12), -D2 * math.sin(q12)],
                     [D1 * math.cos(q1) + D2 * math.cos(q12), D2 * math.cos(q12)]])


def planar_centripetal(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """End-effector acceleration at ``qdd = 0``: each link's tip turns on its circle, ``-r w^2`` towards the joint."""
    q1, q12, w1, w12 = q[0], q[0] + q[1], qd[0], qd[0] + qd[1]
    return -np.array([D1 * math.cos(q1) * w1**2 + D2 * math.cos(q12) * w12**2,
                      D1 * math.sin(q1) * w1**2 + D2 * math.sin(q12) * w12**2])


def planar_ik(p: np.ndarray, elbow: float) -> np.ndarray:
    """Closed-form inverse kinematics (law of cosines) on the elbow branch ``sign(q2) = elbow``."""
    c2 = (p @ p - D1**2 - D2**2) / (2 * D1 * D2)
    q2 = elbow * math.acos(c2)
    q1 = math.atan2(p[1], p[0]) - math.atan2(D2 * math.sin(q2), D1 + D2 * math.cos(q2))
    return np.array([q1, q2])


def _np(x) -> np.ndarray:
    return np.asarray(x, dtype=float)


# ----------------------------------------------------------------------------- orientation error


_angle = st.floats(-1.55, 1.55, allow_nan=False).filter(lambda a: abs(a) > 1e-6)
_axis = st.tuples(*[st.floats(-1.0, 1.0, allow_nan=False)] * 3).filter(lambda v: math.hypot(*v) > 0.1)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), axis=_axis, theta=_angle)
def test_orientation_error_is_sine_of_the_angle_times_the_axis(seed, axis, theta):
    k = np.array(axis) / np.linalg.norm(axis)
    R = Rotation.random(random_state=seed).as_matrix()
    R_D = Rotation.from_rotvec(theta * k).as_matrix() @ R  # rotation from the actual to the desired
    expected = math.sin(theta) * k
    assert orientation_error(R, R_D) == pytest.approx(expected, abs=1e-12)
    # the CasADi branch (symbolic R, numeric R_D), as task_functions uses it, gives the same numbers
    S = ca.SX.sym("R", 3, 3)
    f = ca.Function("e_o", [S], [orientation_error(S, R_D)])
    assert _np(f(R)).ravel() == pytest.approx(expected, abs=1e-12)


def test_orientation_error_vanishes_only_at_the_held_orientation_within_a_quarter_turn():
    rng = np.random.default_rng(3)
    R = Rotation.random(random_state=5).as_matrix()
    assert orientation_error(R, R) == pytest.approx(np.zeros(3), abs=1e-15)
    for _ in range(20):  # |e_o| = |sin theta| > 0 for 0 < |theta| < pi/2: unique there
        theta = rng.uniform(0.05, 1.5)
        k = rng.normal(size=3)
        k /= np.linalg.norm(k)
        e = orientation_error(R, Rotation.from_rotvec(theta * k).as_matrix() @ R)
        assert np.linalg.norm(e) == pytest.approx(math.sin(theta), rel=1e-12)


def test_tracked_orientation_moves_with_the_angular_velocity_at_the_held_orientation():
    rng = np.random.default_rng(11)
    h = 1e-6
    for seed in range(5):
        R_D = Rotation.random(random_state=seed).as_matrix()
        w = rng.normal(size=3)

        def tracked(t: float, R_D=R_D, w=w) -> np.ndarray:  # -e_o along R(t) = exp([w] t) R_D (base-frame w)
            return -orientation_error(Rotation.from_rotvec(w * t).as_matrix() @ R_D, R_D)

        rate = (tracked(h) - tracked(-h)) / (2 * h)
        assert scaled_error(rate, w) < TOL["finite_difference"]


# ----------------------------------------------------------------------------- which rows


def test_task_space_rows_follow_what_each_arm_can_move():
    planar = robot("planar2r")
    q0 = np.array([0.3, 1.2])
    space = task_space(planar, None, q0, orientation=False)
    assert space.names == ("x", "y") and space.units == ("m", "m") and space.m == 2
    # a planar arm turns only about z: with orientation it keeps rz, never rx, ry (nor z)
    assert task_space(planar, None, q0, orientation=True).names == ("x", "y", "rz")

    puma = robot("puma560")
    space = task_space(puma, None, PUMA_Q0, orientation=True)
    assert space.names == ("x", "y", "z", "rx", "ry", "rz")
    assert space.position_rows == (0, 1, 2) and space.orientation_rows == (0, 1, 2)
    assert task_space(puma, None, PUMA_Q0, orientation=False).names == ("x", "y", "z")

    # the zoo SCARA: RRPR with every joint axis vertical (two turns, a quill along z, a wrist turn)
    scara = robot("scara")
    q = np.array([0.1, -0.4, 0.05, 0.7])
    T = _np(scara.functions["fkine"](q))
    assert T[:3, 2] @ np.array([0.0, 0.0, 1.0]) == pytest.approx(-1.0, abs=1e-12)  # tool z points down
    space = task_space(scara, None, q, orientation=True)
    assert space.names == ("x", "y", "z", "rz") and space.units == ("m", "m", "m", "rad")


def test_held_orientation_is_the_initial_one():
    puma = robot("puma560")
    space = task_space(puma, None, PUMA_Q0, orientation=True)
    T = _np(puma.functions["fkine"](PUMA_Q0))
    assert np.max(np.abs(space.R_D - T[:3, :3])) <= 1e-15
    # and the tracked orientation coordinates are zero there
    fns = task_functions(puma, None, space)
    assert _np(fns.tracked(PUMA_Q0)).ravel()[3:] == pytest.approx(np.zeros(3), abs=1e-15)


# ----------------------------------------------------------------------------- task functions, planar 2R


def test_planar_task_functions_equal_the_closed_form_kinematics():
    arm = robot("planar2r")
    rng = np.random.default_rng(1)
    fns = task_functions(arm, None, task_space(arm, None, np.array([0.3, 1.2]), orientation=False))
    for _ in range(10):
        q, qd = rng.uniform(-math.pi, math.pi, 2), rng.uniform(-3, 3, 2)
        assert scaled_error(_np(fns.tracked(q)).ravel(), planar_position(q)) < TOL["algebra"]
        assert scaled_error(_np(fns.jacobian(q)), planar_jacobian(q)) < TOL["algebra"]
        assert scaled_error(_np(fns.tracked_jacobian(q)), planar_jacobian(q)) < TOL["algebra"]
        assert scaled_error(_np(fns.rate(q, qd)).ravel(), planar_jacobian(q) @ qd) < TOL["algebra"]
        bias = _np(fns.bias(q, qd)).ravel()
        assert scaled_error(bias, planar_centripetal(q, qd)) < TOL["algebra"]
        # Jdot qd = (d/ds J(q + s qd)) qd at s = 0, by central differences of the hand-written Jacobian
        h = 1e-6
        Jdot = (planar_jacobian(q + h * qd) - planar_jacobian(q - h * qd)) / (2 * h)
        assert scaled_error(bias, Jdot @ qd) < TOL["finite_difference"]


def test_planar_held_orientation_is_the_sine_of_the_turn_away_from_it():
    arm = robot("planar2r")
    q0 = np.array([0.3, 1.2])
    fns = task_functions(arm, None, task_space(arm, None, q0, orientation=True))
    rng = np.random.default_rng(2)
    for _ in range(10):
        q = q0 + rng.uniform(-1.2, 1.2, 2)
        # the end effector is turned by q1 + q2 about z; from the held q01 + q02 that is theta = sum(q - q0),
        # so -e_o = -sin(-theta) z: rz = sin(q1 + q2 - q01 - q02)
        x = _np(fns.tracked(q)).ravel()
        assert x == pytest.approx([*planar_position(q), math.sin(q.sum() - q0.sum())], abs=1e-14)


# ----------------------------------------------------------------------------- task functions, PUMA 560


def test_puma_jacobian_is_the_derivative_of_the_tracked_coordinates_at_the_held_orientation():
    puma = robot("puma560")
    rows = task_space(puma, None, PUMA_Q0, orientation=True).rows
    rng = np.random.default_rng(4)
    for q in [PUMA_Q0, *rng.uniform(-2.0, 2.0, (3, 6))]:
        T = _np(puma.functions["fkine"](q))
        fns = task_functions(puma, None, TaskSpace(rows, tuple(T[:3, :3].ravel())))  # hold the orientation at q
        J = _np(fns.jacobian(q))
        fd = central_difference(lambda z, f=fns: _np(f.tracked(z)).ravel(), q)
        assert scaled_error(J, fd) < TOL["finite_difference"]
        assert scaled_error(_np(fns.tracked_jacobian(q)), J) < TOL["algebra"]
        # Jdot qd from differences of J along qd
        qd = rng.uniform(-2.0, 2.0, 6)
        h = 1e-6
        Jdot = (_np(fns.jacobian(q + h * qd)) - _np(fns.jacobian(q - h * qd))) / (2 * h)
        assert scaled_error(_np(fns.bias(q, qd)).ravel(), Jdot @ qd) < TOL["finite_difference"]


def test_puma_tracked_jacobian_differs_from_the_geometric_rows_away_from_the_held_orientation():
    # the Newton steps of joint_path use d tracked/dq: away from R_D it is not J_omega (e_o is not linear)
    puma = robot("puma560")
    space = task_space(puma, None, PUMA_Q0, orientation=True)
    fns = task_functions(puma, None, space)
    q = PUMA_Q0 + np.array([0.0, 0.0, 0.0, 0.6, -0.5, 0.7])
    fd = central_difference(lambda z: _np(fns.tracked(z)).ravel(), q)
    assert scaled_error(_np(fns.tracked_jacobian(q)), fd) < TOL["finite_difference"]
    assert np.max(np.abs(_np(fns.tracked_jacobian(q)) - _np(fns.jacobian(q)))) > 0.05


# ----------------------------------------------------------------------------- joint path, planar 2R


def _planar_line(q0: np.ndarray, p1: np.ndarray, N: int = 101, T: float = 1.0):
    """Samples of a rest-to-rest quintic line from the end effector at ``q0`` to ``p1`` (written here)."""
    t = np.linspace(0.0, T, N)
    s = t / T
    p0 = planar_position(q0)
    sig, dsig = 10 * s**3 - 15 * s**4 + 6 * s**5, (30 * s**2 - 60 * s**3 + 30 * s**4) / T
    return t, p0 + np.outer(sig, p1 - p0), np.outer(dsig, p1 - p0)


@pytest.mark.parametrize("q0", [np.array([0.3, 1.2]), np.array([1.4, -1.0])], ids=["elbow-up", "elbow-down"])
def test_joint_path_is_the_closed_form_inverse_kinematics_on_the_elbow_branch_of_q0(q0):
    arm = robot("planar2r")
    fns = task_functions(arm, None, task_space(arm, None, q0, orientation=False))
    p0 = planar_position(q0)
    t, X, Xd = _planar_line(q0, p0 + np.array([-0.25, 0.15]))
    path = joint_path(fns, q0, t, X, Xd)
    elbow = math.copysign(1.0, q0[1])
    Q = np.array([planar_ik(x, elbow) for x in X])
    assert np.max(np.abs(path.q - Q)) < 1e-9
    assert np.max(path.residual) < 1e-9
    Qd = np.array([np.linalg.solve(planar_jacobian(q), xd) for q, xd in zip(Q, Xd, strict=True)])
    assert np.max(np.abs(path.qd - Qd)) < 1e-8
    # conditioning from the closed-form 2 x 2 Jacobian
    sv = np.array([np.linalg.svd(planar_jacobian(q), compute_uv=False) for q in Q])
    assert scaled_error(path.sigma, sv) < 1e-9
    assert scaled_error(path.condition, sv[:, 0] / sv[:, 1]) < 1e-8
    # Yoshikawa's manipulability of a square J is |det J| = d1 d2 |sin q2|
    assert scaled_error(path.manipulability, D1 * D2 * np.abs(np.sin(Q[:, 1]))) < 1e-9
    assert path.worst == int(np.argmax(sv[:, 0] / sv[:, 1]))


def test_check_path_refuses_a_target_out_of_reach_and_joint_limits():
    arm = robot("planar2r")
    q0 = np.array([0.3, 1.2])
    fns = task_functions(arm, None, task_space(arm, None, q0, orientation=False))
    p0 = planar_position(q0)
    far = p0 / np.linalg.norm(p0) * 0.95  # beyond d1 + d2 = 0.9 m
    t, X, Xd = _planar_line(q0, far)
    path = joint_path(fns, q0, t, X, Xd)
    # first unreachable sample: where the line leaves the disc of radius 0.9 m
    first = int(np.argmax(np.linalg.norm(X, axis=1) > D1 + D2 + 1e-6))
    assert np.all(path.residual[:first] < 1e-9) and path.residual[first] > 1e-6
    with pytest.raises(ModelError, match="out of reach") as info:
        check_path(path, "simulation.trajectory.to", [None, None])
    assert info.value.field == "simulation.trajectory.to"
    # a reachable path whose q2 passes below a limit set just above its smallest value
    t, X, Xd = _planar_line(q0, p0 + np.array([0.1, 0.05]))
    path = joint_path(fns, q0, t, X, Xd)
    low = float(np.min(path.q[:, 1]))
    check_path(path, "simulation.trajectory", [None, (low - 1e-3, 3.0)])
    with pytest.raises(ModelError, match="joint 2's limits") as info:
        check_path(path, "simulation.trajectory", [None, (low + 1e-3, 3.0)])
    assert info.value.field == "simulation.trajectory"
    peak = float(np.max(np.abs(path.qd)))
    check_path(path, "simulation.trajectory", [None, None], velocity_limits=peak * 1.01)
    with pytest.raises(ModelError, match="rad/s"):
        check_path(path, "simulation.trajectory", [None, None], velocity_limits=peak * 0.99)
