"""The gradient search against Nelder--Mead on specs/tune-simnog-decentralized-pid.yaml, in one process.

Run apart from the tests:  python benchmarks/bench_tuning_gradient.py [--budget S] [--seeds N]

The problem is the one ``designkit tune specs/tune-simnog-decentralized-pid.yaml`` solves: SIMNOG's decentralized PID,
its three poles and zero (four log coordinates), overshoot <= 5 % and settling <= 1 s at the nominal m2 = 3 kg and at
both ends of [2, 4] kg, every certificate enforced.  Per seed both searches run in the same process, one after the
other, with the same budget and the same candidate evaluation (:func:`designkit.tuning.evaluate.evaluate`): the
gradient search (SLSQP on the epigraph, CasADi forward sensitivities) and Nelder--Mead with restarts.  Quoted per
search: the simulations (the gradient search's sensitivity runs among them), the wall and CPU seconds, the best worst
normalised margin, and the simulations and seconds (wall and CPU) until a certified candidate first meets every
requirement and first reaches ``--target`` (default 0.7); and, per seed, the ratios gradient / Nelder--Mead of the
simulations and seconds in all and to the target.  Writes
benchmarks/results/tuning_gradient.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "specs" / "tune-simnog-decentralized-pid.yaml"


def _first(search, start: tuple[float, float], marks: dict[int, tuple[float, float, int]], target: float) -> dict:
    """When (wall and CPU seconds from ``start``) and after how many simulations a certified candidate first reached
    a worst normalised margin of ``target`` (0: first met every requirement)."""
    for e in search.evaluations:
        if e.feasible and e.score >= target:
            wall, cpu, sims = marks[id(e)]
            return {"seconds": round(wall - start[0], 2), "cpu_seconds": round(cpu - start[1], 2),
                    "simulations": sims}
    return {"seconds": None, "cpu_seconds": None, "simulations": None}


def main() -> None:
    import designkit as dk
    from designkit.tuning.api import prepare
    from designkit.tuning.descent import slsqp
    from designkit.tuning.evaluate import evaluate
    from designkit.tuning.search import nelder_mead
    from designkit.tuning.sensitivity import gradients

    parser = argparse.ArgumentParser()
    parser.add_argument("--budget", type=float, default=60.0)
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--target", type=float, default=0.7, help="the worst normalised margin both are timed to")
    args = parser.parse_args()
    loaded = dk.load_spec(SPEC)
    problem, space = prepare(loaded)
    evaluate(problem, space, space.x0, above=1e9)  # compile and import once, outside the timings
    gradients(problem, space, space.x0)
    rows = []
    for seed in range(args.seeds):
        for name in ("gradient", "nelder_mead"):
            marks: dict[int, tuple[float, float, int]] = {}
            sims = [0]

            def run(x, above, marks=marks, sims=sims):
                e = evaluate(problem, space, x, above=above)
                sims[0] += e.runs
                marks[id(e)] = (time.perf_counter(), time.process_time(), sims[0])
                return e

            def grad(x, sims=sims):
                g = gradients(problem, space, x)
                sims[0] += g.runs
                return g

            start, cpu = time.perf_counter(), time.process_time()
            if name == "gradient":
                search = slsqp(run, grad, space.x0, space.bounds, budget=args.budget, seed=seed)
            else:
                search = nelder_mead(run, space.x0, space.bounds, budget=args.budget, seed=seed)
            row = {"search": name, "seed": seed, "seconds": round(search.seconds, 2),
                   "cpu_seconds": round(time.process_time() - cpu, 2), "iterations": search.iterations,
                   "candidates": len(search.evaluations), "simulations": search.simulations,
                   "sensitivity_runs": search.sensitivity_runs, "best_score": round(search.best.score, 4),
                   "best_margins": {k: round(v, 4) for k, v in search.best.margins.items()},
                   "feasible": search.best.feasible, "first_feasible": _first(search, (start, cpu), marks, 0.0),
                   "first_at_target": _first(search, (start, cpu), marks, args.target),
                   "stopped": search.stopped}
            rows.append(row)
            print(json.dumps(row), flush=True)
    ratios = []
    for seed in range(args.seeds):
        g, n = (next(r for r in rows if r["search"] == k and r["seed"] == seed) for k in ("gradient", "nelder_mead"))
        gt, nt = g["first_at_target"], n["first_at_target"]
        reached = gt["simulations"] is not None and nt["simulations"] is not None
        ratios.append({"seed": seed, "simulations": round(g["simulations"] / n["simulations"], 3),
                       "seconds": round(g["seconds"] / n["seconds"], 3),
                       "cpu_seconds": round(g["cpu_seconds"] / n["cpu_seconds"], 3),
                       "best_score_difference": round(g["best_score"] - n["best_score"], 4),
                       "to_target": None if not reached else {
                           k: round(gt[k] / nt[k], 3) for k in ("simulations", "seconds", "cpu_seconds")}})
    summary = {name: {"median_best_score": statistics.median(r["best_score"] for r in rows if r["search"] == name),
                      "median_simulations": statistics.median(r["simulations"] for r in rows if r["search"] == name),
                      "median_seconds": statistics.median(r["seconds"] for r in rows if r["search"] == name)}
               for name in ("gradient", "nelder_mead")}
    out = {"spec": str(SPEC.relative_to(ROOT)), "budget_s": args.budget, "target": args.target,
           "coordinates": [c.label for c in space.coordinates], "points": [dict(p) for p in problem.points],
           "runs": rows, "same_run_ratios": ratios, "summary": summary,
           "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                       "load_average": os.getloadavg()}}
    path = ROOT / "benchmarks" / "results" / "tuning_gradient.json"
    path.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    print(json.dumps({"summary": summary, "same_run_ratios": ratios}, indent=2))


if __name__ == "__main__":
    main()
