"""Benchmark: the MRAC on the link, 20 s at a 1 ms step with its sensitivity states, against ``solve_ivp``.

Scenario (the notes' MRAC simulator, ``specs/mrac-link.yaml`` shortened): the link Km = 2, tau = 0.5 s
under the adaptive PD servo (poles -4, -5 1/s; gamma = 1e4; Q = diag(1, 0.1)), a square wave of
+-0.5 rad every 4 s, the link's gain halving at t = 10 s; 20 s at ``dt = 1 ms`` (20,000 RK4 steps of
10 states: the link, the reference model, four sensitivities and the two adapted parameters),
``numerics: {compile: always}``.

Timed (``time.perf_counter``, median of interleaved repeats, all in the same run):

(a) ``Simulator.run()`` warm: the simulator built once (its step compiled to C, or taken from the
    compiled-library cache), what a repeated simulation costs -- the goal is <= 20 ms;
(b) ``build`` + ``run`` end to end with the compiled library already cached;
(c) the baseline: ``scipy.integrate.solve_ivp`` on a NumPy right-hand side of the same ODE written
    here from the notes (the sensitivity filters derived by hand from the reference model, not
    CasADi's), integrated piece by piece between the reference's jumps and the plant change (kinder
    to scipy than one call across the discontinuities), sampled on the 1 ms grid.  At matched
    accuracy: every trajectory is compared with a DOP853 solution at ``rtol = 1e-12``; of a ladder
    of RK45 tolerances the cheapest whose errors (position, adapted parameters) do not exceed
    designkit's RK4 errors is timed;
(d) a fixed-step NumPy RK4 loop of the same right-hand side (same scheme, same steps).

Before timing, the NumPy right-hand side is checked against designkit's closed loop (the loop
function of :mod:`designkit.synthesis.closed_loop`) at random points.

Run: ``python benchmarks/bench_mrac.py [--out results.json]`` (prints the JSON; writes it only with ``--out``).
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
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from designkit.synthesis.closed_loop import loop_functions

SPEC = """\
name: mrac-bench
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: mrac, poles: [-4, -5], gamma: 10000, Q: [1, 0.1]}
simulation:
  duration: 20
  dt: 0.001
  trajectory: {kind: square, amplitude: 0.5, period: 4}
  plant_change: {time: 10, values: {Km: 1.0}}
numerics: {compile: always}
"""
A, NOMINAL, GAMMA, Q = (20.0, 9.0), (2.0, 0.5), (1e4, 1e4), np.diag([1.0, 0.1])
TAU, KM, KM_AFTER, T_CHANGE, AMPLITUDE, PERIOD = 0.5, 2.0, 1.0, 10.0, 0.5, 4.0
GOAL_RUN_S = 0.020
REPEAT = 15
REFERENCE_TOL = (1e-12, 1e-14)
RTOL_LADDER = tuple(10.0 ** (-k / 2) for k in range(4, 21))  # 1e-2 .. 1e-10, half decades


def rhs(s: np.ndarray, Km: float, r: float) -> np.ndarray:
    """The MRAC loop from the notes, ``s = (x1, x2, y1, y2, dy1/da1, dy2/da1, dy1/da2, dy2/da2, a1, a2)``."""
    x1, x2, y1, y2, s11, s21, s12, s22, al1, al2 = s
    a1, a2 = A
    K1, K2 = NOMINAL[1] * al1 / NOMINAL[0], (NOMINAL[1] * al2 - 1.0) / NOMINAL[0]
    u = -K1 * (x1 - r) - K2 * x2
    e1, e2 = y1 - x1, y2 - x2
    qe1, qe2 = Q[0, 0] * e1 + Q[0, 1] * e2, Q[1, 0] * e1 + Q[1, 1] * e2
    return np.array([x2, -x2 / TAU + Km / TAU * u, y2, -a1 * y1 - a2 * y2 + a1 * r,
                     s21, -a1 * s11 - a2 * s21 + (r - y1), s22, -a1 * s12 - a2 * s22 - y2,
                     GAMMA[0] * (s11 * qe1 + s21 * qe2), GAMMA[1] * (s12 * qe1 + s22 * qe2)])


def segments(t_end: float) -> list[tuple[float, float, float, float]]:
    """``(start, end, Km, r)`` of the pieces between the reference's jumps and the plant change."""
    edges = sorted({*(k * 0.5 * PERIOD for k in range(int(t_end / (0.5 * PERIOD)) + 1)), T_CHANGE, t_end})
    out = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        mid = 0.5 * (lo + hi)
        out.append((lo, hi, KM_AFTER if mid >= T_CHANGE else KM, AMPLITUDE if mid % PERIOD < 0.5 * PERIOD else
                    -AMPLITUDE))
    return out


def ivp(t: np.ndarray, method: str, rtol: float, atol: float) -> tuple[np.ndarray, int]:
    """``solve_ivp`` piece by piece, sampled on ``t``; returns the states and the number of evaluations."""
    s = np.array([0.0] * 8 + list(A))
    out = np.empty((t.size, 10))
    nfev = 0
    for lo, hi, Km, r in segments(float(t[-1])):
        inside = (t >= lo - 1e-12) & (t <= hi + 1e-12)
        sol = solve_ivp(lambda _t, z, Km=Km, r=r: rhs(z, Km, r), (lo, hi), s, method=method, rtol=rtol, atol=atol,
                        dense_output=True)
        if not sol.success:
            raise RuntimeError(f"solve_ivp {method} rtol={rtol:g}: {sol.message}")
        out[inside] = sol.sol(t[inside]).T
        nfev += sol.nfev
        s = sol.y[:, -1]
    return out, nfev


