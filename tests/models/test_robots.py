"""Built-in robots: registry, overrides, the notes' SIMNOG closed forms, PUMA 560 references, Pinocchio."""

from __future__ import annotations

import math

import numpy as np
import pytest

import designkit as dk
from designkit.errors import ModelError
from designkit.models.robot import Robot, robot_from_dh
from designkit.models.robots import ROBOTS, puma560, robot
from tests.models.support import TOL_EXACT, TOL_REFERENCE, ZOO, pinocchio_model, random_states, scaled_error


def test_registry_builds_every_robot_by_name():
    assert set(ROBOTS) == set(ZOO)
    for name in ZOO:
        arm = robot(name)
        assert isinstance(arm, Robot) and arm.name == name and arm.n == len(arm.description.links)
        assert arm.description.source
    assert dk.robot("planar2r").n == 2


def test_overrides_replace_named_parameters():
    arm = dk.robot("planar2r", m1=1.0, d2=0.5)
    assert arm.description.links[0].mass == 1.0
    assert arm.description.links[1].a == 0.5
    assert robot("puma560", g=0.0).gravity_torque(puma560.QN) == pytest.approx(np.zeros(6), abs=1e-15)


@pytest.mark.parametrize(("name", "kwargs", "path"), [
    ("ur5", {}, "robot"),
    ("planar2r", {"m3": 1.0}, "planar2r.m3"),
    ("planar2r", {"m1": "heavy"}, "planar2r.m1"),
    ("puma560", {"symbolic": ("d9",)}, "puma560.d9"),
])
def test_bad_names_and_values_raise_spec_errors(name, kwargs, path):
    with pytest.raises(ModelError) as info:
        robot(name, **kwargs)
    assert info.value.path == path


# ----------------------------------------------------------------------------- SIMNOG (appendix B)


def _simnog_terms(p: dict[str, float], q: np.ndarray) -> dict[str, float]:
    """Appendix B, fig. 2.2, as printed (x11 = q1, x21 = q2)."""
    m1, m2, d1, d2, I1, I2, g = (p[k] for k in ("m1", "m2", "d1", "d2", "I1", "I2", "g"))
    c2, s2 = math.cos(q[1]), math.sin(q[1])
    return {
        "D11": m1 * d1**2 / 4 + m2 * (d1**2 + d2**2 / 4 + d1 * d2 * c2) + I1 + I2,
        "D12": m2 * (d2**2 / 4 + d1 * d2 * c2 / 2) + I2,
        "D22": m2 * d2**2 / 4 + I2,
        "D112": -m2 * d1 * d2 * s2,  # coefficient of x12*x22, i.e. D_112 + D_121
        "D122": -m2 * d1 * d2 * s2 / 2,
        "D211": m2 * d1 * d2 * s2 / 2,
        "T1g": -g * ((m2 + m1 / 2) * d1 * math.cos(q[0]) + m2 * d2 * math.cos(q[0] + q[1]) / 2),
        "T2g": -g * (m2 * d2 * math.cos(q[0] + q[1]) / 2),
    }


def _random_simnog(rng: np.random.Generator) -> dict[str, float]:
    keys = ("m1", "m2", "d1", "d2", "I1", "I2", "f1", "f2", "g")
    return dict(zip(keys, rng.uniform(0.2, 3.0, len(keys)), strict=True))


def test_planar2r_matches_the_appendix_closed_forms():
    rng = np.random.default_rng(40)
    for _ in range(10):
        params = _random_simnog(rng)
        arm = robot("planar2r", **params)
        q = rng.uniform(-math.pi, math.pi, 2)
        ref = _simnog_terms(params, q)
        M, G, g = arm.mass_matrix(q), arm.christoffel(q), arm.gravity_torque(q)
        assert scaled_error(M, [[ref["D11"], ref["D12"]], [ref["D12"], ref["D22"]]]) < TOL_EXACT
        assert G[0, 0, 1] + G[0, 1, 0] == pytest.approx(ref["D112"], rel=1e-12, abs=1e-14)
        assert G[0, 1, 1] == pytest.approx(ref["D122"], rel=1e-12, abs=1e-14)
        assert G[1, 0, 0] == pytest.approx(ref["D211"], rel=1e-12, abs=1e-14)
        for i, j, k in ((0, 0, 0), (1, 0, 1), (1, 1, 0), (1, 1, 1)):  # the terms the appendix leaves out
            assert abs(G[i, j, k]) < 1e-14
        assert scaled_error(-g, [ref["T1g"], ref["T2g"]]) < TOL_EXACT


def test_planar2r_forward_dynamics_matches_the_simnog_state_equations():
    """x12', x22' of fig. 2.2 with the joint friction T_iv = -f_i x_i2 (see docs/models.md on T1v)."""
    rng = np.random.default_rng(41)
    for _ in range(10):
        params = _random_simnog(rng)
        arm = robot("planar2r", friction=True, **params)
        q, qd, torque = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2), rng.uniform(-5, 5, 2)
        r = _simnog_terms(params, q)
        a = 1 / (r["D11"] * r["D22"] - r["D12"] ** 2)
        t1 = torque[0] + r["T1g"] - params["f1"] * qd[0]
        t2 = torque[1] + r["T2g"] - params["f2"] * qd[1]
        e1 = t1 - r["D112"] * qd[0] * qd[1] - r["D122"] * qd[1] ** 2
        e2 = t2 - r["D211"] * qd[0] ** 2
        expected = [a * r["D22"] * e1 - a * r["D12"] * e2, -a * r["D12"] * e1 + a * r["D11"] * e2]
        assert scaled_error(arm.forward_dynamics(q, qd, torque), expected) < 1e-10


