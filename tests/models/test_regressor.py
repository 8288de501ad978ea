"""Regressor: tau = W P, parameter layout and names, linearity in the physical parameters."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from designkit.models import regressor
from designkit.models.robots import robot
from tests.models.support import TOL_EXACT, ZOO, random_states, scaled_error

VARIANTS = [(name, friction, rotors) for name in ZOO for friction in (False, True) for rotors in (False, True)]


@pytest.mark.parametrize(("name", "friction", "rotors"), VARIANTS)
def test_regressor_times_parameters_is_the_inverse_dynamics(name, friction, rotors):
    arm = robot(name, friction=friction, motor_inertia=rotors)
    q, qd, qdd = random_states(np.random.default_rng(20), arm.n, 10)
    W = arm.regressor(q, qd, qdd)
    assert W.shape == (10, arm.n, len(arm.parameter_names))
    assert arm.parameters.shape == (len(arm.parameter_names),)
    assert scaled_error(W @ arm.parameters, arm.inverse_dynamics(q, qd, qdd)) < TOL_EXACT


def test_parameter_names_and_layout():
    names = regressor.parameter_names(2, friction=True, motor_inertia=True)
    assert names[:10] == ("m1", "mcx1", "mcy1", "mcz1", "Ixx1", "Ixy1", "Ixz1", "Iyy1", "Iyz1", "Izz1")
    assert names[10] == "m2"
    assert names[20:] == ("fv1", "fc1", "fv2", "fc2", "Ia1", "Ia2")
    assert len(set(names)) == len(names)
    arm = robot("puma560", friction=True, motor_inertia=True)
    P = dict(zip(arm.parameter_names, arm.parameters, strict=True))
    link2 = arm.description.links[1]
    assert P["m2"] == 17.4
    assert P["mcx2"] == pytest.approx(17.4 * -0.3638, rel=1e-15)
    assert P["Izz2"] == pytest.approx(0.539 + 17.4 * (0.3638**2 + 0.006**2), rel=1e-15)
    assert P["Ia2"] == pytest.approx(link2.gear_ratio**2 * link2.motor_inertia, rel=1e-15)
    assert P["fv2"] == link2.viscous


@pytest.mark.parametrize("change", [{"m2": 4.0}, {"I1": 0.3}, {"f2": 0.7}])
def test_torque_change_from_a_parameter_change_is_w_times_the_parameter_change(change):
    # an independent physical perturbation: a different robot, same regressor
    base = robot("planar2r", friction=True)
    other = robot("planar2r", friction=True, **change)
    q, qd, qdd = random_states(np.random.default_rng(21), 2, 10)
    delta_tau = other.inverse_dynamics(q, qd, qdd) - base.inverse_dynamics(q, qd, qdd)
    delta_p = other.parameters - base.parameters
    assert np.count_nonzero(delta_p) >= 1
    assert scaled_error(base.regressor(q, qd, qdd) @ delta_p, delta_tau) < TOL_EXACT


def test_regressor_function_is_named_and_independent_of_the_parameters():
    arm = robot("scara", friction=True)
    W = arm.functions["regressor"]
    assert W.name() == "regressor"
    assert W.name_in() == ["q", "qd", "qdd"] and W.name_out() == ["W"]
    # the same regressor serves a different (heavier) robot of the same kinematics
    heavy = robot("scara", friction=True, m2=12.0, m4=2.0)
    q, qd, qdd = random_states(np.random.default_rng(22), arm.n, 5)
    assert scaled_error(arm.regressor(q, qd, qdd) @ heavy.parameters, heavy.inverse_dynamics(q, qd, qdd)) < TOL_EXACT


def test_symbolic_description_regressor_depends_on_kinematic_symbols_only():
    arm = robot("planar2r", symbolic=("m1", "d1", "g"))
    assert arm.parameters is None
    q, qd, qdd = random_states(np.random.default_rng(23), 2, 4)
    p = np.array([1.5, 0.6, 9.81])  # m1, d1, g in the order of DEFAULTS
    W1 = arm.regressor(q, qd, qdd, p=p)
    W2 = arm.regressor(q, qd, qdd, p=np.array([7.0, 0.6, 9.81]))  # another mass: same W
    assert np.array_equal(W1, W2)
    P = arm.parameter_values(p)
    assert scaled_error(W1 @ P, arm.inverse_dynamics(q, qd, qdd, p=p)) < TOL_EXACT


def test_parameter_vector_is_linear_in_symbolic_masses():
    m = ca.SX.sym("m")
    arm = robot("onelink", m=m)
    P = arm.functions["parameters"]
    assert P.name_in() == ["p"]
    assert float(P(2.0)[0]) == 2.0
    assert float(P(2.0)[1]) == pytest.approx(2.0 * -0.25)
