"""The unisolvent evaluation set: its size, the degree bounds it relies on, and the verification's teeth."""

from __future__ import annotations

import itertools

import casadi
import numpy as np

import designkit.models.base_parameters as discovery
from designkit.models.robots import robot
from designkit.models.unisolvent import evaluation_states, relation_residuals


def harmonics(values: np.ndarray) -> np.ndarray:
    """Magnitude of each Fourier harmonic of samples on an equispaced grid (axis 0)."""
    return np.abs(np.fft.rfft(values, axis=0)) / values.shape[0]


def test_evaluation_set_size():
    q, qd, qdd = evaluation_states(("revolute",) * 6)
    assert q.shape == (3**6 + 5**5 * (6 + 3 * 6 + 15), 6) == qd.shape == qdd.shape
    q, _, _ = evaluation_states(("revolute", "prismatic"))
    assert q.shape[0] == 3 * 2 + 3 * (2 + 6 + 1)


def test_degree_bounds_and_q1_independence():
    """The unisolvence argument: degree <= 2 per joint (<= 1 for gravity), inertial part free of q1."""
    arm = robot("puma560", friction=True, motor_inertia=True)
    reg = arm.functions["regressor"]
    rng = np.random.default_rng(5)
    grid = 2 * np.pi * np.arange(9) / 9
    for j, _ in itertools.product(range(6), range(2)):
        q0, qd, qdd = rng.uniform(-2, 2, (3, 6))
        qs = np.tile(q0, (9, 1))
        qs[:, j] = grid
        full = np.stack([np.asarray(reg(q, qd, qdd)) for q in qs])
        gravity = np.stack([np.asarray(reg(q, 0 * qd, 0 * qdd)) for q in qs])
        scale = np.abs(full).max()
        assert harmonics(full - gravity)[3:].max() < 1e-12 * scale
        assert harmonics(gravity)[2:].max() < 1e-12 * scale
        if j == 0:
            assert np.abs(full - gravity - (full - gravity)[0]).max() < 1e-12 * scale


def test_structure_in_rates():
    """W is affine in qdd and, apart from friction, a quadratic form in qd (structural check)."""
    arm = robot("puma560")
    q, qd, qdd = (casadi.SX.sym(s, 6) for s in ("q", "qd", "qdd"))
    W = arm.functions["regressor"](q, qd, qdd)
    assert not casadi.depends_on(casadi.jacobian(casadi.vec(W), qdd), casadi.vertcat(qd, qdd))
    hessian = casadi.jacobian(casadi.jacobian(casadi.vec(W), qd), qd)
    assert not casadi.depends_on(hessian, casadi.vertcat(qd, qdd))


def test_verification_detects_a_wrong_coefficient():
    """Relations found by discovery pass; the same relations with coefficients perturbed by 1e-7 fail."""
    arm = robot("scara")
    reg = arm.functions["regressor"]
    found = discovery._discover(discovery._stacked_r(reg, *discovery._sample_states(4, 500)),
                                discovery._preference_order(40, 4), 1e-8, 1e-10)
    states = evaluation_states(("revolute", "revolute", "prismatic", "revolute"))
    claims = {"kept": found.kept, "dependent": found.dependent, "zero": found.zero}
    assert relation_residuals(reg, states, relation=found.relation, **claims)[0] < 1e-12
    relation = found.relation.copy()
    relation[relation != 0] *= 1 + 1e-7
    assert relation_residuals(reg, states, relation=relation, **claims)[0] > 1e-9
