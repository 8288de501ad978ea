"""Benchmark: what the ``generated_code`` check adds to ``designkit verify``, and the C law's loop against the
compiled simulation.

For each link example (``specs/posspeed-link.yaml``, ``specs/sliding-mode-link.yaml``, ``specs/pid-sm-link.yaml``):

1. ``designkit verify --json`` as a user runs it, in a fresh interpreter (``command_check_share``), and
   ``verify --jobs 1 --json`` in this process, warm (``check_share``), each with the check and without it
   (``generated_code`` filtered out of the rules the suite resolves), the libraries cached (one warm-up run
   first); the ratio ``with / without - 1`` is the share the check adds.  Goal: at most 0.30.  The check's own
   time (``compare_generated_code`` given the verdict's simulator, as in ``verify``; cached) over the warm verify
   without it is given too: on a loaded machine the difference of two verify times is noise of the size of the
   check.
2. The loop calling the compiled C law (``GeneratedLoops.c.run()``) against the verdict's own compiled
   simulation (``build(...).run()``: the Dormand--Prince pair or the compiled RK4 roll), and against the compiled
   RK4 roll of the same loop with the Python law (``GeneratedLoops.python.run()``, the same integrator); the ratios
   ``C loop / compiled simulation``.  Goal: at most 2.
3. A cold compile: the check's work with an empty cache (``DESIGNKIT_CACHE_DIR`` a fresh folder): writing the C,
   compiling the law and the loop library.

Timed with ``time.perf_counter``: medians of interleaved repeats; the machine is shared (its load average is
recorded), so compare the ratios, each measured within one run.

Run: ``python benchmarks/bench_generated_code_overhead.py [--repeats N] [--out results.json]`` (prints the JSON and
writes ``benchmarks/results/generated_code_overhead.json``, or ``--out``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from designkit.cli import main
from designkit.runner.run import run_spec
from designkit.schema.loader import load_spec
from designkit.verification import suite
from designkit.verification.generated_loop import compare_generated_code, generated_loops

ROOT = Path(__file__).resolve().parents[1]
SPECS = ("posspeed-link", "sliding-mode-link", "pid-sm-link")


def _verify(path: Path, with_check: bool) -> float:
    """Wall time of ``verify --jobs 1 --json`` in this process, without ``generated_code`` when asked (the rules
    :func:`~designkit.verification.suite.resolve` returns, which adds the universal ones, filtered)."""
    original = suite.resolve
    if not with_check:
        suite.resolve = lambda offered: tuple(r for r in original(offered) if r.name != "generated_code")
    try:
        out = io.StringIO()
        start = time.perf_counter()
        with contextlib.redirect_stdout(out):
            main(["verify", "--jobs", "1", "--json", str(path)])
        seconds = time.perf_counter() - start
    finally:
        suite.resolve = original
    ran = any(c["name"] == "generated_code" for c in json.loads(out.getvalue())["checks"])
    if ran != with_check:
        raise RuntimeError(f"{path.name}: generated_code ran {ran}, expected {with_check}")
    return seconds


_FRESH = """import os, sys
from designkit.verification import suite
if sys.argv[2] == "without":
    resolve = suite.resolve
    suite.resolve = lambda offered: tuple(r for r in resolve(offered) if r.name != "generated_code")
from designkit.cli import main
code = main(["verify", "--json", sys.argv[1]])
sys.stdout.flush()
os._exit(code)
"""


def _verify_fresh(path: Path, with_check: bool) -> float:
    """Wall time of ``designkit verify --json`` in a fresh interpreter (the command as a user runs it, default
    ``--jobs``), without ``generated_code`` when asked."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", _FRESH, str(path), "with" if with_check else "without"],
                          capture_output=True, text=True, env=env)
    seconds = time.perf_counter() - start
    ran = any(c["name"] == "generated_code" for c in json.loads(proc.stdout)["checks"])
    if ran != with_check:
        raise RuntimeError(f"{path.name}: generated_code ran {ran}, expected {with_check}")
    return seconds


