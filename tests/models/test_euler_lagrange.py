"""Euler--Lagrange terms: M symmetric positive definite, Mdot - 2C skew, Christoffel symbols vs finite differences."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from designkit.models.robots import robot
from tests.models.support import TOL_EXACT, TOL_FD, ZOO, central_difference, random_states, scaled_error


@pytest.mark.parametrize("name", ZOO)
def test_mass_matrix_is_symmetric_positive_definite(name):
    arm = robot(name, motor_inertia=True)
    q, _, _ = random_states(np.random.default_rng(11), arm.n, 30)
    M = arm.mass_matrix(q)
    assert np.array_equal(M, np.transpose(M, (0, 2, 1)))
    assert np.min(np.linalg.eigvalsh(M)) > 0


@pytest.mark.parametrize("name", ZOO)
def test_mdot_minus_2c_is_skew_symmetric(name):
    arm = robot(name)
    mass = arm.functions["mass_matrix"]
    q_sym, qd_sym = ca.SX.sym("q", arm.n), ca.SX.sym("qd", arm.n)
    mdot = ca.Function("Mdot", [q_sym, qd_sym], [ca.jtimes(mass(q_sym), q_sym, qd_sym)])
    rng = np.random.default_rng(12)
    for q, qd, _ in zip(*random_states(rng, arm.n, 5), strict=True):
        Mdot = np.array(mdot(q, qd))
        h = 1e-5
        Mdot_fd = (arm.mass_matrix(q + h * qd) - arm.mass_matrix(q - h * qd)) / (2 * h)
        assert scaled_error(Mdot, Mdot_fd) < TOL_FD
        N = Mdot - 2 * arm.coriolis_matrix(q, qd)
        assert np.max(np.abs(N + N.T)) < TOL_EXACT * (1 + np.max(np.abs(Mdot)))


@pytest.mark.parametrize("name", ["planar2r", "scara", "puma560"])
def test_christoffel_symbols_match_finite_differences_of_m(name):
    arm = robot(name)
    q = np.random.default_rng(13).uniform(-2, 2, arm.n)
    dM = central_difference(arm.mass_matrix, q)  # dM[i, j, k] = dM_ij / dq_k
    expected = 0.5 * (dM + np.transpose(dM, (0, 2, 1)) - np.transpose(dM, (2, 1, 0)))
    gamma = arm.christoffel(q)
    assert scaled_error(gamma, expected) < TOL_FD
    assert scaled_error(gamma, np.transpose(gamma, (0, 2, 1))) < TOL_EXACT  # symmetric in j, k
