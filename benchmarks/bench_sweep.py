"""Benchmark: ``designkit sweep`` of the SIMNOG decentralized PID, 2 s per sample, the default integrator.

Scenario: ``specs/simnog-decentralized-pid.yaml`` with ``simulation.duration: 2.0`` (2 s each),
``m2`` uniform on [2, 4] kg, every requirement of the spec scored per sample.  Measured in one run, on this
machine under whatever load it carries (stated in the output: the load average before and after):

(a) the in-process batched run (``engine="process"``: the same chunks, the same batched compiled loop, no
    Dask) -- the alternative a user would pick on one core;
(b) Dask LocalCluster, 1 worker, the same samples, on a warm client (after a small sweep of the same spec, so
    each worker has built its loop; the start-up is reported apart);
(c) Dask LocalCluster, 2 workers, the same way;  the engine's overhead per core is the CPU seconds of (b) and
    (c) (every worker process and this one) over those of (a) (goal <= 1.3): CPU time, because on a machine
    shared with other work the wall time measures the other work too; the speed-up from 1 to 2 workers is
    the wall-time ratio (b)/(c), which needs two idle cores to show;
(d) the time for 10^6 samples extrapolated from (c) (not run: said so), against the 5-minute goal;
(e) peak memory: the resident set of the process engine's run (one process does everything) at N and 2 N,
    showing it is set by the chunk, not by N (the per-sample table, 10 numbers a sample, aside);
(f) with ``numerics.integrator: rk4``: the batched mapped step against a loop of single runs
    (``Simulator.run(parameters=...)``), per sample;
(g) with the default integrator: a batch scored by the compiled kernel (``designkit.sweep.kernel``: the metrics
    reduced inside the integrator) against the records path (each run's records, then NumPy), CPU per sample.

Every sweep's per-sample table is checked identical across (a), (b), (c) before any figure is reported.

Run: ``python benchmarks/bench_sweep.py [N]`` (default N = 1000); writes ``benchmarks/results/sweep.json``.
"""

from __future__ import annotations

import json
import os
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


def _worker_cpu(client) -> float:
    """CPU seconds (user + system) used so far by every worker process of ``client``."""
    import psutil

    def cpu() -> float:
        t = psutil.Process().cpu_times()
        return t.user + t.system

    return float(sum(client.run(cpu).values()))


def _dask_run(spec: Path, n: int, workers: int, reference) -> dict:
    """A warm sweep on a LocalCluster of ``workers``: wall time and CPU seconds (workers and this process)."""
    from designkit.sweep.api import sweep
    from designkit.sweep.engine import connect

    cold_start = time.perf_counter()
    client, cluster = connect(None, workers)
    try:
        sweep(spec, 4 * workers, client=client, chunk=2, falsification=False)  # every worker builds its loop
        cold = time.perf_counter() - cold_start
        cpu0, own0 = _worker_cpu(client), time.process_time()
        res, wall = _timed(lambda: sweep(spec, n, client=client, falsification=False))
        cpu = _worker_cpu(client) - cpu0 + time.process_time() - own0
        assert _same(reference, res), "the per-sample tables differ between engines"
    finally:
        client.close()
        cluster.close()
    return {"wall_s": round(wall, 3), "cpu_s": round(cpu, 3), "startup_s": round(cold, 3)}


def _kernel_against_records(spec: Path, b: int = 64, rounds: int = 3) -> dict:
    """CPU per sample of one batch scored by the compiled kernel (metrics reduced inside the integrator) and by the
    records path (each run's records, then the NumPy metrics), the same samples, interleaved rounds, best of each."""
    import dataclasses

    from designkit.sweep.chunk import prepared, run_samples

    prep = prepared(spec.read_text(), str(spec), b)
    assert prep.kernel is not None, "the default integrator's sweep runs the kernel"
    slow = dataclasses.replace(prep, kernel=None)
    vals = prep.space.draw(0, np.arange(b))[0]
    seeds = np.full(b, -1)
    best = {"kernel": np.inf, "records": np.inf}
    for _ in range(rounds):
        for name, p in (("kernel", prep), ("records", slow)):
            c0 = time.process_time()
            run_samples(p, vals, seeds)
            best[name] = min(best[name], time.process_time() - c0)
    return {"kernel": round(1e3 * best["kernel"] / b, 3), "records": round(1e3 * best["records"] / b, 3),
            "records_over_kernel": round(best["records"] / best["kernel"], 2)}


