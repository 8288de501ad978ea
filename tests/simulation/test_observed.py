"""Batches of the compiled Dormand-Prince pair with a caller's observer (simulation/observed.py) against the single
run's records (Simulator.run), run by run and to the last bit: the observer sees the grid points the records hold."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.models.codegen import find_compiler
from designkit.pipeline import design, plant
from designkit.schema.loader import parse_spec
from designkit.simulation.observed import observed
from designkit.simulation.run import build
from designkit.simulation.step import layout

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="the observed pair runs compiled only")

SIMNOG = """\
name: simnog-observed
plant: {kind: robot, robot: planar2r}
controller: {kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}
simulation: {duration: 1.0, step: [1.0, -0.5], perturbation: {value: [2.0, 0.0], time: 0.5}}
"""

# The observer keeps, per run, the sum of every observed row over the grid and the rows at grid point K.
OBSERVER = r"""
#define K 1234
typedef struct { double sum[NOBS + 1], at[NOBS + 1]; long seen; } dk_obs;
static void dk_obs_begin(dk_obs *o, const double *s0, const double *W, long N, const double *prm) {
  memset(o, 0, sizeof *o); (void)s0; (void)W; (void)N; (void)prm;
}
static void dk_obs_point(dk_obs *o, long k, const double *y, const double *w) {
  for (int i = 0; i < NOBS; ++i) { o->sum[i] += y[i]; if (k == K) o->at[i] = y[i]; }
  o->seen = k + 1; (void)w;
}
static void dk_obs_end(dk_obs *o, int status, long stop, double *out) {
  for (int i = 0; i < NOBS; ++i) { out[i] = o->sum[i]; out[NOBS + i] = o->at[i]; }
  out[2 * NOBS] = o->seen; out[2 * NOBS + 1] = status; (void)stop;
}
"""


class _NoElement:
    n_memory = 0


@pytest.fixture(scope="module")
def simulator():
    loaded = parse_spec(SIMNOG)
    p = plant(loaded)
    sim = build(loaded.spec, design(loaded, p), plant=p)
    assert sim.dopri5 is not None
    return sim


@pytest.mark.parametrize("from_state", [True, False], ids=["state rows", "computed rows"])
def test_observed_runs_are_the_single_runs(simulator, from_state):
    sim = simulator
    L = layout(sim.plant, sim.law, _NoElement, 0)
    cuts = np.cumsum([0, *L.record_sizes])
    # positions (read from the integrated state), or the commands (computed by the generated output function)
    rows = [int(cuts[0]) + k for k in sim.plant.positions] if from_state else list(range(int(cuts[2]), int(cuts[3])))
    nobs = len(rows)
    runner = observed(sim.dopri5, rows, OBSERVER, 2 * nobs + 2, L.np_)
    assert not isinstance(runner, str), runner
    names = [q.name for q in sim.plant.parameters]
    base = np.asarray(sim.plant.parameter_vector, dtype=float)
    P = np.tile(base, (3, 1))
    P[1, names.index("m2")] = 4.0
    P[2, names.index("m2")] = 2.0
    out, stats = runner.run(np.tile(sim.z0, (3, 1)), sim.inputs, np.zeros(1), P)
    for i in range(3):
        rec = sim.run(parameters={"m2": float(P[i, names.index("m2")])} if i else None)
        ref = rec.state[:, list(sim.plant.positions)] if from_state else rec.u_command
        assert out[i, 2 * nobs] == sim.time.size and out[i, 2 * nobs + 1] == 0
        assert np.array_equal(out[i, nobs:2 * nobs], ref[1234]), i
        # summed in grid order, as the observer does
        acc = np.zeros(nobs)
        for k in range(ref.shape[0]):
            acc += ref[k]
        assert np.array_equal(out[i, :nobs], acc), i
    assert stats[1, 0] > 0 and not np.array_equal(out[1], out[2])  # another plant, another run
