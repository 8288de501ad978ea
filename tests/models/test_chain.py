"""Kinematics: DH transforms, forward kinematics, Jacobians (vs finite differences and Pinocchio)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.errors import ModelError
from designkit.models import chain
from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.robot import Robot
from designkit.models.robots import robot
from tests.models.support import (
    TOL_EXACT,
    TOL_FD,
    ZOO,
    central_difference,
    chains,
    pinocchio_model,
    rotation_vee,
    scaled_error,
)

_angle = st.floats(-math.pi, math.pi)
_length = st.floats(-1.0, 1.0)


def _rz(t: float) -> np.ndarray:
    return np.array([[math.cos(t), -math.sin(t), 0, 0], [math.sin(t), math.cos(t), 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])


def _rx(t: float) -> np.ndarray:
    return np.array([[1, 0, 0, 0], [0, math.cos(t), -math.sin(t), 0], [0, math.sin(t), math.cos(t), 0], [0, 0, 0, 1]])


def _trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = [x, y, z]
    return T


@given(a=_length, alpha=_angle, d=_length, theta=_angle)
def test_dh_transform_is_the_product_of_elementary_transforms(a, alpha, d, theta):
    standard = _rz(theta) @ _trans(0, 0, d) @ _trans(a, 0, 0) @ _rx(alpha)
    modified = _rx(alpha) @ _trans(a, 0, 0) @ _rz(theta) @ _trans(0, 0, d)
    assert scaled_error(np.array(ca.DM(chain.dh_transform(a, alpha, d, theta, "standard"))), standard) < 1e-14
    assert scaled_error(np.array(ca.DM(chain.dh_transform(a, alpha, d, theta, "modified"))), modified) < 1e-14


def test_numeric_right_angles_give_exact_zeros():
    theta = ca.SX.sym("theta")
    T = chain.dh_transform(0.3, math.pi / 2, 0.1, theta, "standard")
    # cos(pi/2) in floating point is 6e-17; the builder must fold it to a structural zero
    assert T[2, 2].is_zero() and T[0, 1].is_zero() and T[1, 1].is_zero()
    assert T[2, 1].is_one()


def test_unknown_convention_and_representation_raise():
    with pytest.raises(ModelError, match="convention"):
        chain.dh_transform(0, 0, 0, 0, "craig")
    with pytest.raises(ModelError, match="representation"):
        chain.representation("quaternion")


def _check_jacobian(arm: Robot, q: np.ndarray) -> None:
    J = arm.jacobian(q)

    def position(x: np.ndarray) -> np.ndarray:
        return arm.fkine(x)[:3, 3]

    def rotation(x: np.ndarray) -> np.ndarray:
        return arm.fkine(x)[:3, :3]

    dp = central_difference(position, q)
    dR = central_difference(rotation, q)
    R = rotation(q)
    omega = np.stack([rotation_vee(dR[:, :, k] @ R.T) for k in range(q.size)], axis=1)
    assert scaled_error(J[:3], dp) < TOL_FD
    assert scaled_error(J[3:], omega) < TOL_FD


@pytest.mark.parametrize("name", ZOO)
def test_geometric_jacobian_matches_finite_differences_of_fkine(name):
    arm = robot(name)
    rng = np.random.default_rng(1)
    for q in rng.uniform(-2, 2, (3, arm.n)):
        _check_jacobian(arm, q)


@settings(max_examples=25, deadline=None)
@given(description=chains(), seed=st.integers(0, 2**16))
def test_random_chains_jacobian_and_jdot_qd(description, seed):
    arm = Robot(description)
    rng = np.random.default_rng(seed)
    q, qd = rng.uniform(-2, 2, arm.n), rng.uniform(-2, 2, arm.n)
    _check_jacobian(arm, q)
    h = 1e-5
    expected = (arm.jacobian(q + h * qd) - arm.jacobian(q - h * qd)) / (2 * h) @ qd
    assert scaled_error(arm.jacobian_dot_qd(q, qd), expected) < TOL_FD


@pytest.mark.parametrize("name", ZOO)
def test_jacobian_dot_qd_matches_finite_differences(name):
    arm = robot(name)
    rng = np.random.default_rng(2)
    h = 1e-5
    for _ in range(3):
        q, qd = rng.uniform(-2, 2, arm.n), rng.uniform(-2, 2, arm.n)
        expected = (arm.jacobian(q + h * qd) - arm.jacobian(q - h * qd)) / (2 * h) @ qd
        assert scaled_error(arm.jacobian_dot_qd(q, qd), expected) < TOL_FD


@pytest.mark.parametrize("representation", sorted(chain.REPRESENTATIONS))
def test_analytic_jacobian_matches_finite_differences_of_the_angles(representation):
    arm = robot("puma560")
    rep = chain.REPRESENTATIONS[representation]
    function = arm.functions[f"analytic_jacobian_{representation}"]
    rng = np.random.default_rng(3)
    checked = 0
    for q in rng.uniform(-2, 2, (20, arm.n)):
        Ja, x = (np.array(v) for v in function(q))
        angles = x[3:, 0]
        # stay away from the representation singularity and from the +-pi wrap of atan2
        middle = angles[1] if representation == "rpy" else angles[1] - math.pi / 2
        if abs(abs(middle) - math.pi / 2) < 0.2 or np.any(np.abs(np.abs(angles) - math.pi) < 0.05):
            continue
        expected = central_difference(lambda v: np.array(function(v)[1]).ravel(), q)
        assert scaled_error(Ja, expected) < TOL_FD
        assert scaled_error(arm.analytic_jacobian(q, representation), Ja) == 0.0
        E = np.array(ca.DM(rep.rate(ca.DM(angles))))
        E_inv = np.array(ca.DM(rep.inverse_rate(ca.DM(angles))))
        assert scaled_error(E_inv @ E, np.eye(3)) < TOL_EXACT
        checked += 1
    assert checked >= 5


@settings(max_examples=20, deadline=None)
@given(description=chains(), seed=st.integers(0, 2**16))
def test_frames_match_pinocchio(description, seed):
    import pinocchio as pin

    arm = Robot(description)
    model, posts = pinocchio_model(description)
    data = model.createData()
    q = np.random.default_rng(seed).uniform(-2, 2, arm.n)
    pin.forwardKinematics(model, data, q)
    frames = arm.fkine_all(q)
    for i, post in enumerate(posts):
        assert scaled_error(frames[i], data.oMi[i + 1].homogeneous @ post) < TOL_EXACT
    tool = frames[-1] @ np.array(description.tool)
    assert scaled_error(arm.fkine(q), tool) < TOL_EXACT


def test_batches_equal_single_evaluations():
    arm = robot("scara")
    q = np.random.default_rng(4).uniform(-1, 1, (5, arm.n))
    assert arm.fkine(q).shape == (5, 4, 4)
    assert arm.fkine_all(q).shape == (5, arm.n, 4, 4)
    assert arm.jacobian(q).shape == (5, 6, arm.n)
    for k in range(5):
        assert np.array_equal(arm.fkine(q)[k], arm.fkine(q[k]))
        assert np.array_equal(arm.fkine_all(q)[k], arm.fkine_all(q[k]))
        assert np.array_equal(arm.jacobian(q)[k], arm.jacobian(q[k]))


def test_prismatic_and_modified_conventions_by_hand():
    # modified DH, prismatic joint along z0 after a 90 degree twist about x: moves along -y of the base
    link = LinkDescription(joint="prismatic", alpha=math.pi / 2, a=0.2, mass=1.0)
    arm = Robot(ChainDescription("slider", (link,), convention="modified"))
    assert scaled_error(arm.fkine([0.5])[:3, 3], [0.2, -0.5, 0.0]) < TOL_EXACT
    assert scaled_error(arm.jacobian([0.5])[:, 0], [0, -1, 0, 0, 0, 0]) < TOL_EXACT
