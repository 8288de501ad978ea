"""Robust-stability sweep: vectorised Routh (`stable_fraction`) over 10^5 sampled plants.

Run apart from the tests:  python benchmarks/bench_robustness.py
Goal: < 5 s for 10^5 plants on 2 cores.  Baseline measured in the same run: a per-plant loop
building the closed loop (``family.closed_loop``) and calling ``numpy.linalg.eigvals``, timed on
a 10^3 subsample and *extrapolated linearly* to 10^5 (the loop's cost per plant is constant).
The two verdicts are compared on the subsample, away from the stability boundary.
Writes benchmarks/results/robustness.json.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
from designkit.synthesis.registry import family

from designkit.models.link import LinkPlant
from designkit.synthesis.pid import design_tracking
from designkit.verification.robustness import stable_fraction

ROOT = Path(__file__).resolve().parents[1]
N, N_BASE, SEED = 100_000, 1_000, 0


def main() -> None:
    # a slow tracker on a wide box, so that both verdicts occur (about 5 % unstable plants)
    design = design_tracking(LinkPlant(Km=2.0, tau=0.5), [-1.0, -1.2, -1.5])
    fam = family("pid_tracking")
    rng = np.random.default_rng(SEED)
    Km = rng.uniform(0.1, 10.0, N)
    tau = rng.uniform(0.01, 5.0, N)

    stable_fraction(design, fam, Km[:100], tau[:100])  # warm-up (imports, caches)
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        fast = stable_fraction(design, fam, Km, tau)
        times.append(time.perf_counter() - t0)
    t_fast = statistics.median(times)

    t0 = time.perf_counter()
    slow, decidable = [], []
    for k, t in zip(Km[:N_BASE], tau[:N_BASE], strict=True):
        ev = np.linalg.eigvals(fam.closed_loop(design, LinkPlant(Km=float(k), tau=float(t))).A)
        slow.append(bool(np.all(ev.real < 0)))
        decidable.append(np.min(np.abs(ev.real)) > 1e-6 * np.max(np.abs(ev)))
    t_base = time.perf_counter() - t0
    t_base_extrapolated = t_base * N / N_BASE
    slow, decidable = np.array(slow), np.array(decidable)
    agree = bool(np.array_equal(fast[:N_BASE][decidable], slow[decidable]))

    results = {
        "plants": N,
        "stable_fraction": float(fast.mean()),
        "vectorised_routh_seconds_median_of_5": t_fast,
        "baseline_eigvals_loop_seconds_on_subsample": t_base,
        "baseline_subsample": N_BASE,
        "baseline_seconds_extrapolated_to_plants": t_base_extrapolated,
        "speed_up": t_base_extrapolated / t_fast,
        "verdicts_agree_on_subsample": agree,
        "goal_seconds": 5.0,
        "goal_met": t_fast < 5.0,
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
        "python": platform.python_version(),
        "numpy": np.__version__,
    }
    print("| sweep | plants | wall time (s) | ratio |")
    print("|---|---|---|---|")
    print(f"| vectorised Routh `stable_fraction` | {N} | {t_fast:.4f} | 1 |")
    print(
        f"| per-plant `eigvals` loop (timed on {N_BASE}, extrapolated) | {N} | {t_base_extrapolated:.2f} | "
        f"{t_base_extrapolated / t_fast:.0f} |"
    )
    print(f"stable fraction {fast.mean():.4f}; verdicts agree on the subsample: {agree}")
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    (ROOT / "benchmarks" / "results" / "robustness.json").write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
