"""Benchmark: what the sweep kernel's time is made of, by the integrator's tolerance.

Scenario: the sweep benchmark's (``benchmarks/bench_sweep.py``): ``specs/simnog-decentralized-pid.yaml`` with
``simulation.duration: 2.0``, ``m2`` uniform on [2, 4] kg, every requirement scored per sample by the compiled
kernel (``designkit.sweep.kernel``: the Dormand--Prince pair integrates each sample and an observer reduces each of
the 20,001 grid points to the requirements' metrics).  The same batch of samples is run at the default tolerance
(rtol 1e-10, atol 1e-12) and at looser ones (``numerics.rtol``/``atol``), rounds interleaved, best round of each;
reported per tolerance: CPU per sample, right-hand-side evaluations and accepted steps per sample, and the largest
difference of any requirement's margin from the default's; and the least-squares line CPU = fixed + slope x
evaluations through the rows (the fixed part is what no tolerance removes).

The question it answers: would a looser tolerance put 10^6 samples inside the goal of 5 minutes on two cores
(about 0.6 ms of CPU a sample with the engine's overhead)?  The integration shrinks with the tolerance; the grid
points, their dense output and the observer do not.

Run: ``python benchmarks/bench_sweep_tolerance.py [B]`` (default B = 256 samples); writes
``benchmarks/results/sweep_tolerance.json``.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "specs" / "simnog-decentralized-pid.yaml"
LADDER = ((1e-10, 1e-12), (1e-8, 1e-10), (1e-6, 1e-8), (1e-4, 1e-6))


def _text(rtol: float, atol: float) -> str:
    text = SPEC.read_text().replace("duration: 5.0", "duration: 2.0")
    return text + f"numerics: {{rtol: {rtol!r}, atol: {atol!r}}}\n"


def main(b: int = 256, rounds: int = 3) -> dict:
    from designkit.sweep.chunk import _inputs, prepared, run_samples

    load_before = os.getloadavg()
    preps = {}
    for rtol, atol in LADDER:
        prep = prepared(_text(rtol, atol), str(SPEC), b)
        assert prep.kernel is not None, "the default integrator's sweep runs the kernel"
        preps[rtol] = prep
    vals = preps[LADDER[0][0]].space.draw(0, np.arange(b))[0]
    seeds = np.full(b, -1)
    best = {r: np.inf for r in preps}
    margins = {}
    for _ in range(rounds):
        for r, prep in preps.items():
            c0 = time.process_time()
            m, failed = run_samples(prep, vals, seeds)
            best[r] = min(best[r], time.process_time() - c0)
            assert not np.any(failed), f"the integrator failed at rtol {r:g}"
            margins[r] = m
    params = _inputs(preps[LADDER[0][0]], vals, seeds)["parameters"]
    ref = margins[LADDER[0][0]]
    rows = []
    for rtol, atol in LADDER:
        prep = preps[rtol]  # the pair's own counters, one more (untimed) run of the batch
        z0 = np.tile(np.asarray(prep.simulator.z0, dtype=float), (b, 1))
        _, stats = prep.kernel.observed.run(z0, prep.simulator.inputs, prep.kernel.constants, params)
        diff = max(float(np.nanmax(np.abs(margins[rtol].margin[k] - ref.margin[k]))) for k in ref.names)
        rows.append({"rtol": rtol, "atol": atol, "cpu_ms_per_sample": round(1e3 * best[rtol] / b, 3),
                     "evaluations_per_sample": round(float(stats[:, 0].mean()), 1),
                     "accepted_steps_per_sample": round(float(stats[:, 1].mean()), 1),
                     "largest_margin_difference": diff})
    evals = np.array([r["evaluations_per_sample"] for r in rows])
    cpu = np.array([r["cpu_ms_per_sample"] for r in rows])
    slope, fixed = np.polyfit(evals, cpu, 1)  # CPU = fixed + slope * evaluations
    n_grid = preps[LADDER[0][0]].simulator.time.size
    fit = {"us_per_evaluation": round(1e3 * slope, 4), "fixed_ms_per_sample": round(fixed, 4),
           "grid_points": int(n_grid), "fixed_ns_per_grid_point": round(1e6 * fixed / n_grid, 1),
           "largest_residual_ms": round(float(np.max(np.abs(np.polyval([slope, fixed], evals) - cpu))), 4)}
    out = {"benchmark": "bench_sweep_tolerance", "samples_per_batch": b, "rounds": rounds, "rows": rows,
           "linear_fit": fit,
           "floor_ms_per_sample_for_1e6_in_5_min_on_2_cores": round(1e3 * 300 * 2 / 1e6, 3),
           "load_average": {"before": [round(x, 2) for x in load_before],
                            "after": [round(x, 2) for x in os.getloadavg()]}}
    return out


if __name__ == "__main__":
    result = main(int(sys.argv[1]) if len(sys.argv) > 1 else 256)
    print(json.dumps(result, indent=1))
    path = ROOT / "benchmarks" / "results" / "sweep_tolerance.json"
    path.write_text(json.dumps(result, indent=1) + "\n")
