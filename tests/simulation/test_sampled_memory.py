"""A law with discrete memory that declares its sampling period (the core extension for sampled laws):
the simulation samples it at its period, holds the command between samples, orders a sample as
measure -> update -> command, and refuses a conflicting ``simulation.sampling_period``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from designkit.errors import SpecError
from designkit.models.link import LinkPlant
from designkit.simulation.run import build
from designkit.synthesis.law import Memory, dynamic_law
from tests.simulation.helpers import design_of, make_spec

KM, TAU, TS, K = 2.0, 0.5, 0.02, 3.0


def _integrating_law(period: float | None = TS):
    """``i(k) = i(k-1) + Ts (xD - y(k))``, ``u(k) = K i(k)``: the command reads the memory *after* the update."""
    return dynamic_law("demo_sampled", LinkPlant(Km=KM, tau=TAU), sampling_period=period,
                       sampling_period_source="controller.sampling_period",
                       memory=[Memory("i", lambda s: s.memory("i") + TS * (s.qD[0] - s.q[0]), unit="rad*s")],
                       command=lambda s: K * s.memory("i"))


def _numpy_loop(n_samples: int, xD: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The same loop on the exact ZOH model computed here (scipy expm of the augmented matrix)."""
    F = np.array([[0.0, 1.0], [0.0, -1.0 / TAU]])
    b = np.array([[0.0], [KM / TAU]])
    M = expm(np.block([[F, b], [np.zeros((1, 3))]]) * TS)
    A, B = M[:2, :2], M[:2, 2]
    x, i, us, xs = np.zeros(2), 0.0, [], []
    for _ in range(n_samples):
        xs.append(x.copy())
        i = i + TS * (xD - x[0])
        u = K * i
        us.append(u)
        x = A @ x + B * u
    return np.asarray(us), np.asarray(xs)


def test_declared_period_samples_the_law_and_matches_the_exact_sampled_loop():
    spec = make_spec(duration=2.0, dt=0.005)
    design = design_of(spec)
    res = build(spec, design, law=_integrating_law()).run()
    assert res.settings["sampling_period"] == TS and res.settings["steps_per_sample"] == 4
    assert res.settings["sampling_period_source"] == "controller.sampling_period"
    u = np.asarray(res.u_command)[:, 0]
    # held between samples: constant over each block of four steps
    blocks = u[: 4 * (len(u) // 4)].reshape(-1, 4)
    assert np.max(np.ptp(blocks, axis=1)) == 0.0
    n = len(blocks)
    u_ref, x_ref = _numpy_loop(n)
    np.testing.assert_allclose(blocks[:, 0], u_ref, rtol=1e-8, atol=1e-10)  # the first sample already updated
    np.testing.assert_allclose(res.state[::4][:n], x_ref, rtol=1e-6, atol=1e-9)  # RK4 inside the hold


def test_the_first_command_reads_the_updated_memory():
    spec = make_spec(duration=0.5, dt=0.005)
    res = build(spec, design_of(spec), law=_integrating_law()).run()
    assert float(res.u_command[0, 0]) == pytest.approx(K * TS * 1.0)  # i(0) = Ts (xD - 0), not the initial 0


def test_a_conflicting_simulation_sampling_period_is_refused_naming_both():
    spec = make_spec(duration=0.5, dt=0.005, sampling_period=0.01)
    with pytest.raises(SpecError) as err:
        build(spec, design_of(spec), law=_integrating_law())
    assert err.value.path == "simulation.sampling_period"
    assert "controller.sampling_period" in err.value.message and "0.02" in err.value.message


def test_the_same_sampling_period_is_accepted_and_a_continuous_law_keeps_the_spec_period():
    spec = make_spec(duration=0.5, dt=0.005, sampling_period=TS)
    assert build(spec, design_of(spec), law=_integrating_law()).run().settings["steps_per_sample"] == 4
    spec = make_spec(duration=0.5, dt=0.005, sampling_period=0.01)
    res = build(spec, design_of(spec), law=_integrating_law(period=None)).run()
    assert res.settings["steps_per_sample"] == 2


def test_a_user_step_must_divide_the_declared_period():
    spec = make_spec(duration=0.5, dt=0.003)
    with pytest.raises(SpecError) as err:
        build(spec, design_of(spec), law=_integrating_law())
    assert err.value.path == "simulation.dt" and "controller.sampling_period" in err.value.message
