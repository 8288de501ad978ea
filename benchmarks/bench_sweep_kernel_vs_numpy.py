"""Benchmark: CPU per Monte Carlo sample of the SIMNOG sweep -- the compiled kernel against a NumPy integration
vectorised over the samples -- and the 10^6-sample sweep on two Dask workers, extrapolated.

Scenario: ``specs/simnog-decentralized-pid.yaml`` as it is (5 s per sample on the 0.1 ms output grid: 50,001 grid
points; m2 uniform on [2, 4] kg; overshoot, settling time and steady-state error scored per sample).  Measured in
one run, on this machine under whatever load it carries (the load average is recorded before and after):

(a) the compiled kernel (``designkit.sweep.kernel``): the Dormand--Prince pair integrates each sample and the
    observer reduces it to the metrics, reading only the grid points each step's dense-output bounds say can change
    a metric; and the same kernel made to read every grid point (the metrics are checked identical, bit for bit);
    CPU per sample, best of interleaved rounds on one batch;
(b) the NumPy route: the same Dormand--Prince 5(4) pair with the same tolerances and PI step control, written here
    with NumPy arrays over the samples (every sample its own step size; the loop's right-hand side is CasADi's
    function mapped over the batch's columns), its continuous extension evaluated on the whole grid and the
    metrics computed from it by ``designkit.sweep.margins.joint_metrics`` (vectorised over the samples); its
    margins are checked against the kernel's (within 1e-6 relative: an independent integration to rtol 1e-10);
(c) ``designkit.sweep.api.sweep`` on a warm two-worker LocalCluster (``S`` samples, default 10^4; every worker
    built its loop first): wall and CPU seconds (every worker and this process), the per-sample table checked
    identical to a one-worker sweep of the same samples; 10^6 samples extrapolated from it (not run: said so).

Run: ``python benchmarks/bench_sweep_kernel_vs_numpy.py [S]``; writes ``benchmarks/results/sweep_kernel_vs_numpy.json``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "specs" / "simnog-decentralized-pid.yaml"

# Dormand & Prince (1980) 5(4), Hairer's dense output (contd5) and PI control: the published coefficients
C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
A = [[], [1 / 5], [3 / 40, 9 / 40], [44 / 45, -56 / 15, 32 / 9],
     [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
     [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
     [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]]
E = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])
D = np.array([-12715105075 / 11282082432, 0.0, 87487479700 / 32700410799, -10690763975 / 1880347072,
              701980252875 / 199316789632, -1453857185 / 822651844, 69997945 / 29380423])


def numpy_pair(rhs, a: np.ndarray, q: np.ndarray, s0: np.ndarray, t_end: float, rtol: float, atol: float):
    """Integrate ``B`` samples of ``s' = rhs(s, a, q_b)`` from ``s0`` to ``t_end`` with every sample's own step:
    per sample the list of accepted steps ``(t, h, r1..r5)`` (arrays over the steps) and the evaluations."""
    B, ns = s0.shape
    maps: dict[int, object] = {}

    def f(S: np.ndarray, Q: np.ndarray) -> np.ndarray:
        m = S.shape[0]
        if m not in maps:
            maps[m] = rhs.map(m)
        return np.asarray(maps[m](S.T, np.repeat(a[:, None], m, axis=1), Q.T)).T

    y, t = s0.copy(), np.zeros(B)
    k1 = f(y, q)
    evals = np.ones(B)
    sk = atol + rtol * np.abs(y)
    dnf, dny = np.sum((k1 / sk) ** 2, axis=1), np.sum((y / sk) ** 2, axis=1)
    h = np.where((dnf <= 1e-10) | (dny <= 1e-10), 1e-6, np.sqrt(dny / np.maximum(dnf, 1e-300)) * 0.01)
    h = np.minimum(h, t_end)
    k2 = f(y + h[:, None] * k1, q)
    evals += 1
    der2 = np.sqrt(np.sum(((k2 - k1) / sk) ** 2, axis=1)) / h
    der12 = np.maximum(der2, np.sqrt(dnf))
    h1 = np.where(der12 <= 1e-15, np.maximum(1e-6, h * 1e-3), (0.01 / np.maximum(der12, 1e-300)) ** 0.2)
    h = np.minimum(100 * h, h1)
    facold = np.full(B, 1e-4)
    rejected = np.zeros(B, dtype=bool)
    steps: list[list[np.ndarray]] = [[] for _ in range(B)]
    active = np.arange(B)
    while active.size:
        ya, ta, ha, qa = y[active], t[active], h[active], q[active]
        last = ta + ha >= t_end - 1e-13
        ha = np.where(last, t_end - ta, ha)
        K = [k1[active]]
        for i in range(1, 7):
            stage = ya + ha[:, None] * sum(A[i][j] * K[j] for j in range(i) if A[i][j] != 0.0)
            K.append(f(stage, qa))
        evals[active] += 6
        y1 = ya + ha[:, None] * sum(A[6][j] * K[j] for j in range(6) if A[6][j] != 0.0)
        sc = atol + rtol * np.maximum(np.abs(ya), np.abs(y1))
        err = np.sqrt(np.mean((ha[:, None] * sum(E[j] * K[j] for j in range(7) if E[j] != 0.0) / sc) ** 2, axis=1))
        fac11 = np.where(np.isnan(err), 1e3, err ** 0.17)
        ok = err <= 1.0
        # accepted: the dense output's coefficients, then the PI control
        yd = y1 - ya
        bs = ha[:, None] * K[0] - yd
        r4 = yd - ha[:, None] * K[6] - bs
        r5 = ha[:, None] * sum(D[j] * K[j] for j in range(7) if D[j] != 0.0)
        for i in np.flatnonzero(ok):
            steps[active[i]].append(np.concatenate([[ta[i], ha[i]], ya[i], yd[i], bs[i], r4[i], r5[i]]))
        fac = np.clip(fac11 / facold[active] ** 0.04 / 0.9, 0.1, 5.0)
        hnew = ha / fac
        hnew = np.where(rejected[active], np.minimum(hnew, ha), hnew)
        acc = active[ok]
        y[acc], t[acc] = y1[ok], np.where(last[ok], t_end, ta[ok] + ha[ok])
        k1[acc] = K[6][ok]
        facold[acc] = np.maximum(err[ok], 1e-4)
        rejected[acc] = False
        h[acc] = hnew[ok]
        rej = active[~ok]
        rejected[rej] = True
        h[rej] = ha[~ok] / np.minimum(5.0, fac11[~ok] / 0.9)
        active = active[~(ok & last)]
    return [np.array(s) for s in steps], evals


def dense_on_grid(steps: np.ndarray, grid: np.ndarray, rows: list[int], ns: int) -> np.ndarray:
    """``(N, len(rows))``: the continuous extension of the accepted steps ``steps`` at the grid's instants."""
    t0, h = steps[:, 0], steps[:, 1]
    idx = np.clip(np.searchsorted(t0, grid, side="right") - 1, 0, len(t0) - 1)
    th = ((grid - t0[idx]) / h[idx])[:, None]
    r = [steps[idx, 2 + k * ns:2 + (k + 1) * ns][:, rows] for k in range(5)]
    return r[0] + th * (r[1] + (1 - th) * (r[2] + th * (r[3] + (1 - th) * r[4])))