def numpy_rk4(t: np.ndarray) -> np.ndarray:
    """Fixed-step RK4 of the NumPy loop on the grid (the reference sampled as designkit's step does)."""
    dt = float(t[1] - t[0])
    s = np.array([0.0] * 8 + list(A))
    out = np.empty((t.size, 10))

    def level(tk: float) -> float:
        return AMPLITUDE if (tk % PERIOD) < 0.5 * PERIOD - 1e-12 else -AMPLITUDE

    for k, tk in enumerate(t):
        out[k] = s
        Km = KM_AFTER if tk >= T_CHANGE - 1e-9 * dt else KM
        r0, rm, r1 = level(tk), level(tk + 0.5 * dt), level(tk + dt)
        k1 = rhs(s, Km, r0)
        k2 = rhs(s + 0.5 * dt * k1, Km, rm)
        k3 = rhs(s + 0.5 * dt * k2, Km, rm)
        k4 = rhs(s + dt * k3, Km, r1)
        s = s + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return out


def errors(states: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    """Largest absolute errors on the grid: link position (rad) and adapted parameters (1/s^2, 1/s)."""
    e = np.abs(states - reference).max(axis=0)
    return {"position_rad": float(e[0]), "a1": float(e[8]), "a2": float(e[9])}


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, dict[str, float]]:
    """Median and min wall time of each function, timed round-robin."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: {"median_s": statistics.median(v), "min_s": min(v), "repeats": repeat} for k, v in times.items()}


def check_rhs(design: Any, rng: np.random.Generator, n: int = 300) -> float:
    """Largest relative difference of the NumPy right-hand side from designkit's closed loop at random points."""
    fns = loop_functions(design.plant, design.law)
    worst = 0.0
    for _ in range(n):
        z = rng.uniform(-1, 1, 10) * np.array([1, 3, 1, 3, 0.05, 0.2, 0.05, 0.2, 0, 0]) + np.array([0] * 8 + [30, 12])
        r, Km = rng.uniform(-1, 1), rng.choice([KM, KM_AFTER])
        theirs = np.asarray(fns.loop(z, [r, 0, 0], [0.0], [Km, TAU])[0], dtype=float).ravel()
        ours = rhs(z, Km, r)
        worst = max(worst, float(np.abs(ours - theirs).max() / max(1.0, np.abs(theirs).max())))
    return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, help="write the JSON here too")
    args = parser.parse_args()
    spec = parse_spec(SPEC).spec
    design = synthesize(spec)
    t0 = time.perf_counter()
    sim = build(spec, design)
    first_build = time.perf_counter() - t0
    result = sim.run()
    t = np.asarray(result.time)
    ours = np.hstack([result.state, result.controller_state])
    rng = np.random.default_rng(0)
    rhs_diff = check_rhs(design, rng)
    same_scheme = float(np.abs(numpy_rk4(t) - ours).max())

    reference, _ = ivp(t, "DOP853", *REFERENCE_TOL)
    dk_err = errors(ours, reference)
    ladder = []
    for rtol in RTOL_LADDER:
        states, nfev = ivp(t, "RK45", rtol, 1e-3 * rtol)
        ladder.append({"rtol": rtol, "atol": 1e-3 * rtol, "nfev": nfev, "errors": errors(states, reference)})
    ok = [row for row in ladder if all(row["errors"][k] <= dk_err[k] for k in dk_err)]
    chosen = min(ok, key=lambda row: row["nfev"]) if ok else ladder[-1]

    fns = {
        "designkit_run_warm": sim.run,
        "designkit_build_and_run_cached": lambda: build(spec, design).run(),
        "solve_ivp_rk45_matched": lambda: ivp(t, "RK45", chosen["rtol"], chosen["atol"]),
        "numpy_rk4_same_scheme": lambda: numpy_rk4(t),
    }
    timings = interleaved(fns, REPEAT)
    run_s = timings["designkit_run_warm"]["median_s"]
    base_s = timings["solve_ivp_rk45_matched"]["median_s"]
    out = {
        "scenario": {"spec": SPEC, "steps": int(t.size - 1), "dt_s": float(result.settings["dt"]), "states": 10},
        "compiled": dict(sim.compiled),
        "first_build_s": first_build,
        "checks": {"numpy_rhs_vs_designkit_max_rel_diff": rhs_diff,
                   "numpy_rk4_vs_designkit_max_abs_diff": same_scheme},
        "accuracy_vs_dop853_1e-12": {"designkit_rk4": dk_err, "solve_ivp_chosen": chosen, "ladder": ladder},
        "timings": timings,
        "goal": {"run_s": GOAL_RUN_S, "met": bool(run_s <= GOAL_RUN_S)},
        "ratio_solve_ivp_over_designkit": base_s / run_s,
        "ratio_numpy_rk4_over_designkit": timings["numpy_rk4_same_scheme"]["median_s"] / run_s,
        "machine": {"python": platform.python_version(), "machine": platform.machine(),
                    "casadi": metadata.version("casadi"), "scipy": metadata.version("scipy")},
        "summary": (f"Simulator.run() warm {1e3 * run_s:.1f} ms median (goal {1e3 * GOAL_RUN_S:.0f} ms: "
                    f"{'met' if run_s <= GOAL_RUN_S else 'not met'}), "
                    f"{'compiled' if sim.compiled.get('compiled') else 'interpreted'}; "
                    f"solve_ivp RK45 at matched accuracy (rtol {chosen['rtol']:.3g}, {chosen['nfev']} evaluations) "
                    f"{1e3 * base_s:.1f} ms: {base_s / run_s:.0f} x; NumPy RK4 "
                    f"{1e3 * timings['numpy_rk4_same_scheme']['median_s']:.0f} ms"),
    }
    text = json.dumps(out, indent=2)
    print(text)
    if args.out is not None:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
