"""Benchmark: ``designkit sweep`` of the SIMNOG decentralized PID, 2 s per sample, the default integrator.

Scenario: ``specs/simnog-decentralized-pid.yaml`` with ``simulation.duration: 2.0`` (the issue's "2 s each"),
``m2`` uniform on [2, 4] kg, every requirement of the spec scored per sample.  Measured in one run, on this
machine under whatever load it carries (stated in the output: the load average before and after):

(a) the in-process batched run (``engine="process"``: the same chunks, the same batched compiled loop, no
    Dask) -- the alternative a user would pick on one core;
(b) Dask LocalCluster, 1 worker, the same samples;  (a)/(b) per core is the engine's overhead (goal <= 1.3),
    measured twice: cold (starting the cluster, each worker designing and building the loop) and warm (the
    same client after a small sweep of the same spec: the per-sample overhead of tasks, transfers and files);
(c) Dask LocalCluster, 2 workers, cold and warm;  (b)/(c) the speed-up from 1 to 2 workers;
(d) the time for 10^6 samples extrapolated from (c) (not run: said so), against the 5-minute goal;
(e) peak memory: the resident set of the process engine's run (one process does everything) at N and 2 N,
    showing it is set by the chunk, not by N (the per-sample table, 10 numbers a sample, aside);
(f) with ``numerics.integrator: rk4``: the batched mapped step against a loop of single runs
    (``Simulator.run(parameters=...)``), per sample.

Every sweep's per-sample table is checked identical across (a), (b), (c) before any figure is reported.

Run: ``python benchmarks/bench_sweep.py [N]`` (default N = 1000); writes ``benchmarks/results/sweep.json``.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "specs" / "simnog-decentralized-pid.yaml"


def _spec(folder: Path, rk4: bool = False) -> Path:
    text = SPEC.read_text().replace("duration: 5.0", "duration: 2.0")
    if rk4:
        text += "numerics: {integrator: rk4}\n"
    path = folder / ("simnog-rk4.yaml" if rk4 else "simnog-2s.yaml")
    path.write_text(text)
    return path


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _same(a, b) -> bool:
    return all(np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True)
               for f in ("index", "values", "achieved", "margin", "passed"))


def _peak_rss_of_process_run(spec: Path, n: int) -> float:
    """Peak resident set (MB) of a fresh process running the in-process sweep of ``n`` samples."""
    code = ("import resource, sys; from designkit.sweep.api import sweep; "
            f"sweep({str(spec)!r}, {n}, engine='process', falsification=False); "
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return int(out.stdout.strip().splitlines()[-1]) / 1024.0


def main(n: int = 1000) -> dict:
    from designkit.sweep.api import sweep
    from designkit.sweep.chunk import prepared

    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = _spec(folder)
        sweep(spec, 8, engine="process", falsification=False)  # warm: compile caches
        a, t_a = _timed(lambda: sweep(spec, n, engine="process", falsification=False))
        b, t_b = _timed(lambda: sweep(spec, n, workers=1, falsification=False))
        c, t_c = _timed(lambda: sweep(spec, n, workers=2, falsification=False))
        assert _same(a, b) and _same(a, c), "the per-sample tables differ between engines"
        warm = {}
        for k in (1, 2):
            from designkit.sweep.engine import connect

            client, cluster = connect(None, k)
            try:
                sweep(spec, 4 * k, client=client, chunk=2, falsification=False)  # every worker builds its loop
                w, warm[k] = _timed(lambda c=client: sweep(spec, n, client=c, falsification=False))
                assert _same(a, w)
            finally:
                client.close()
                cluster.close()
        rss_n = _peak_rss_of_process_run(spec, n // 2)
        rss_2n = _peak_rss_of_process_run(spec, n)
        rk4 = _spec(folder, rk4=True)
        text = rk4.read_text()
        prep = prepared(text, str(rk4), 64)
        vals = prep.space.draw(0, np.arange(64))[0]
        from designkit.sweep.chunk import run_samples

        run_samples(prep, vals, np.full(64, -1))
        _, t_batch = _timed(lambda: run_samples(prep, vals, np.full(64, -1)))
        _, t_loop = _timed(lambda: [prep.simulator.run(parameters={"m2": float(v)}) for v in vals[:16, 0]])
    load_after = os.getloadavg()
    rate_a, rate_b, rate_c = n / t_a, n / t_b, n / t_c
    million = 1e6 / rate_c
    out = {
        "scenario": "SIMNOG decentralized PID, 2 s per sample, m2 uniform on [2, 4] kg, default integrator: "
                    + str(a.engine["integrator"]),
        "samples": n,
        "steps_per_run": a.engine["steps_per_run"],
        "in_process_batched_s": round(t_a, 3),
        "dask_1_worker_s": round(t_b, 3),
        "dask_2_workers_s": round(t_c, 3),
        "samples_per_s": {"in_process": round(rate_a, 1), "dask_1": round(rate_b, 1), "dask_2": round(rate_c, 1)},
        "engine_overhead_per_core_cold": round(rate_a / rate_b, 3),
        "engine_overhead_per_core_warm": round(warm[1] / t_a, 3),
        "dask_warm_s": {"1_worker": round(warm[1], 3), "2_workers": round(warm[2], 3)},
        "speedup_1_to_2_workers_warm": round(warm[1] / warm[2], 3),
        "engine_overhead_goal": 1.3,
        "speedup_1_to_2_workers_cold": round(rate_c / rate_b, 3),
        "extrapolated_1e6_samples_s": round(million, 1),
        "extrapolated_1e6_samples_s_warm": round(1e6 * warm[2] / n, 1),
        "goal_1e6_s": 300.0,
        "goal_met": million < 300.0,
        "extrapolated": "10^6 samples were not run: the figures are 10^6 / (2-worker rate) from this run",
        "peak_rss_mb": {f"process engine, {n // 2} samples": round(rss_n, 1),
                        f"process engine, {n} samples": round(rss_2n, 1)},
        "rk4_batched_vs_single_runs_per_sample": round((t_loop / 16) / (t_batch / 64), 3),
        "rk4_us_per_sample_batched": round(1e6 * t_batch / 64, 1),
        "rk4_us_per_sample_single": round(1e6 * t_loop / 16, 1),
        "identical_tables": True,
        "load_average_before_after": [round(load_before[0], 2), round(load_after[0], 2)],
        "cores": os.cpu_count(),
        "peak_rss_this_process_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1),
    }
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    (ROOT / "benchmarks" / "results" / "sweep.json").write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000)
