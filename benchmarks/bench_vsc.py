"""Benchmark: the vsc regulator on the ROBEL elastic joint, 10 s at the step the switching needs, warm.

Scenario: ``specs/vsc-elastic-joint.yaml`` (figure 5.3's regulator, sliding poles -8, -10, -12 1/s, the box
J2 +-10 %, Km +-10 %, 0.2 N*m load at t = 1 s) run for 10 s, ``numerics: {compile: always}``.  The law is
discontinuous, so the simulator holds its command over each step; the step is the design's ``max_step`` (the
first held step at the initial error moves sigma by at most 5 % of |sigma(0)|), rounded down by the simulator.

Timed (``time.perf_counter``, median and min of ``REPEAT`` runs): ``Simulator.run()`` warm (built once, its step
compiled or taken from the compiled-library cache) -- the target is <= 50 ms -- and, for scale, ``build`` +
``run``.  Reported with the step, the number of steps and the cost per step, and the run's own evidence that the
step is the one the switching needs (the invariant band check and the fitted sliding poles).

Run: ``python benchmarks/bench_vsc.py [--out results.json]`` (prints the JSON; writes it only with ``--out``).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

from designkit.schema.loader import parse_spec
from designkit.simulation.run import build

ROOT = Path(__file__).resolve().parents[1]
GOAL_RUN_S = 0.050
REPEAT = 5
DURATION = 10.0


def spec_text() -> str:
    """The example spec, 10 s long, compiled."""
    text = (ROOT / "specs" / "vsc-elastic-joint.yaml").read_text()
    text = text.replace("  duration: 2.0\n", f"  duration: {DURATION}\n")
    return text + "numerics: {compile: always}\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    loaded = parse_spec(spec_text())
    spec = loaded.spec
    from designkit.pipeline import run as pipeline_run

    result = pipeline_run(loaded)
    design = result.design
    t0 = time.perf_counter()
    sim = build(spec, design, plant=result.plant)
    first = sim.run()
    first_build_and_run = time.perf_counter() - t0
    runs = []
    for _ in range(REPEAT):
        t1 = time.perf_counter()
        sim.run()
        runs.append(time.perf_counter() - t1)
    builds = []
    for _ in range(2):
        t1 = time.perf_counter()
        build(spec, design, plant=result.plant).run()
        builds.append(time.perf_counter() - t1)
    dt = float(first.settings["dt"])
    steps = round(DURATION / dt)
    checks = {c.name: c for c in result.checks}
    out = {
        "scenario": "vsc elastic joint, 10 s, held switching command",
        "dt_s": dt, "max_step_s": design.extra["vsc"]["max_step"], "steps": steps,
        "run_warm_median_s": statistics.median(runs), "run_warm_min_s": min(runs),
        "per_step_us": 1e6 * statistics.median(runs) / steps,
        "goal_run_s": GOAL_RUN_S, "goal_met": statistics.median(runs) <= GOAL_RUN_S,
        "build_and_run_cached_median_s": statistics.median(builds), "first_build_and_run_s": first_build_and_run,
        "band_check": checks["vsc_band"].passed, "max_sigma_over_band": checks["vsc_band"].achieved,
        "sliding_pole_error": checks["vsc_sliding_poles"].achieved,
        "python": platform.python_version(), "machine": platform.machine(),
    }
    text = json.dumps(out, indent=2)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