def _cpu(fn):
    c0 = time.process_time()
    out = fn()
    return out, time.process_time() - c0


def kernel_and_numpy(b: int, rounds: int = 3) -> dict:
    from designkit.simulation.batch import BatchRecords
    from designkit.sweep.chunk import _inputs, prepared
    from designkit.sweep.margins import joint_metrics, margins_of

    prep = prepared(SPEC.read_text(), str(SPEC), b)
    sim, k = prep.simulator, prep.kernel
    assert k is not None, "the default integrator's sweep runs the kernel"
    every = dataclasses.replace(k, constants=np.concatenate([[2.0], k.constants[1:]]))  # 2: read every point
    vals = prep.space.draw(0, np.arange(b))[0]
    P = _inputs(prep, vals, np.full(b, -1))["parameters"]
    best = {"kernel": np.inf, "kernel_every_point": np.inf}
    for _ in range(rounds):
        for name, kk in (("kernel", k), ("kernel_every_point", every)):
            (jm, failed), c = _cpu(lambda kk=kk: kk.run(sim, P))
            best[name] = min(best[name], c)
    fast, _ = k.run(sim, P)
    slow, _ = every.run(sim, P)
    for f in ("finite", "overshoot", "rise", "settle", "moving", "sse", "max_err", "amps"):
        assert np.array_equal(getattr(fast, f), getattr(slow, f), equal_nan=True), f

    pair = sim.dopri5
    w = np.asarray(sim.inputs, dtype=float)
    assert np.all(w == w[:, :1]), "a step held from t = 0: the inputs are one column"
    na, n = pair.n_ref, len(prep.plant.positions)
    a, q0 = w[:na, 0], w[3 * na:, 0]
    Q = np.tile(q0, (b, 1))
    Q[:, -P.shape[1]:] = P
    s0 = np.tile(np.asarray(sim.z0, dtype=float)[:pair.ns], (b, 1))
    t = np.asarray(sim.time, dtype=float)
    rows = list(prep.plant.positions)

    def numpy_route():
        steps, evals = numpy_pair(pair.rhs, a, Q, s0, float(t[-1]), pair.rtol, pair.atol)
        y = np.stack([dense_on_grid(s, t, rows, pair.ns) for s in steps])
        xd = np.broadcast_to(w[:n, 0], y.shape)
        rec = BatchRecords(time=t, desired=xd, tracked=y, u_command=np.zeros((b, t.size, 0)),
                           u_applied=np.zeros((b, t.size, 0)), failures=("",) * b)
        return joint_metrics(rec, sim.kind, prep.requirements.settling_band, False), evals

    best_np = np.inf
    for _ in range(max(1, rounds - 1)):
        (jm_np, evals), c = _cpu(numpy_route)
        best_np = min(best_np, c)
    m_fast = margins_of(fast, sim.kind, prep.requirements)
    m_np = margins_of(jm_np, sim.kind, prep.requirements)
    worst_rel = 0.0
    for name in m_fast.names:
        x, y_ = m_fast.achieved[name], m_np.achieved[name]
        worst_rel = max(worst_rel, float(np.max(np.abs(x - y_) / np.maximum(np.abs(x), 1e-12))))
    assert worst_rel < 1e-6, f"the NumPy route's metrics differ from the kernel's by {worst_rel:g} (relative)"
    return {"batch": b, "rounds": rounds,
            "cpu_ms_per_sample": {"kernel": round(1e3 * best["kernel"] / b, 4),
                                  "kernel_every_grid_point": round(1e3 * best["kernel_every_point"] / b, 4),
                                  "numpy_vectorised_over_samples": round(1e3 * best_np / b, 2)},
            "numpy_over_kernel": round(best_np / best["kernel"], 1),
            "every_point_over_plan": round(best["kernel_every_point"] / best["kernel"], 2),
            "numpy_evaluations_per_sample": float(np.mean(evals)),
            "largest_relative_difference_numpy_vs_kernel": worst_rel,
            "grid_points": int(t.size)}