# ----------------------------------------------------------------------------- PUMA 560

# Robotics Toolbox for Python, unit tests of its Puma560 model (test_gravload, test_inertia,
# test_itorque, test_coriolis), 4 decimals; gravity 9.81 m/s^2 downwards, rotor inertia included in M.
RTB_GRAVLOAD_QN = [-0.0000, 31.6399, 6.0351, 0.0000, 0.0283, 0]
RTB_INERTIA_QN = [
    [3.6594, -0.4044, 0.1006, -0.0025, 0.0000, -0.0000],
    [-0.4044, 4.4137, 0.3509, 0.0000, 0.0024, 0.0000],
    [0.1006, 0.3509, 0.9378, 0.0000, 0.0015, 0.0000],
    [-0.0025, 0.0000, 0.0000, 0.1925, 0.0000, 0.0000],
    [0.0000, 0.0024, 0.0015, 0.0000, 0.1713, 0.0000],
    [-0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.1941],
]
RTB_ITORQUE_QN = [3.1500, 9.4805, 3.6189, 0.1901, 0.3519, 0.5823]  # M(qn) @ [1, 2, 3, 1, 2, 3]
RTB_CORIOLIS_QN = [  # C(qn, qd = [1, 2, 3, 1, 2, 3])
    [-0.1735, -2.0494, -0.1178, -0.0002, -0.0045, 0.0001],
    [0.6274, 1.1572, 1.9287, -0.0015, -0.0003, -0.0000],
    [-0.3608, -0.7734, -0.0018, -0.0009, -0.0064, -0.0000],
    [0.0011, 0.0005, -0.0001, 0.0002, 0.0002, -0.0001],
    [-0.0002, 0.0028, 0.0046, -0.0002, -0.0000, -0.0000],
    [0.0001, 0.0000, 0.0000, 0.0000, 0.0000, 0],
]


def test_puma560_matches_robotics_toolbox_reference_values():
    arm = robot("puma560", motor_inertia=True)
    qn, ramp = puma560.QN, np.array([1.0, 2, 3, 1, 2, 3])
    assert np.max(np.abs(arm.gravity_torque(qn) - RTB_GRAVLOAD_QN)) < TOL_REFERENCE
    assert np.max(np.abs(arm.inverse_dynamics(qn, np.zeros(6), np.zeros(6)) - RTB_GRAVLOAD_QN)) < TOL_REFERENCE
    assert np.max(np.abs(arm.mass_matrix(qn) - RTB_INERTIA_QN)) < TOL_REFERENCE
    assert np.max(np.abs(arm.mass_matrix(qn) @ ramp - RTB_ITORQUE_QN)) < TOL_REFERENCE
    assert np.max(np.abs(arm.coriolis_matrix(qn, ramp) - RTB_CORIOLIS_QN)) < TOL_REFERENCE


def test_puma560_inverse_dynamics_is_compact():
    # operation-count goal of the model layer: <= 730 CasADi instructions with numeric parameters
    assert robot("puma560").functions["inverse_dynamics"].n_instructions() <= 730


@pytest.mark.parametrize("name", ["planar2r", "scara", "puma560"])
def test_zoo_dynamics_match_pinocchio(name):
    import pinocchio as pin

    arm = robot(name)
    model, posts = pinocchio_model(arm.description)
    data = model.createData()
    q, qd, qdd = random_states(np.random.default_rng(42), arm.n, 10)
    tau = arm.inverse_dynamics(q, qd, qdd)
    for k in range(q.shape[0]):
        assert scaled_error(tau[k], pin.rnea(model, data, q[k], qd[k], qdd[k])) < TOL_EXACT
        assert scaled_error(arm.mass_matrix(q[k]), pin.crba(model, data, q[k])) < TOL_EXACT
        pin.forwardKinematics(model, data, q[k])
        assert scaled_error(arm.fkine(q[k]), data.oMi[arm.n].homogeneous @ posts[-1]) < TOL_EXACT


# ----------------------------------------------------------------------------- the Robot API


def test_unknown_representation_names_the_argument():
    with pytest.raises(ModelError, match="representation"):
        robot("planar2r").analytic_jacobian(np.zeros(2), "axis-angle")


def test_robot_from_dh_accepts_fields_and_validates():
    arm = robot_from_dh(name="pendulum", links=[{"a": 1.0, "mass": 2.0, "com": (-0.5, 0, 0)}],
                        gravity=(0.0, -9.81, 0.0))
    assert arm.gravity_torque([0.0])[0] == pytest.approx(9.81)
    same = robot_from_dh(arm.description, friction=True)
    assert same.friction and same.parameter_names[-2:] == ("fv1", "fc1")
    with pytest.raises(ModelError) as info:
        robot_from_dh(name="bad", links=[{"joint": "spherical"}])
    assert info.value.path == "links[0].joint"
    with pytest.raises(ModelError) as info:
        robot_from_dh(name="bad", links=[{"mass": -1.0}])
    assert info.value.path == "links[0].mass"
    with pytest.raises(ModelError):
        robot_from_dh(name="empty", links=[])
    assert arm.replace(motor_inertia=True).motor_inertia
