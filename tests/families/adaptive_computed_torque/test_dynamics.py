"""The law's model: D^ and h^ built from the regressor equal the arm's inverse dynamics at the true parameters
(against Pinocchio's CRBA and RNEA, and the model layer's own mass matrix), and the update law's sign: the
derivative of V along the closed loop, by finite differences of the law's and the plant's functions, is
-sum 2 K1 e^2 + 2 (psi K2 - 1) e'^2 at random states."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.adaptive_computed_torque.laws import (
    Adaptation,
    adaptive_law,
    estimated_dynamics,
    fixed_law,
    true_parameters,
)
from designkit.models.robot_plant import zoo_plant
from designkit.models.robots import robot
from tests.models.support import pinocchio_model


def _states(n: int, count: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(-2, 2, (count, n)), rng.uniform(-2, 2, (count, n)), rng.uniform(-5, 5, (count, n))


@pytest.mark.parametrize("name", ["planar2r", "puma560"])
def test_regressor_model_at_the_true_parameters_is_pinocchio(name):
    pin = pytest.importorskip("pinocchio")
    plant = zoo_plant(name, motor_inertia=name == "puma560")
    arm = robot(name)  # numeric description, no friction: Pinocchio's model
    model, _ = pinocchio_model(arm.description)
    data = model.createData()
    names = ("m2",)
    values = [true_parameters(plant)[list(plant.robot.parameter_names).index("m2")]]
    f = estimated_dynamics(plant, names, values)
    P = true_parameters(plant)
    pn = list(plant.robot.parameter_names)
    fv = np.array([P[pn.index(f"fv{j + 1}")] for j in range(plant.n_joints)])
    fc = np.array([P[pn.index(f"fc{j + 1}")] for j in range(plant.n_joints)])
    Ia = np.array([P[pn.index(f"Ia{j + 1}")] for j in range(plant.n_joints)]) if plant.robot.motor_inertia else 0.0
    q, qd, v = _states(plant.n_joints, 8, 3)
    for k in range(len(q)):
        D, h, tau = (np.asarray(x, dtype=float) for x in f(q[k], qd[k], v[k]))
        D_pin = pin.crba(model, data, q[k])
        D_pin = np.triu(D_pin) + np.triu(D_pin, 1).T + np.diag(np.broadcast_to(Ia, (plant.n_joints,)))
        h_pin = pin.rnea(model, data, q[k], qd[k], np.zeros(plant.n_joints)) + fv * qd[k] + fc * np.sign(qd[k])
        scale = 1.0 + np.max(np.abs(D_pin))
        np.testing.assert_allclose(D, D_pin, atol=1e-9 * scale)
        np.testing.assert_allclose(h.ravel(), h_pin, atol=1e-9 * (1 + np.max(np.abs(h_pin))))
        np.testing.assert_allclose(tau.ravel(), D_pin @ v[k] + h_pin, atol=1e-8 * (1 + np.max(np.abs(h_pin))))


def test_estimated_inertia_is_the_models_mass_matrix_at_other_masses():
    """At m2 = 4 kg the regressor model is the planar arm's model with the 10 inertial parameters of link 2 as the
    model layer computes them -- here only the mass entry changes, so D^ - D = dD/dm2 (m2^ - m2), affine."""
    plant = zoo_plant("planar2r")
    q = np.array([0.3, -0.7])
    D3 = np.asarray(estimated_dynamics(plant, ("m2",), [3.0])(q, [0, 0], [0, 0])[0])
    D4 = np.asarray(estimated_dynamics(plant, ("m2",), [4.0])(q, [0, 0], [0, 0])[0])
    D5 = np.asarray(estimated_dynamics(plant, ("m2",), [5.0])(q, [0, 0], [0, 0])[0])
    np.testing.assert_allclose(D3, plant.robot.mass_matrix(q, p=plant.model_parameters()), atol=1e-12)
    np.testing.assert_allclose(D5 - D4, D4 - D3, atol=1e-12)
    # the mass m2 at the link-2 frame origin (the elbow's far end, a1 + a2 cos q2 ... from the base): with the
    # first moment and inertia held, dD11/dm2 = |origin of frame 2|^2 = a1^2 + a2^2 + 2 a1 a2 cos q2
    a1, a2 = 0.5, 0.4
    assert D4[0, 0] - D3[0, 0] == pytest.approx(a1**2 + a2**2 + 2 * a1 * a2 * np.cos(q[1]), rel=1e-12)


def test_fixed_law_at_the_true_parameters_is_the_models_inverse_dynamics():
    plant = zoo_plant("planar2r")
    law = fixed_law(plant, ("m1", "m2"), [5.0, 3.0], [100.0, 100.0], [20.0, 20.0])
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qd, r = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 6)
        u = np.asarray(law.command(np.concatenate([q, qd]), [], [], r), dtype=float).ravel()
        a = r[4:6] + 100 * (r[0:2] - q) + 20 * (r[2:4] - qd)
        np.testing.assert_allclose(u, plant.robot.inverse_dynamics(q, qd, a, p=plant.model_parameters()), atol=1e-10)


@pytest.mark.parametrize("seed", range(4))
def test_update_law_makes_v_decrease_as_the_proof_says(seed):
    """dV/dt along the closed loop (central differences of V along the field z' = f(z)) is -x'Q1x: the update's
    sign (e = qD - q, P^' = + K W' D^-1 e1) is the one that cancels the cross term."""
    plant = zoo_plant("planar2r")
    a = Adaptation(names=("m1", "m2"), initial=(7.0, 4.5), gain=(2.0, 3.0), K1=(100.0, 80.0), K2=(20.0, 25.0),
                   psi=(0.1, 0.08))
    law = adaptive_law(plant, a)
    rng = np.random.default_rng(seed)
    y = np.concatenate([rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)])
    xc = rng.uniform([4.5, 2.7], [8.0, 5.0])
    # a reference frozen in time is a valid input at one instant: qD, qD', qD'' with qD'' the derivative of qD'
    r = rng.uniform(-1, 1, 6)
    ode = plant.ode()

    def field(z: np.ndarray, t: float) -> np.ndarray:
        rr = r.copy()
        rr[0:2] = r[0:2] + r[2:4] * t + 0.5 * r[4:6] * t * t  # qD(t) of constant acceleration
        rr[2:4] = r[2:4] + r[4:6] * t
        u = np.asarray(law.command(z[:4], z[4:], [], rr)).ravel()
        xdot = np.asarray(ode(z[:4], u, np.zeros(2), plant.model_parameters())).ravel()
        cdot = np.asarray(law.derivative(z[:4], z[4:], [], rr, np.ones(2))).ravel()
        return np.concatenate([xdot, cdot]), rr

    def V(z: np.ndarray, t: float) -> float:
        _, rr = field(z, t)
        return float(np.asarray(law.signals(z[:4], z[4:], [], rr)).ravel()[0])

    z = np.concatenate([y, xc])
    dz, rr = field(z, 0.0)
    h = 1e-6
    dV = (V(z + h * dz, h) - V(z - h * dz, -h)) / (2 * h)
    e, ed = rr[0:2] - y[0:2], rr[2:4] - y[2:4]
    K1, K2, psi = np.array(a.K1), np.array(a.K2), np.array(a.psi)
    expected = -np.sum(2 * K1 * e**2 + 2 * (psi * K2 - 1) * ed**2)
    assert dV == pytest.approx(expected, rel=1e-5, abs=1e-6)
    assert expected < 0