def _worker_cpu(client) -> float:
    import psutil

    def cpu() -> float:
        c = psutil.Process().cpu_times()
        return c.user + c.system

    return float(sum(client.run(cpu).values()))


def dask_run(n: int, workers: int) -> tuple[dict, object]:
    from designkit.sweep.api import sweep
    from designkit.sweep.engine import connect

    client, cluster = connect(None, workers)
    try:
        sweep(SPEC, 8 * workers, client=client, chunk=4, falsification=False, report=False)  # every worker warm
        cpu0, own0 = _worker_cpu(client), time.process_time()
        t0 = time.perf_counter()
        res = sweep(SPEC, n, client=client, falsification=False, report=False)
        wall = time.perf_counter() - t0
        cpu = _worker_cpu(client) - cpu0 + time.process_time() - own0
    finally:
        client.close()
        cluster.close()
    return {"samples": n, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2)}, res


def main(n: int = 10_000) -> dict:
    load0 = os.getloadavg()
    kn = kernel_and_numpy(64)
    load1 = os.getloadavg()
    two, r2 = dask_run(n, 2)
    load2 = os.getloadavg()
    one, r1 = dask_run(min(n, 4000), 1)
    same = all(np.array_equal(getattr(r1, f), getattr(r2, f)[:r1.index.size], equal_nan=True)
               for f in ("index", "values", "achieved", "margin", "passed"))
    assert same, "the per-sample tables differ between one and two workers"
    out = {
        "scenario": "specs/simnog-decentralized-pid.yaml: 5 s per sample on the 0.1 ms grid (50,001 points), "
                    "m2 uniform on [2, 4] kg, overshoot, settling time and steady-state error per sample",
        "kernel_vs_numpy": kn,
        "dask_2_workers": two,
        "dask_1_worker_same_samples_identical": {"samples": one["samples"], "identical": same},
        "cpu_ms_per_sample_2_workers": round(1e3 * two["cpu_s"] / n, 3),
        "extrapolated_1e6_samples_s": {
            "2 workers, this run's wall rate": round(1e6 * two["wall_s"] / n, 1),
            "2 idle cores, this run's CPU per sample": round(1e6 * two["cpu_s"] / n / 2, 1)},
        "goal_1e6_s": 300.0,
        "extrapolated": f"10^6 samples were not run: the figures are 10^6 times this run's time per sample "
                        f"({n} samples)",
        "load_average_1min": {"before_kernel": round(load0[0], 2), "before_dask": round(load1[0], 2),
                              "after_dask": round(load2[0], 2), "end": round(os.getloadavg()[0], 2)},
        "machine": {"cores": os.cpu_count(), "python": platform.python_version(), "machine": platform.machine()},
    }
    (ROOT / "benchmarks" / "results" / "sweep_kernel_vs_numpy.json").write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000)
