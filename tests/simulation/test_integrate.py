"""Plant integration: the free link's speed decays as exp(-t/tau); the chunked runner is exact."""

from __future__ import annotations

import casadi as ca
import numpy as np

from designkit.models.link import LinkPlant, link_ode
from designkit.simulation.integrate import plant_step, rk4, run_steps
from tests.simulation.helpers import scaled_error


def test_free_plant_speed_decays_as_exp_minus_t_over_tau():
    plant, dt, n = LinkPlant(Km=2.0, tau=0.5), 0.005, 400
    step = plant_step(plant, dt)
    x = np.array([0.0, 1.0])
    speeds, positions = [x[1]], [x[0]]
    for _ in range(n):
        x = np.asarray(step(x, [0.0], [0.0])).ravel()
        speeds.append(x[1])
        positions.append(x[0])
    t = dt * np.arange(n + 1)
    # RK4 local error of exp(-dt/tau) is (dt/tau)^5/120 ~ 8e-13 per step.
    assert scaled_error(np.array(speeds), np.exp(-t / plant.tau)) < 1e-9
    # Position = integral of the speed: tau (1 - exp(-t/tau)); no energy is created.
    assert scaled_error(np.array(positions), plant.tau * (1 - np.exp(-t / plant.tau))) < 1e-9
    assert np.all(np.diff(np.abs(speeds)) < 0)


def test_constant_input_reaches_the_speed_Km_u():
    plant = LinkPlant(Km=2.0, tau=0.5)
    step = plant_step(plant, 0.01)
    x = np.zeros(2)
    for _ in range(1000):  # 10 s = 20 tau
        x = np.asarray(step(x, [1.5], [0.5])).ravel()
    assert abs(x[1] - plant.Km * 2.0) < 1e-8


def test_rk4_is_fourth_order_on_a_time_varying_ode():
    # s' = cos(t) s, s(0) = 1 -> s = exp(sin t)
    def integrate(dt):
        s, t = 1.0, 0.0
        for _ in range(round(1.0 / dt)):
            s = rk4(lambda s, a: np.cos(a) * s, s, dt, (t, t + dt / 2, t + dt))
            t += dt
        return abs(s - np.exp(np.sin(1.0)))

    ratio = integrate(0.05) / integrate(0.025)
    assert 13.0 < ratio < 19.0


def test_chunked_runner_equals_a_plain_mapaccum():
    ode = link_ode(LinkPlant(Km=1.0, tau=0.3))
    z, w = ca.SX.sym("z", 2), ca.SX.sym("w", 2)
    z_next = rk4(lambda s, a: ode(s, a, w[1]), z, 0.01, (w[0], w[0], w[0]))
    step = ca.Function("toy", [z, w], [z_next, ca.vertcat(z, w[0])], ["z", "w"], ["z_next", "record"])
    rng = np.random.default_rng(3)
    inputs = rng.normal(size=(2, 1003))
    z0 = np.array([0.1, -0.2])
    expected_z, expected_rec = step.mapaccum("plain", inputs.shape[1])(z0, inputs)
    for chunk in (1, 7, 256, 5000):
        records = run_steps(step, z0, inputs, chunk=chunk)
        np.testing.assert_allclose(records, np.asarray(expected_rec), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(records[:2, 1:], np.asarray(expected_z)[:, :-1], rtol=1e-13, atol=1e-13)
