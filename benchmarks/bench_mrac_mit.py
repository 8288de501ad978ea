"""Benchmark: Astrom and Wittenmark's MIT-rule example (specs/mrac-mit-first-order.yaml), 100 s, against solve_ivp.

Scenario (Adaptive Control, 2nd ed., Example 5.2): ``G = 0.5/(s + 1)``, ``Gm = 2/(s + 2)``, ``u = theta1 uc -
theta2 y`` from zero, the MIT rule with the filters ``2/(p + 2)`` of ``uc`` and ``y``, ``gamma = 1``, a square wave of
amplitude 1 and period 20 s; 100 s, ``numerics: {compile: always}`` (6 states: plant, model, two sensitivity filters,
two parameters).

Timed (``time.perf_counter``, median of interleaved repeats, all in the same run):

(a) ``Simulator.run()`` warm: the simulator built once (its step compiled to C), a repeated simulation -- the goal
    is <= 20 ms;
(b) the baseline: ``scipy.integrate.solve_ivp`` on a NumPy right-hand side of the same six equations written here
    by hand from the book, piece by piece between the square wave's jumps, sampled on designkit's grid; of a ladder of
    RK45 tolerances the cheapest whose largest errors (y, theta) against DOP853 at ``rtol = 1e-12`` do not exceed
    designkit's is timed, and DOP853 at ``rtol = 1e-10`` beside it.

Run: ``python benchmarks/bench_mrac_mit.py [--out results.json]`` (prints the JSON; writes it only with ``--out``).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from designkit.families import synthesize
from designkit.schema.loader import load_spec
from designkit.simulation.run import build

SPEC = Path(__file__).resolve().parents[1] / "specs" / "mrac-mit-first-order.yaml"
A, B, AM, BM, GAMMA, PERIOD, DURATION = 1.0, 0.5, 2.0, 2.0, 1.0, 20.0, 100.0
GOAL_RUN_S = 0.020
REPEAT = 21
RTOL_LADDER = tuple(10.0 ** (-k / 2) for k in range(4, 21))


def rhs(_t: float, z: np.ndarray, uc: float) -> list[float]:
    """``z = (y, ym, filtered uc, filtered y, theta1, theta2)``: the book's loop."""
    y, ym, fuc, fy, th1, th2 = z
    e = y - ym
    return [-A * y + B * (th1 * uc - th2 * y), -AM * ym + BM * uc, -AM * fuc + AM * uc, -AM * fy + AM * y,
            -GAMMA * fuc * e, GAMMA * fy * e]


def ivp(t: np.ndarray, method: str, rtol: float, atol: float) -> tuple[np.ndarray, int]:
    """``solve_ivp`` between the jumps, sampled on ``t``: the states and the number of evaluations."""
    z = np.zeros(6)
    out = np.empty((t.size, 6))
    nfev = 0
    half = 0.5 * PERIOD
    for k in range(int(round(DURATION / half))):
        lo, hi = k * half, (k + 1) * half
        inside = (t >= lo) & ((t < hi) if k < int(round(DURATION / half)) - 1 else (t <= hi))
        sol = solve_ivp(rhs, (lo, hi), z, method=method, rtol=rtol, atol=atol, dense_output=True,
                        args=(1.0 if k % 2 == 0 else -1.0,))
        out[inside] = sol.sol(t[inside]).T
        nfev += sol.nfev
        z = sol.y[:, -1]
    return out, nfev


def errors(y: np.ndarray, theta: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    return {"y": float(np.max(np.abs(y - reference[:, 0]))),
            "theta": float(np.max(np.abs(theta - reference[:, 4:6])))}


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, dict[str, float]]:
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: {"median_s": statistics.median(v), "min_s": min(v), "repeats": repeat} for k, v in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, help="write the JSON here too")
    args = parser.parse_args()
    loaded = load_spec(SPEC)
    spec = loaded.spec.model_copy(update={"numerics": loaded.spec.numerics.model_copy(update={"compile": "always"})})
    design = synthesize(spec)
    t0 = time.perf_counter()
    sim = build(spec, design)
    first_build = time.perf_counter() - t0
    result = sim.run()
    t = np.asarray(result.time, dtype=float)
    y = np.asarray(result.state, dtype=float)[:, result.positions[0]]
    theta = np.column_stack([np.asarray(result.signals[n], dtype=float) for n in ("theta1", "theta2")])
    reference, _ = ivp(t, "DOP853", 1e-12, 1e-14)
    dk_err = errors(y, theta, reference)
    ladder = []
    for rtol in RTOL_LADDER:
        states, nfev = ivp(t, "RK45", rtol, 1e-3 * rtol)
        ladder.append({"rtol": rtol, "nfev": nfev, "errors": errors(states[:, 0], states[:, 4:6], reference)})
    ok = [row for row in ladder if all(row["errors"][k] <= dk_err[k] for k in dk_err)]
    chosen = min(ok, key=lambda row: row["nfev"]) if ok else ladder[-1]
    fns = {
        "designkit_run_warm": sim.run,
        "solve_ivp_rk45_matched": lambda: ivp(t, "RK45", chosen["rtol"], 1e-3 * chosen["rtol"]),
        "solve_ivp_dop853_1e-10": lambda: ivp(t, "DOP853", 1e-10, 1e-12),
    }
    timings = interleaved(fns, REPEAT)
    run_s = timings["designkit_run_warm"]["median_s"]
    out = {
        "scenario": {"spec": str(SPEC.name), "duration_s": DURATION, "grid_points": int(t.size),
                     "integrator": result.settings.get("integrator"), "dt_s": result.settings.get("dt")},
        "compiled": dict(sim.compiled),
        "first_build_s": first_build,
        "accuracy_vs_dop853_1e-12": {"designkit": dk_err, "solve_ivp_rk45_chosen": chosen},
        "final_theta": theta[-1].tolist(),
        "timings": timings,
        "ratios": {"rk45_matched_over_designkit": timings["solve_ivp_rk45_matched"]["median_s"] / run_s,
                   "dop853_over_designkit": timings["solve_ivp_dop853_1e-10"]["median_s"] / run_s},
        "goal": {"run_warm_s": GOAL_RUN_S, "met": bool(run_s <= GOAL_RUN_S)},
        "machine": {"python": platform.python_version(), "numpy": np.__version__,
                    "scipy": metadata.version("scipy"), "casadi": metadata.version("casadi"),
                    "load_average": list(__import__("os").getloadavg())},
    }
    text = json.dumps(out, indent=2)
    print(text)
    if args.out is not None:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