def main(n: int = 1000) -> dict:
    from designkit.sweep.api import sweep
    from designkit.sweep.chunk import prepared, run_samples

    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = _spec(folder)
        sweep(spec, 8, engine="process", falsification=False)  # warm: compile caches
        cpu0 = time.process_time()
        a, t_a = _timed(lambda: sweep(spec, n, engine="process", falsification=False))
        cpu_a = time.process_time() - cpu0
        one = _dask_run(spec, n, 1, a)
        two = _dask_run(spec, n, 2, a)
        rss_n = _peak_rss_of_process_run(spec, n // 2)
        rss_2n = _peak_rss_of_process_run(spec, n)
        kernel = _kernel_against_records(spec)
        rk4 = _spec(folder, rk4=True)
        prep = prepared(rk4.read_text(), str(rk4), 64)
        vals = prep.space.draw(0, np.arange(64))[0]
        run_samples(prep, vals, np.full(64, -1))
        c0 = time.process_time()
        run_samples(prep, vals, np.full(64, -1))
        c_batch = time.process_time() - c0
        c0 = time.process_time()
        for v in vals[:16, 0]:
            prep.simulator.run(parameters={"m2": float(v)})
        c_loop = time.process_time() - c0
    load_after = os.getloadavg()
    out = {
        "scenario": "SIMNOG decentralized PID, 2 s per sample, m2 uniform on [2, 4] kg, default integrator: "
                    + str(a.engine["integrator"]),
        "samples": n,
        "steps_per_run": a.engine["steps_per_run"],
        "in_process": {"wall_s": round(t_a, 3), "cpu_s": round(cpu_a, 3)},
        "dask_1_worker": one,
        "dask_2_workers": two,
        "cpu_ms_per_sample": {"in_process": round(1e3 * cpu_a / n, 2), "dask_1": round(1e3 * one["cpu_s"] / n, 2),
                              "dask_2": round(1e3 * two["cpu_s"] / n, 2)},
        "engine_overhead_per_core_cpu": {"1_worker": round(one["cpu_s"] / cpu_a, 3),
                                         "2_workers": round(two["cpu_s"] / cpu_a, 3)},
        "engine_overhead_per_core_wall_1_worker": round(one["wall_s"] / t_a, 3),
        "engine_overhead_goal": 1.3,
        "speedup_1_to_2_workers_wall": round(one["wall_s"] / two["wall_s"], 3),
        "extrapolated_1e6_samples_s": {
            "2 workers, this run's wall rate": round(1e6 * two["wall_s"] / n, 1),
            "2 idle cores, this run's CPU per sample": round(1e6 * two["cpu_s"] / n / 2, 1)},
        "goal_1e6_s": 300.0,
        "goal_met": 1e6 * two["cpu_s"] / n / 2 < 300.0,
        "extrapolated": "10^6 samples were not run: the figures are 10^6 times this run's time per sample",
        "peak_rss_mb": {f"process engine, {n // 2} samples": round(rss_n, 1),
                        f"process engine, {n} samples": round(rss_2n, 1)},
        "default_integrator_cpu_ms_per_sample": kernel,
        "rk4_cpu_ms_per_sample": {"batched (64 mapped)": round(1e3 * c_batch / 64, 2),
                                  "single runs": round(1e3 * c_loop / 16, 2)},
        "rk4_single_over_batched": round((c_loop / 16) / (c_batch / 64), 3),
        "identical_tables": True,
        "load_average_before_after": [round(load_before[0], 2), round(load_after[0], 2)],
        "cores": os.cpu_count(),
    }
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    (ROOT / "benchmarks" / "results" / "sweep.json").write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1000)
