"""The Slotine--Li scheme: its Coriolis matrix is the model layer's (Christoffel) one at the true parameters, with
D' - 2C skew-symmetric; V' = -s' KD s along the closed loop (finite differences); the example converges."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.adaptive_computed_torque.laws import (
    Adaptation,
    _torque_of_parameters,
    adaptive_law,
    estimates,
    true_parameters,
)
from designkit.families.adaptive_computed_torque.slotine_li import christoffel_torque
from designkit.models.robot_plant import zoo_plant


@pytest.mark.parametrize("name", ["planar2r", "puma560"])
def test_coriolis_is_the_models_christoffel_matrix(name):
    plant = zoo_plant(name)
    n, p = plant.n_joints, plant.model_parameters()
    P = true_parameters(plant)
    Y = christoffel_torque(_torque_of_parameters(plant), n, len(P))
    rng = np.random.default_rng(1)
    for _ in range(4):
        q, qd, v = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
        zero = np.zeros(n)
        # Y(q, qd, v, 0) - Y(q, qd, 0, 0) = C(q, qd) v  (Y is affine in v)
        Cv = np.asarray(Y(q, qd, v, zero, P) - Y(q, qd, zero, zero, P)).ravel()
        C = np.asarray(plant.robot.coriolis_matrix(q, qd, p=p))
        np.testing.assert_allclose(Cv, C @ v, atol=1e-9 * (1 + np.abs(C).max()))
        # D' - 2C skew: finite-difference D' along qd, with the model's own mass matrix
        h = 1e-6
        Ddot = (np.asarray(plant.robot.mass_matrix(q + h * qd, p=p)) - np.asarray(plant.robot.mass_matrix(
            q - h * qd, p=p))) / (2 * h)
        N = Ddot - 2 * C
        np.testing.assert_allclose(N + N.T, 0.0, atol=1e-6 * (1 + np.abs(Ddot).max()))
        # at qd' = qd, qd'' = a: Y P is the inverse dynamics
        a = rng.uniform(-1, 1, n)
        np.testing.assert_allclose(np.asarray(Y(q, qd, qd, a, P)).ravel(),
                                   plant.robot.inverse_dynamics(q, qd, a, p=p), atol=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_v_decreases_as_minus_s_kd_s(seed):
    plant = zoo_plant("planar2r")
    a = Adaptation(names=("m1", "m2"), initial=(7.0, 4.5), gain=(2.0, 3.0), K1=(), K2=(), psi=(),
                   scheme="slotine_li", Lambda=(10.0, 8.0), KD=(5.0, 1.0))
    law = adaptive_law(plant, a)
    ode = plant.ode()
    rng = np.random.default_rng(seed)
    y = rng.uniform(-1, 1, 4)
    xc = rng.uniform([4.5, 2.7], [8.0, 5.0])
    r = rng.uniform(-1, 1, 6)

    def at(t: float) -> np.ndarray:
        rr = r.copy()
        rr[0:2] = r[0:2] + r[2:4] * t + 0.5 * r[4:6] * t * t
        rr[2:4] = r[2:4] + r[4:6] * t
        return rr

    def field(z: np.ndarray, t: float) -> np.ndarray:
        u = np.asarray(law.command(z[:4], z[4:], [], at(t))).ravel()
        return np.concatenate([np.asarray(ode(z[:4], u, np.zeros(2), plant.model_parameters())).ravel(),
                               np.asarray(law.derivative(z[:4], z[4:], [], at(t), np.ones(2))).ravel()])

    def V(z: np.ndarray, t: float) -> float:
        return float(np.asarray(law.signals(z[:4], z[4:], [], at(t))).ravel()[0])

    z = np.concatenate([y, xc])
    dz = field(z, 0.0)
    h = 1e-6
    dV = (V(z + h * dz, h) - V(z - h * dz, -h)) / (2 * h)
    e, ed = r[0:2] - y[0:2], r[2:4] - y[2:4]
    s = ed + np.array(a.Lambda) * e
    assert dV == pytest.approx(-np.sum(np.array(a.KD) * s * s), rel=1e-5, abs=1e-7)


def test_slotine_li_example_converges_without_acceleration_or_spr():
    from designkit.pipeline import run
    from designkit.schema.loader import load_spec
    from tests.families.adaptive_computed_torque.conftest import SPECS

    result = run(load_spec(SPECS / "adaptive-ct-simnog-slotine-li.yaml"))
    names = {c.name for c in result.checks}
    assert "spr_certificate" not in names  # no SPR filter in this scheme
    sim = result.simulation
    np.testing.assert_allclose(estimates(sim, ("m1", "m2"))[-1], [5.0, 3.0], rtol=1e-6)
    V = np.asarray(sim.signals["V"])
    assert np.all(np.diff(V) <= 1e-9 * V[0]) and V[-1] < 1e-9 * V[0]
    assert not any(name.startswith("vf") for name in sim.controller_state_names)
    assert result.verified