def _median_time(f: Any, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def measure(name: str, repeats: int) -> dict[str, Any]:
    path = ROOT / "specs" / f"{name}.yaml"
    _verify(path, True)  # warm-up: every library compiled and cached
    with_check, without, fresh_with, fresh_without = [], [], [], []
    for _ in range(repeats):
        without.append(_verify(path, False))
        with_check.append(_verify(path, True))
        fresh_without.append(_verify_fresh(path, False))
        fresh_with.append(_verify_fresh(path, True))
    run = run_spec(load_spec(path), box=False, verdict_run=True)
    loops = generated_loops(run.loaded.spec, run.design, plant=run.plant)
    compiled = _median_time(loops.verdict.run, max(repeats, 5))
    c_loop = _median_time(loops.c.run, max(repeats, 5))
    python_loop = _median_time(loops.python.run, max(repeats, 5))
    check_s = _median_time(lambda: compare_generated_code(run.loaded.spec, run.design, plant=run.plant,
                                                          simulator=loops.verdict), repeats)
    with tempfile.TemporaryDirectory() as cold:
        before = os.environ.get("DESIGNKIT_CACHE_DIR")
        os.environ["DESIGNKIT_CACHE_DIR"] = cold
        try:
            start = time.perf_counter()
            generated_loops(run.loaded.spec, run.design, plant=run.plant)
            cold_s = time.perf_counter() - start
        finally:
            if before is None:
                os.environ.pop("DESIGNKIT_CACHE_DIR", None)
            else:
                os.environ["DESIGNKIT_CACHE_DIR"] = before
    check = next(c for c in run.checks if c.name == "generated_code")
    v_with, v_without = statistics.median(with_check), statistics.median(without)
    f_with, f_without = statistics.median(fresh_with), statistics.median(fresh_without)
    return {
        "spec": name, "steps": int(run.simulation.time.size),
        "verdict_integrator": loops.verdict.settings["integrator"],
        "command_without_check_s": round(f_without, 4), "command_with_check_s": round(f_with, 4),
        "command_check_share": round(f_with / f_without - 1, 4),
        "verify_without_check_s": round(v_without, 4), "verify_with_check_s": round(v_with, 4),
        "check_share": round(v_with / v_without - 1, 4), "check_s": round(check_s, 4),
        "check_s_over_verify_without": round(check_s / v_without, 4),
        "compiled_simulation_s": round(compiled, 5), "c_loop_s": round(c_loop, 5),
        "compiled_rk4_python_law_s": round(python_loop, 5),
        "c_loop_over_compiled_simulation": round(c_loop / compiled, 3),
        "c_loop_over_compiled_rk4": round(c_loop / python_loop, 3),
        "cold_compile_s": round(cold_s, 3), "check_status": check.status,
        "state_difference": check.certificate.get("state_difference"),
        "command_difference": check.certificate.get("command_difference"),
    }


def main_(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "generated_code_overhead.json")
    args = parser.parse_args(argv)
    load = os.getloadavg()
    rows = [measure(name, args.repeats) for name in SPECS]
    result = {
        "benchmark": "generated_code_overhead",
        "goals": {"check_share_max": 0.30, "c_loop_over_compiled_simulation_max": 2.0},
        "met": {"command_check_share": all(r["command_check_share"] <= 0.30 for r in rows),
                "check_share": all(r["check_share"] <= 0.30 for r in rows),
                "check_s_over_verify_without": all(r["check_s_over_verify_without"] <= 0.30 for r in rows),
                "c_loop_over_compiled_simulation": all(r["c_loop_over_compiled_simulation"] <= 2.0 for r in rows),
                "c_loop_over_compiled_rk4": all(r["c_loop_over_compiled_rk4"] <= 2.0 for r in rows)},
        "specs": rows, "repeats": args.repeats,
        "load_average": {"before": list(load), "after": list(os.getloadavg())},
        "python": sys.version.split()[0], "machine": platform.machine(),
    }
    text = json.dumps(result, indent=2)
    print(text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text + "\n")
    return result


if __name__ == "__main__":
    main_()
