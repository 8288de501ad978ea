"""The batched closed loop (simulation/batch.py) against the single run, sample by sample: the step mapped over
samples and rolled over time gives each sample's single run to the last bit, whatever the batch it ran in."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.pipeline import design, plant
from designkit.schema.loader import parse_spec
from designkit.simulation.batch import batch_simulator, noise_rows
from designkit.simulation.run import build

SIMNOG = """\
name: simnog-batch
plant: {kind: robot, robot: planar2r}
controller: {kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}
simulation: {duration: 0.5, step: [1.0, -0.5], noise: {std: 0.001, seed: 4}}
numerics: {integrator: rk4}
"""

SATURATED_LINK = """\
name: link-batch
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
simulation: {duration: 1.0, nonlinearity: {kind: saturation, limit: 20}}
numerics: {integrator: rk4}
"""


def _simulator(text):
    loaded = parse_spec(text)
    p = plant(loaded)
    return build(loaded.spec, design(loaded, p), plant=p), p


@pytest.mark.parametrize(("text", "name", "values"), [(SIMNOG, "m2", [2.0, 3.3, 4.1]),
                                                       (SATURATED_LINK, "Km", [1.0, 2.0, 3.5, 0.7])])
def test_every_sample_is_its_single_run_to_the_last_bit(text, name, values):
    sim, p = _simulator(text)
    k = [q.name for q in p.parameters].index(name)
    P = np.tile(p.parameter_vector, (len(values), 1))
    P[:, k] = values
    for batch in (len(values), 8):
        rec = batch_simulator(sim, batch).run(P)
        for i, v in enumerate(values):
            single = sim.run(parameters={name: v})
            q = single.state[:, list(p.positions)]
            assert np.array_equal(rec.tracked[i], q)
            assert np.array_equal(rec.u_command[i], single.u_command.reshape(q.shape[0], -1))
            assert np.array_equal(rec.u_applied[i], single.u_applied.reshape(q.shape[0], -1))


def test_per_sample_noise_is_the_single_run_of_that_seed():
    sim, p = _simulator(SIMNOG)
    std = np.full(len(p.states), 0.001)
    noise = np.stack([noise_rows(std, s, sim.time.size) for s in (4, 9)])
    rec = batch_simulator(sim, 2).run(np.tile(p.parameter_vector, (2, 1)), noise=noise)
    assert np.array_equal(rec.tracked[0], sim.run().state[:, :2])  # seed 4 is the spec's own
    other, _ = _simulator(SIMNOG.replace("seed: 4", "seed: 9"))
    assert np.array_equal(rec.tracked[1], other.run().state[:, :2])


def test_a_batch_holds_at_most_its_size():
    sim, p = _simulator(SATURATED_LINK)
    with pytest.raises(ValueError, match="1 to 2"):
        batch_simulator(sim, 2).run(np.tile(p.parameter_vector, (3, 1)))


def test_the_default_integrator_s_runs_are_its_single_runs():
    """Without ``numerics.integrator`` (the compiled adaptive pair where the simulator has one, else RK4): each
    run of the batch is the simulator's own run of that sample, and a batch's buffer carries nothing over."""
    sim, p = _simulator(SIMNOG.replace("numerics: {integrator: rk4}\n", "").replace(
        ", noise: {std: 0.001, seed: 4}", ""))
    k = [q.name for q in p.parameters].index("m2")
    P = np.tile(p.parameter_vector, (3, 1))
    P[:, k] = [4.0, 2.0, 3.1]
    rec = batch_simulator(sim, 3).run(P)
    for i, v in enumerate(P[:, k]):
        single = sim.run(parameters={"m2": float(v)})
        assert np.array_equal(rec.tracked[i], single.state[:, :2], equal_nan=True)
        assert np.array_equal(rec.u_command[i], single.u_command.reshape(-1, 2), equal_nan=True)


class _Adaptive:
    """A simulator seen through the adaptive interface (``dopri5.run(z0, inputs, failure)``), each run a plain
    single run of the same inputs: the one-by-one path of the batch, whichever integrator the machine has."""

    def __init__(self, sim):
        self._sim = sim
        self.dopri5 = self

    def __getattr__(self, name):
        return getattr(self._sim, name)

    def run(self, z0, inputs, failure=None):
        from designkit.simulation.integrate import run_steps

        assert inputs.T.flags.c_contiguous  # the integrator reads the buffer without copying it
        return run_steps(self._sim.step, z0, np.array(inputs), failure=failure)


def test_the_one_by_one_path_gives_each_sample_its_own_inputs():
    sim, p = _simulator(SIMNOG)
    k = [q.name for q in p.parameters].index("m2")
    P = np.tile(p.parameter_vector, (3, 1))
    P[:, k] = [4.0, 2.0, 3.1]
    std = np.full(len(p.states), 0.001)
    noise = np.stack([noise_rows(std, s, sim.time.size) for s in (4, 4, 4)])
    rec = batch_simulator(_Adaptive(sim), 3).run(P, noise=noise)
    for i, v in enumerate(P[:, k]):
        assert np.array_equal(rec.tracked[i], sim.run(parameters={"m2": float(v)}).state[:, :2])
