"""Conformance of every plant to the :class:`~designkit.models.plant.Plant` protocol, and independent checks.

Each plant is checked against routes outside the code under test: central finite differences of
``rhs`` (linearization), the closed-form step response of the link, the numeric zoo robots'
forward dynamics, Pinocchio's ABA on the packaged URDF, the ROBEL state space, and conservation
(frictionless arm) or dissipation (arm with friction) of mechanical energy.

Tolerances (errors scaled as ``|x - ref| / (1 + |ref|)``):

* ``TOL_EXACT`` (1e-10): two exact routes to the same number (same algebra, different code).
* ``TOL_FD`` (1e-6): five-point central differences with step ``FD_STEP`` = 1e-3: truncation ~h^4 times
  the fifth derivatives, rounding ~eps |xdot| / h with |xdot| up to 3e4 rad/s^2 (puma560's light wrist
  against its joint friction); measured worst case 1.6e-7 (puma560), 6e-8 (planar2r), <1e-9 elsewhere.
* ``TOL_ODE`` (1e-7): ``solve_ivp`` (DOP853, rtol 1e-11, atol 1e-12) against the link's closed form.
* ``TOL_ENERGY`` (1e-8): drift of the frictionless arm's energy over 3 s with the same integrator
  (measured 2e-10), relative to ``1 + |E0|``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from importlib.resources import files

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from designkit.errors import ModelError
from designkit.models.elastic import ElasticJointPlant, elastic_state_space
from designkit.models.linear_system import LinearSystem
from designkit.models.link import LinkPlant
from designkit.models.plant import Plant, PlantBase
from designkit.models.robot_plant import RobotPlant, chain_plant, zoo_plant
from designkit.models.robots import planar2r, robot
from designkit.models.robots.elastic_link import DEFAULTS as ELASTIC_DEFAULTS
from designkit.models.urdf import description_from_urdf
from tests.models.support import scaled_error

TOL_EXACT = 1e-10
TOL_FD = 1e-6
TOL_ODE = 1e-7
TOL_ENERGY = 1e-8
FD_STEP = 1e-3

PLANAR2R_URDF = files("designkit.models.robots") / "planar2r.urdf"
URDF_GRAVITY = (0.0, -9.81, 0.0)
ELASTIC_GRAVITY = dataclasses.replace(ELASTIC_DEFAULTS, mgl=3.0, R2=0.8)


@functools.cache
def _urdf_plant() -> RobotPlant:
    return chain_plant(description_from_urdf(PLANAR2R_URDF, gravity=URDF_GRAVITY), source="planar2r.urdf")


# name -> (factory, parameter to change, new value, indices of xdot that must change with it)
CASES: dict[str, tuple[Callable[[], PlantBase], str, float, tuple[int, ...]]] = {
    "link": (lambda: LinkPlant(2, 0.5), "tau", 0.25, (1,)),
    "planar2r": (functools.cache(lambda: zoo_plant("planar2r")), "m2", 4.0, (2, 3)),
    "scara": (functools.cache(lambda: zoo_plant("scara")), "m3", 3.0, (4, 5, 6, 7)),
    "puma560": (functools.cache(lambda: zoo_plant("puma560")), "m3", 6.0, tuple(range(6, 12))),
    "dh_chain": (functools.cache(lambda: chain_plant(planar2r.description())), "m2", 4.0, (2, 3)),
    "urdf_chain": (_urdf_plant, "f1", 3.0, (2, 3)),
    "elastic": (lambda: ElasticJointPlant(ELASTIC_DEFAULTS), "J2", 0.8, (3,)),
    "elastic_gravity": (lambda: ElasticJointPlant(ELASTIC_GRAVITY), "mgl", 5.0, (3,)),
}
NAMES = tuple(CASES)


def _plant(name: str) -> PlantBase:
    return CASES[name][0]()


def _jacobian_fd(f: Callable[[np.ndarray], np.ndarray], z: np.ndarray, h: float = FD_STEP) -> np.ndarray:
    """Five-point central differences ``(-f(z+2h) + 8 f(z+h) - 8 f(z-h) + f(z-2h)) / 12h``, column by column."""
    columns = []
    for k in range(z.size):
        e = np.zeros_like(z)
        e[k] = h
        columns.append((-f(z + 2 * e) + 8 * f(z + e) - 8 * f(z - e) + f(z - 2 * e)) / (12 * h))
    return np.stack(columns, axis=-1)


def _random_point(plant: PlantBase, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A random state (velocities away from 0, where Coulomb friction switches), input and disturbance."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, plant.n_states)
    x[list(plant.velocities)] = rng.choice([-1.0, 1.0], plant.n_joints) * rng.uniform(0.3, 1.0, plant.n_joints)
    return x, rng.uniform(-1.0, 1.0, plant.n_inputs), rng.uniform(-1.0, 1.0, plant.n_disturbances)


# ----------------------------------------------------------------------------------- protocol


@pytest.mark.parametrize("name", NAMES)
def test_signals_units_and_ode_signature(name):
    plant = _plant(name)
    assert isinstance(plant, Plant)
    f = plant.ode()
    assert isinstance(f, ca.Function)
    assert f.name_in() == ["x", "u", "d", "p"] and f.name_out() == ["xdot"]
    sizes = (plant.n_states, plant.n_inputs, plant.n_disturbances, len(plant.parameters))
    assert tuple(f.size1_in(i) for i in range(4)) == sizes
    assert all(f.size2_in(i) == 1 for i in range(4))
    assert (f.size1_out(0), f.size2_out(0)) == (plant.n_states, 1)
    assert plant.n_states > 0 and plant.n_inputs > 0
    for item in (*plant.states, *plant.inputs, *plant.disturbances, *plant.parameters):
        assert isinstance(item.unit, str) and item.unit.strip(), f"{item.name} has no unit"
    for group in (plant.states, plant.inputs, plant.disturbances, plant.parameters):
        assert len({s.name for s in group}) == len(group), "names must be distinct"
    indices = (*plant.positions, *plant.velocities)
    assert len(set(indices)) == len(indices), "positions and velocities must be distinct states"
    assert all(isinstance(i, int) and 0 <= i < plant.n_states for i in indices)
    assert len(plant.positions) == len(plant.velocities) == plant.n_joints >= 1
    # a position and its rate share a length unit: rad -> rad/s, m -> m/s
    for i, j in zip(plant.positions, plant.velocities, strict=True):
        assert plant.states[j].unit == f"{plant.states[i].unit}/s"
    vec = plant.parameter_vector
    assert vec.shape == (len(plant.parameters),) and np.all(np.isfinite(vec))
    with pytest.raises(ValueError, match="read-only"):
        vec[0] = 1.0
    xdot = plant.rhs(*_random_point(plant, 0))
    assert xdot.shape == (plant.n_states,) and np.all(np.isfinite(xdot))


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("seed", [1, 2])
def test_linearize_is_the_finite_difference_jacobian_of_rhs(name, seed):
    """A = d rhs/dx, B = d rhs/d[u; d] (inputs, then disturbances), by central differences of rhs."""
    plant = _plant(name)
    x, u, d = _random_point(plant, seed)
    lin = plant.linearize(x, u, d)
    assert isinstance(lin, LinearSystem)
    n, m, k = plant.n_states, plant.n_inputs, plant.n_disturbances
    A_fd = _jacobian_fd(lambda z: plant.rhs(z, u, d), x)
    B_fd = _jacobian_fd(lambda w: plant.rhs(x, w[:m], w[m:]), np.concatenate([u, d]))
    assert lin.A.shape == (n, n) and lin.B.shape == (n, m + k)
    assert scaled_error(lin.A, A_fd) < TOL_FD
    assert scaled_error(lin.B, B_fd) < TOL_FD
    assert lin.inputs == tuple(s.name for s in (*plant.inputs, *plant.disturbances))
    assert lin.states == lin.outputs == tuple(s.name for s in plant.states)
    assert np.array_equal(lin.C, np.eye(n)) and not lin.D.any()
    # d0 defaults to zero disturbance
    zero = plant.linearize(x, u)
    assert scaled_error(zero.A, _jacobian_fd(lambda z: plant.rhs(z, u), x)) < TOL_FD


@pytest.mark.parametrize("name", NAMES)
def test_with_params_returns_a_new_plant_and_leaves_the_original(name):
    _, param, value, changed = CASES[name]
    plant = _plant(name)
    before = plant.parameter_vector.copy()
    old = plant.parameter(param).value
    assert old != value
    other = plant.with_params(**{param: value})
    assert other is not plant and type(other) is type(plant)
    assert other.parameter(param).value == value
    assert plant.parameter(param).value == old and np.array_equal(plant.parameter_vector, before)
    k = plant.parameter_names.index(param)
    expected = before.copy()
    expected[k] = value
    assert np.array_equal(other.parameter_vector, expected), "only the named parameter changes"
    assert other.parameter_names == plant.parameter_names
    assert plant.with_params() is plant

    x, u, d = _random_point(plant, 3)
    f = plant.ode()
    old_xdot = np.asarray(f(x, u, d, before)).ravel()
    new_xdot = np.asarray(f(x, u, d, other.parameter_vector)).ravel()
    assert scaled_error(other.rhs(x, u, d), new_xdot) < TOL_EXACT
    assert scaled_error(plant.rhs(x, u, d), old_xdot) < TOL_EXACT
    diff = np.abs(new_xdot - old_xdot) / (1 + np.abs(old_xdot))
    unchanged = [i for i in range(plant.n_states) if i not in changed]
    assert np.all(diff[list(changed)] > 1e-6), f"{param} must act on states {changed}: {diff}"
    assert np.all(diff[unchanged] == 0.0), f"{param} must not act on states {unchanged}: {diff}"
    # ode_at fixes the parameters: nominal by default, or the given vector
    assert scaled_error(np.asarray(plant.ode_at()(x, u, d)).ravel(), old_xdot) < TOL_EXACT
    assert scaled_error(np.asarray(plant.ode_at(other.parameter_vector)(x, u, d)).ravel(), new_xdot) < TOL_EXACT


@pytest.mark.parametrize("name", NAMES)
def test_with_params_refuses_unknown_and_invalid_values_naming_the_parameter(name):
    plant = _plant(name)
    before = plant.parameter_vector.copy()
    with pytest.raises(ModelError) as info:
        plant.with_params(not_a_parameter=1.0)
    assert info.value.path == "not_a_parameter"
    for par in plant.parameters:
        bad = [math.nan, math.inf, -math.inf, -1.0, "2.0", True] + ([0.0] if par.positive else [])
        for value in bad:
            with pytest.raises(ModelError) as info:
                plant.with_params(**{par.name: value})
            assert info.value.path == par.name, (par.name, value)
            assert "\n" not in str(info.value)
    assert np.array_equal(plant.parameter_vector, before)


_ACCEPTANCE_PLANTS = ("link", "planar2r", "urdf_chain", "elastic_gravity")


@settings(max_examples=40, deadline=None)
@given(case=st.sampled_from(_ACCEPTANCE_PLANTS), index=st.integers(0, 100),
       value=st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, 1e-300]),
                       st.integers(-3, 3)))
def test_with_params_accepts_exactly_the_finite_values_of_the_parameter_sign(case, index, value):
    """Property: accepted iff finite and > 0 (positive parameters) or >= 0 (the others)."""
    plant = _plant(case)
    par = plant.parameters[index % len(plant.parameters)]
    valid = math.isfinite(value) and (value > 0 if par.positive else value >= 0)
    if valid:
        assert plant.with_params(**{par.name: value}).parameter(par.name).value == float(value)
    else:
        with pytest.raises(ModelError) as info:
            plant.with_params(**{par.name: value})
        assert info.value.path == par.name


@pytest.mark.parametrize("name", NAMES)
def test_rest_state_puts_the_positions_in_the_position_states(name):
    plant = _plant(name)
    q = np.random.default_rng(4).uniform(-1.0, 1.0, plant.n_joints)
    x = plant.rest_state(q)
    assert x.shape == (plant.n_states,)
    assert np.array_equal(x[list(plant.positions)], q)
    assert not x[list(plant.velocities)].any()
    if isinstance(plant, ElasticJointPlant):
        # the motor angle sits where the link is: spring unstretched
        assert x[0] == x[2] == q[0] and x[1] == x[3] == 0.0
        rhs = plant.rhs(x, [0.0], [0.0])
        # without gravity an unstretched spring at rest is an equilibrium; with it only the link accelerates
        if plant.params.mgl == 0:
            assert not rhs.any()
        else:
            assert not rhs[:3].any() and rhs[3] != 0
    else:
        others = [i for i in range(plant.n_states) if i not in plant.positions]
        assert not x[others].any()


@pytest.mark.parametrize("name", NAMES)
def test_rest_state_refuses_the_wrong_number_of_positions(name):
    plant = _plant(name)
    for q in (np.zeros(plant.n_joints + 1), np.zeros(0)):
        with pytest.raises(ModelError) as info:
            plant.rest_state(q)
        assert info.value.path == "q"


# ----------------------------------------------------------------------------------- dynamics


@settings(max_examples=15, deadline=None)
@given(Km=st.floats(0.2, 10.0), tau=st.floats(0.05, 2.0), u=st.floats(-5.0, 5.0), xi=st.floats(-2.0, 2.0))
def test_link_step_response_is_the_first_order_closed_form(Km, tau, u, xi):
    """From rest, with u + xi constant: x2 = Km (u + xi)(1 - e^(-t/tau)), x1 its integral."""
    plant = LinkPlant(Km, tau)
    t = np.linspace(0.0, 5.0 * tau, 21)
    sol = solve_ivp(lambda _, x: plant.rhs(x, [u], [xi]), (0.0, t[-1]), [0.0, 0.0], t_eval=t,
                    method="DOP853", rtol=1e-11, atol=1e-12)
    assert sol.success
    decay = 1.0 - np.exp(-t / tau)
    x2 = Km * (u + xi) * decay
    x1 = Km * (u + xi) * (t - tau * decay)
    assert scaled_error(sol.y[1], x2) < TOL_ODE
    assert scaled_error(sol.y[0], x1) < TOL_ODE


@pytest.mark.parametrize("name", ["planar2r", "scara", "puma560"])
def test_robot_plant_rhs_is_the_numeric_zoo_robots_forward_dynamics(name):
    plant = _plant(name)
    arm = robot(name, friction=True)
    assert arm.parameters is not None and not arm.description.symbols  # the numeric model
    n = plant.n_joints
    for seed in range(4):
        x, u, d = _random_point(plant, 10 + seed)
        xdot = plant.rhs(x, u, d)
        qdd = arm.forward_dynamics(x[:n], x[n:], u + d)
        assert scaled_error(xdot[:n], x[n:]) == 0.0
        assert scaled_error(xdot[n:], qdd) < TOL_EXACT, seed


def test_zoo_overrides_equal_the_numeric_robot_with_the_same_values():
    plant = zoo_plant("planar2r", overrides={"m2": 4.0, "f1": 0.5})
    arm = robot("planar2r", m2=4.0, f1=0.5, friction=True)
    nominal = robot("planar2r", friction=True)
    assert plant.parameter("m2").value == 4.0 and plant.parameter("f1").value == 0.5
    moved = False
    for seed in range(3):
        x, u, d = _random_point(plant, 20 + seed)
        qdd = plant.rhs(x, u, d)[2:]
        assert scaled_error(qdd, arm.forward_dynamics(x[:2], x[2:], u + d)) < TOL_EXACT
        moved |= scaled_error(qdd, nominal.forward_dynamics(x[:2], x[2:], u + d)) > 1e-3
    assert moved, "the overrides must change the dynamics"


def test_zoo_plant_without_friction_and_with_rotor_inertia_follows_the_options():
    for friction, motor_inertia in [(False, False), (True, True)]:
        plant = zoo_plant("puma560", friction=friction, motor_inertia=motor_inertia)
        arm = robot("puma560", friction=friction, motor_inertia=motor_inertia)
        x, u, d = _random_point(plant, 30)
        assert scaled_error(plant.rhs(x, u, d)[6:], arm.forward_dynamics(x[:6], x[6:], u + d)) < TOL_EXACT


def test_urdf_chain_plant_matches_pinocchio_aba():
    """Pinocchio reads the same URDF itself; its ABA ignores joint damping, so the viscous torque
    ``-damping * qd`` (Pinocchio's own ``model.damping``) is applied as a joint torque."""
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(str(PLANAR2R_URDF))
    model.gravity.linear = np.array(URDF_GRAVITY)
    data = model.createData()
    damping = np.array(model.damping, dtype=float)
    assert damping.any(), "the packaged URDF has joint damping"
    plant = _urdf_plant()
    for seed in range(4):
        x, u, d = _random_point(plant, 40 + seed)
        q, qd = x[:2], x[2:]
        config = np.concatenate([[math.cos(v), math.sin(v)] if joint.nq == 2 else [v]
                                 for v, joint in zip(q, model.joints[1:], strict=True)])
        qdd = pin.aba(model, data, config, qd, u + d - damping * qd)
        assert scaled_error(plant.rhs(x, u, d), np.concatenate([qd, qdd])) < TOL_EXACT, seed


def test_dh_and_urdf_chain_plants_equal_the_zoo_robot():
    """The packaged URDF was exported from the planar2r description: all three routes agree."""
    arm = robot("planar2r", friction=True)
    for plant in (_plant("dh_chain"), _urdf_plant()):
        assert plant.parameter_names == ("m1", "f1", "m2", "f2")
        assert scaled_error(plant.parameter_vector, [5.0, 2.0, 3.0, 1.0]) < TOL_EXACT
        x, u, d = _random_point(plant, 50)
        assert scaled_error(plant.rhs(x, u, d)[2:], arm.forward_dynamics(x[:2], x[2:], u + d)) < TOL_EXACT


@pytest.mark.parametrize("params", [ELASTIC_DEFAULTS, ELASTIC_GRAVITY], ids=["mgl0", "mgl3"])
def test_elastic_linearization_at_rest_is_the_robel_state_space(params):
    plant = ElasticJointPlant(params)
    lin = plant.linearize(np.zeros(4), [0.0], [0.0])
    A, B = elastic_state_space(params)
    assert scaled_error(lin.A, A) < TOL_EXACT
    assert scaled_error(lin.B[:, :1], B) < TOL_EXACT
    assert lin.inputs == ("u", "w")


@pytest.mark.parametrize("seed", [0, 1])
def test_frictionless_arm_conserves_mechanical_energy(seed):
    """planar2r with friction off, u = d = 0: kinetic + potential energy is a first integral."""
    plant = zoo_plant("planar2r", friction=False)
    rng = np.random.default_rng(seed)
    x0 = np.concatenate([rng.uniform(-math.pi, math.pi, 2), rng.uniform(-2.0, 2.0, 2)])
    zero = np.zeros(2)
    t = np.linspace(0.0, 3.0, 61)
    sol = solve_ivp(lambda _, x: plant.rhs(x, zero, zero), (0.0, t[-1]), x0, t_eval=t, method="DOP853",
                    rtol=1e-11, atol=1e-12)
    assert sol.success
    q, qd = sol.y[:2].T, sol.y[2:].T
    energy = plant.robot.energy(q, qd, p=plant.parameter_vector)
    total = energy.total
    # the motion is not trivial: energy moves between kinetic and potential
    assert np.ptp(energy.kinetic) > 1.0
    assert np.max(np.abs(total - total[0])) / (1 + abs(total[0])) < TOL_ENERGY


def test_arm_with_friction_only_loses_energy():
    """planar2r with viscous friction, u = d = 0: dE/dt = -qd' F qd <= 0, so E never increases."""
    plant = zoo_plant("planar2r", friction=True)
    x0 = np.array([0.4, -1.0, 1.5, -2.0])
    zero = np.zeros(2)
    t = np.linspace(0.0, 3.0, 61)
    sol = solve_ivp(lambda _, x: plant.rhs(x, zero, zero), (0.0, t[-1]), x0, t_eval=t, method="DOP853",
                    rtol=1e-11, atol=1e-12)
    total = plant.robot.energy(sol.y[:2].T, sol.y[2:].T, p=plant.parameter_vector).total
    assert np.all(np.diff(total) <= TOL_ENERGY * (1 + np.abs(total[:-1])))
    assert total[-1] < total[0] - 1.0
