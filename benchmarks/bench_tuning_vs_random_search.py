"""What ``designkit tune`` costs to meet SIMNOG's requirements over a payload box, against a random search.

Run apart from the tests:  python benchmarks/bench_tuning_vs_random_search.py [--budget S] [--seeds N]

The problem: the decentralized PID of specs/simnog-decentralized-pid.yaml, its poles and zero tuned (four log
coordinates, a decade either side of the poles the requirements derive) for overshoot <= 5 % and settling time <= 1 s
at both ends of m2 in [2, 4] kg and the nominal 3 kg, every certificate enforced.  In one process, per seed, each
search gets the same wall-time budget and the same candidate evaluation (:func:`designkit.tuning.evaluate.evaluate`):
Nelder-Mead with restarts (what ``designkit tune`` runs) and seeded uniform draws in the same log box.  Quoted per
search: the seconds and the simulations until the first candidate meeting every requirement (certified), and the best
worst-case normalised margin at the end.  Writes benchmarks/results/tuning.json.
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

SPEC = """\
name: simnog-tune-benchmark
plant:
  kind: robot
  robot: planar2r
  uncertainty: {m2: [2.0, 4.0], grid: 5}
controller: {kind: decentralized_pid}
requirements: {overshoot: 5, settling_time: 1.0}
simulation:
  duration: 2.5
  step: [1.0, -0.5]
"""


def _first_feasible(search, start: float) -> dict:
    sims, seconds = 0, None
    for e in search.evaluations:
        sims += e.runs
        if e.feasible:
            seconds = e.seconds_at - start
            return {"seconds": round(seconds, 2), "simulations": sims}
    return {"seconds": None, "simulations": None}


def _timed(evaluate):
    """``evaluate`` recording when each candidate finished (``seconds_at``)."""
    import dataclasses

    from designkit.tuning.evaluate import Evaluation

    @dataclasses.dataclass(frozen=True)
    class Timed(Evaluation):
        seconds_at: float = 0.0

    def run(x, above):
        e = evaluate(x, above)
        return Timed(**{f.name: getattr(e, f.name) for f in dataclasses.fields(Evaluation)},
                     seconds_at=time.perf_counter())

    return run


def main() -> None:
    import designkit as dk
    from designkit.tuning.api import prepare
    from designkit.tuning.evaluate import evaluate
    from designkit.tuning.search import nelder_mead, random_search

    parser = argparse.ArgumentParser()
    parser.add_argument("--budget", type=float, default=60.0)
    parser.add_argument("--seeds", type=int, default=2)
    args = parser.parse_args()
    loaded = dk.parse_spec(SPEC)
    problem, space = prepare(loaded)
    ev = _timed(lambda x, above: evaluate(problem, space, x, above=above))
    ev(space.x0, 1e9)  # compile and import once, outside the timings
    rows = []
    for seed in range(args.seeds):
        for name, method in (("nelder_mead", nelder_mead), ("random_search", random_search)):
            start = time.perf_counter()
            cpu = time.process_time()
            search = method(ev, space.x0, space.bounds, budget=args.budget, seed=seed)
            row = {"search": name, "seed": seed, "seconds": round(search.seconds, 2),
                   "cpu_seconds": round(time.process_time() - cpu, 2), "candidates": len(search.evaluations),
                   "simulations": search.simulations, "best_score": round(search.best.score, 4),
                   "best_margins": {k: round(v, 4) for k, v in search.best.margins.items()},
                   "first_feasible": _first_feasible(search, start), "stopped": search.stopped}
            rows.append(row)
            print(json.dumps(row))
    summary = {}
    for name in ("nelder_mead", "random_search"):
        mine = [r for r in rows if r["search"] == name]
        firsts = [r["first_feasible"]["simulations"] for r in mine if r["first_feasible"]["simulations"] is not None]
        summary[name] = {
            "median_best_score": statistics.median(r["best_score"] for r in mine),
            "median_seconds": statistics.median(r["seconds"] for r in mine),
            "median_simulations": statistics.median(r["simulations"] for r in mine),
            "feasible_found": f"{len(firsts)} of {len(mine)}",
            "median_simulations_to_first_feasible": statistics.median(firsts) if firsts else None,
        }
    out = {"spec": SPEC, "budget_s": args.budget, "coordinates": [c.label for c in space.coordinates],
           "points": [dict(p) for p in problem.points], "runs": rows, "summary": summary,
           "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                       "load_average": os.getloadavg()}}
    path = ROOT / "benchmarks" / "results" / "tuning.json"
    path.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
