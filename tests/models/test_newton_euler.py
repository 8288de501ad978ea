"""Recursive Newton--Euler: linear in the inertial parameters, the same torques from numeric or symbolic ones."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from designkit.models.inertial_parameters import inertial_parameters
from designkit.models.newton_euler import rnea
from designkit.models.robots import robot
from tests.models.support import TOL_EXACT, random_states, scaled_error


@pytest.mark.parametrize("name", ["planar2r", "scara", "puma560"])
def test_rnea_is_linear_in_the_inertial_parameters(name):
    description = robot(name).description
    n = description.n
    q, qd, qdd = (ca.SX.sym(s, n) for s in ("q", "qd", "qdd"))
    P = ca.SX.sym("P", 10 * n)
    tau = rnea(description, q, qd, qdd, ca.vertsplit(P))
    W = ca.jacobian(tau, P)
    assert not ca.depends_on(W, P)
    numeric = ca.Function("tau", [q, qd, qdd], [rnea(description, q, qd, qdd)])
    regressor = ca.Function("W", [q, qd, qdd], [W])
    values = np.array([float(v) for v in inertial_parameters(description)])
    for state in zip(*random_states(np.random.default_rng(21), n, 5), strict=True):
        expected = np.asarray(numeric(*state)).ravel()
        assert scaled_error(np.asarray(regressor(*state)) @ values, expected) < TOL_EXACT


def test_gravity_argument_overrides_the_description():
    description = robot("onelink").description
    q, qd, qdd = (ca.SX.sym(s, 1) for s in ("q", "qd", "qdd"))
    at_rest = ca.Function("g", [q], [rnea(description, q, qd * 0, qdd * 0, gravity=(0.0, 0.0, 0.0))])
    assert float(at_rest(0.3)) == 0.0
