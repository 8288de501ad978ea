"""Dynamics: Newton--Euler vs Euler--Lagrange (independent routes), Pinocchio, forward dynamics, energy."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.models import dynamics
from designkit.models.robot import Robot
from designkit.models.robots import robot
from tests.models.support import (
    TOL_EXACT,
    ZOO,
    chains,
    pinocchio_model,
    random_states,
    scaled_error,
)

VARIANTS = [(name, friction, rotors) for name in ZOO for friction, rotors in ((False, False), (True, True))]


def _lagrange_torque(arm: Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    M = arm.mass_matrix(q)
    C = arm.coriolis_matrix(q, qd)
    return (np.einsum("nij,nj->ni", M, qdd) + np.einsum("nij,nj->ni", C, qd) + arm.gravity_torque(q)
            + arm.friction_torque(qd))


@pytest.mark.parametrize(("name", "friction", "rotors"), VARIANTS)
def test_newton_euler_equals_euler_lagrange(name, friction, rotors):
    arm = robot(name, friction=friction, motor_inertia=rotors)
    q, qd, qdd = random_states(np.random.default_rng(10), arm.n, 20)
    assert scaled_error(arm.inverse_dynamics(q, qd, qdd), _lagrange_torque(arm, q, qd, qdd)) < TOL_EXACT


@settings(max_examples=15, deadline=None)
@given(description=chains(), seed=st.integers(0, 2**16))
def test_random_chains_newton_euler_euler_lagrange_and_pinocchio(description, seed):
    import pinocchio as pin

    arm = Robot(description)
    q, qd, qdd = random_states(np.random.default_rng(seed), arm.n, 4)
    tau = arm.inverse_dynamics(q, qd, qdd)
    assert scaled_error(tau, _lagrange_torque(arm, q, qd, qdd)) < TOL_EXACT
    model, _ = pinocchio_model(description)
    data = model.createData()
    for k in range(q.shape[0]):
        assert scaled_error(tau[k], pin.rnea(model, data, q[k], qd[k], qdd[k])) < TOL_EXACT
        assert scaled_error(arm.mass_matrix(q[k]), pin.crba(model, data, q[k])) < TOL_EXACT
        assert scaled_error(arm.gravity_torque(q[k]), pin.computeGeneralizedGravity(model, data, q[k])) < TOL_EXACT


@pytest.mark.parametrize("name", ZOO)
def test_forward_dynamics_inverts_inverse_dynamics(name):
    arm = robot(name, friction=True, motor_inertia=True)
    q, qd, qdd = random_states(np.random.default_rng(14), arm.n, 10)
    tau = arm.inverse_dynamics(q, qd, qdd)
    assert scaled_error(arm.forward_dynamics(q, qd, tau), qdd) < 1e-9


@pytest.mark.parametrize("name", ZOO)
def test_power_balance(name):
    """d/dt (T + V) = qd' (tau - friction) along the forward dynamics, by exact differentiation."""
    arm = robot(name, friction=True, motor_inertia=True)
    f = arm.functions
    q, qd, tau = (ca.SX.sym(s, arm.n) for s in ("q", "qd", "tau"))
    qdd = f["forward_dynamics"](q, qd, tau)
    energy = f["kinetic_energy"](q, qd) + f["potential_energy"](q)
    x, xdot = ca.vertcat(q, qd), ca.vertcat(qd, qdd)
    power = ca.Function("power", [q, qd, tau], [ca.jtimes(energy, x, xdot), ca.dot(qd, tau - f["friction_torque"](qd))])
    rng = np.random.default_rng(15)
    for q0, qd0, tau0 in zip(*random_states(rng, arm.n, 5, scale=3.0), strict=True):
        lhs, rhs = (float(v) for v in power(q0, qd0, tau0))
        assert abs(lhs - rhs) < TOL_EXACT * (1 + abs(rhs)) * 100


def _rk4_energy_drift(arm: Robot, q0: np.ndarray, qd0: np.ndarray, step: float, duration: float) -> float:
    n = arm.n
    x = ca.SX.sym("x", 2 * n)
    fd = arm.functions["forward_dynamics"]

    def rhs(state: ca.SX) -> ca.SX:
        return ca.vertcat(state[n:], fd(state[:n], state[n:], ca.DM.zeros(n)))

    k1 = rhs(x)
    k2 = rhs(x + step / 2 * k1)
    k3 = rhs(x + step / 2 * k2)
    k4 = rhs(x + step * k3)
    rk4 = ca.Function("rk4", [x], [x + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)], ["x"], ["x_next"])
    steps = round(duration / step)
    trajectory = np.array(rk4.mapaccum("simulate", steps)(np.concatenate([q0, qd0]))).T
    states = np.vstack([np.concatenate([q0, qd0]), trajectory])
    energy = arm.energy(states[:, :n], states[:, n:]).total
    return float(np.max(np.abs(energy - energy[0])))


@pytest.mark.parametrize("name", ["planar2r", "puma560"])
def test_energy_is_conserved_in_free_frictionless_motion(name):
    arm = robot(name)
    rng = np.random.default_rng(16)
    q0, qd0 = rng.uniform(-1, 1, arm.n), rng.uniform(-1, 1, arm.n)
    drifts = [_rk4_energy_drift(arm, q0, qd0, step, 1.0) for step in (0.01, 0.005)]
    scale = abs(arm.energy(q0, qd0).kinetic) + 1.0
    assert drifts[0] < 1e-4 * scale
    assert drifts[1] < drifts[0] / 8  # fourth-order method: about 1/16 per halving


def test_symbolic_parameters_give_the_numeric_model():
    from designkit.models.robots.planar2r import DEFAULTS

    numeric = robot("planar2r")
    symbolic = robot("planar2r", symbolic=True)
    assert symbolic.parameters is None
    assert symbolic.symbol_names == tuple(DEFAULTS)
    assert symbolic.functions["inverse_dynamics"].name_in() == ["q", "qd", "qdd", "p"]
    p = np.array([DEFAULTS[name] for name in symbolic.symbol_names])
    q, qd, qdd = random_states(np.random.default_rng(17), 2, 5)
    assert scaled_error(symbolic.inverse_dynamics(q, qd, qdd, p=p), numeric.inverse_dynamics(q, qd, qdd)) < 1e-14
    assert scaled_error(symbolic.mass_matrix(q, p=p), numeric.mass_matrix(q)) < 1e-14
    assert scaled_error(symbolic.parameter_values(p), numeric.parameters) < 1e-14


def test_dynamics_reexports_the_names_of_its_route_modules():
    """``designkit.models.dynamics`` keeps its public names; each is the defining module's object."""
    from designkit.models import euler_lagrange, inertial_parameters, newton_euler

    for name in dynamics.__all__:
        owners = [m for m in (euler_lagrange, inertial_parameters, newton_euler) if name in m.__all__]
        assert owners or name in ("friction_torque", "forward_dynamics"), name
        for module in owners:
            assert getattr(dynamics, name) is getattr(module, name)
