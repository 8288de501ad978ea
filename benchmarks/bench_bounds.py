"""Benchmark: proven ranges of the PUMA 560's six D_ii over its joint-limit box, against the sampled range.

Scenario: ``designkit.robot("puma560")``, the box of its joint limits (``qlim``), each diagonal inertia
``D_ii(q)`` enclosed to ``rel_tol = 1e-3`` by :func:`designkit.models.bounds.model_bound` (Arb balls on CasADi's
graph, the mean-value form, branch and bound), beside :func:`designkit.models.link.link_range` (a 7-point grid
per outboard joint polished by L-BFGS-B: the inner estimate the workspace check used before), in the same run.

Scaling, in the same run: the work (boxes) and the time against the tolerance (``D_11`` of the PUMA at 1e-2,
1e-3, 1e-4) and against the number of joints (``D_11`` of planar chains of 2 to 5 revolute links, every joint in
[-1, 1] rad, 1e-3, at most 40,000 boxes per end).  Timed with ``time.perf_counter`` (median of ``REPEAT``
rounds for the main comparison).

Goal: all six proven ranges in at most 10 s on this 2-core machine.

Run: ``python benchmarks/bench_bounds.py [--out PATH]``; writes ``benchmarks/results/bounds.json`` by default.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

import designkit as dk
from designkit.models.bounds import model_bound
from designkit.models.link import link_range

RESULTS = Path(__file__).resolve().parent / "results" / "bounds.json"
GOAL_S = 10.0
REPEAT = 3


def _puma(arm: Any, low: np.ndarray, high: np.ndarray, tol: float) -> dict[str, Any]:
    rows, t0 = [], time.perf_counter()
    for i in range(arm.n):
        t = time.perf_counter()
        e = model_bound(arm, "mass_matrix", (i, i), q=(low, high), rel_tol=tol)
        rows.append({"joint": i + 1, "proven": [e.lower, e.upper], "attained": [e.min_value, e.max_value],
                     "boxes": e.boxes, "seconds": time.perf_counter() - t})
    return {"seconds": time.perf_counter() - t0, "joints": rows}


def _sampled(arm: Any, low: np.ndarray, high: np.ndarray) -> dict[str, Any]:
    rows, t0 = [], time.perf_counter()
    for i in range(arm.n):
        r = link_range(arm, i, low, high)
        rows.append({"joint": i + 1, "sampled": [float(r.inertia_min), float(r.inertia_max)]})
    return {"seconds": time.perf_counter() - t0, "joints": rows}


def _chain(n: int) -> Any:
    links = [{"a": 0.5 - 0.05 * k, "mass": 4.0 - 0.5 * k, "com": [-(0.25 - 0.025 * k), 0, 0],
              "inertia": [0, (4.0 - 0.5 * k) * (0.5 - 0.05 * k) ** 2 / 12, (4.0 - 0.5 * k) * (0.5 - 0.05 * k) ** 2 / 12,
                          0, 0, 0]} for k in range(n)]
    return dk.robot_from_dh(name=f"planar{n}r", links=links)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    arm = dk.robot("puma560")
    low = np.array([lk.qlim[0] for lk in arm.description.links])
    high = np.array([lk.qlim[1] for lk in arm.description.links])
    proven, sampled = [], []
    for _ in range(REPEAT):  # interleaved
        proven.append(_puma(arm, low, high, 1e-3))
        sampled.append(_sampled(arm, low, high))
    t_proven = statistics.median(r["seconds"] for r in proven)
    t_sampled = statistics.median(r["seconds"] for r in sampled)
    tolerance = []
    for tol in (1e-2, 1e-3, 1e-4):
        t = time.perf_counter()
        e = model_bound(arm, "mass_matrix", (0, 0), q=(low, high), rel_tol=tol, max_boxes=200_000)
        tolerance.append({"rel_tol": tol, "boxes": e.boxes, "seconds": time.perf_counter() - t})
    joints = []
    for n in range(2, 6):
        chain = _chain(n)
        t = time.perf_counter()
        e = model_bound(chain, "mass_matrix", (0, 0), q=(-1.0, 1.0), rel_tol=1e-3, max_boxes=40_000, strict=False)
        joints.append({"joints": n, "free": n - 1, "boxes": e.boxes, "converged": e.converged,
                       "seconds": time.perf_counter() - t})
    result = {
        "scenario": "PUMA 560, six D_ii over the joint-limit box, rel_tol 1e-3",
        "machine": {"python": platform.python_version(), "processor": platform.processor() or platform.machine()},
        "proven_s": t_proven, "sampled_s": t_sampled, "ratio_proven_to_sampled": t_proven / t_sampled,
        "goal_s": GOAL_S, "meets_goal": t_proven <= GOAL_S,
        "per_joint": proven[-1]["joints"], "sampled_per_joint": sampled[-1]["joints"],
        "scaling_tolerance": tolerance, "scaling_joints": joints,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    print(f"proven (six D_ii, 1e-3): {t_proven:.2f} s; sampled grid + L-BFGS-B: {t_sampled:.2f} s "
          f"(ratio {t_proven / t_sampled:.1f}); goal {GOAL_S:g} s: {'met' if t_proven <= GOAL_S else 'missed'}")
    for row in proven[-1]["joints"]:
        s_row = sampled[-1]["joints"][row["joint"] - 1]
        print(f"  D_{row['joint']}{row['joint']}: proven [{row['proven'][0]:.6g}, {row['proven'][1]:.6g}], sampled "
              f"[{s_row['sampled'][0]:.6g}, {s_row['sampled'][1]:.6g}], {row['boxes']} boxes, {row['seconds']:.2f} s")
    for row in tolerance:
        print(f"  D_11 at rel_tol {row['rel_tol']:g}: {row['boxes']} boxes, {row['seconds']:.2f} s")
    for row in joints:
        note = "" if row["converged"] else " (work limit reached before the tolerance)"
        print(f"  planar {row['joints']}R D_11 ({row['free']} free joints): {row['boxes']} boxes, "
              f"{row['seconds']:.2f} s{note}")


if __name__ == "__main__":
    main()
