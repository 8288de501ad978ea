"""Benchmark: the self-tuning regulator on the link, 20 s at a 1 kHz sample rate, warm.

Scenario: the link Km = 2, tau = 0.5 s; the regulator (speed measured, lambda = 0.99, P(0) = 100 I,
pole placement at -4, -5 1/s with the observer at -10 1/s) starts from a wrong nominal link (Km = 1,
tau = 1 s); a square wave of +-0.5 rad every 4 s; the link changes at t = 10 s (Km 2 -> 1).
``controller.sampling_period = 0.001`` and ``simulation.dt = 0.001``: 20,000 samples, each one
RLS update (2 x 2 covariance) and one Diophantine solve (the 3 x 3 Sylvester system, Cramer's rule)
inside the compiled step, plus one RK4 step of the link.  ``numerics: {compile: always}``.

Timed (``time.perf_counter``, median of interleaved repeats):

(a) ``Simulator.run()`` warm (the simulator built once, its step compiled to C or taken from the
    compiled-library cache) -- the goal is <= 50 ms;
(b) the same loop written here in NumPy (the exact ZOH model of the link per sample, ``np.linalg.solve``
    on the Sylvester matrix per sample): the baseline.

Before timing, the NumPy loop is checked against designkit's run (estimates and command at the samples).

Run: ``python benchmarks/bench_self_tuning.py [--out results.json]`` (prints the JSON; writes it only with ``--out``).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
from scipy.linalg import expm

from designkit.families import synthesize
from designkit.pipeline import plant as plant_of
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build

SPEC = """\
name: selftune-bench
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: self_tuning, sampling_period: 0.001, estimator: speed, forgetting: 0.99, initial_covariance: 100,
             poles: [-4, -5], observer: -10, nominal: {Km: 1.0, tau: 1.0}}
simulation:
  duration: 20
  dt: 0.001
  trajectory: {kind: square, amplitude: 0.5, period: 4}
  plant_change: {time: 10, values: {Km: 1.0}}
numerics: {compile: always}
"""
GOAL_RUN_S = 0.050
REPEAT = 15


def numpy_loop(t: np.ndarray, r: np.ndarray, st: Any) -> tuple[np.ndarray, np.ndarray]:
    """The regulator and the exactly sampled link in NumPy (dt = Ts): returns ``(theta, u)`` per sample."""
    Ts = st.Ts

    def zoh(Km: float, tau: float) -> tuple[np.ndarray, np.ndarray]:
        M = expm(np.array([[0, 1, 0], [0, -1 / tau, Km / tau], [0, 0, 0]]) * Ts)
        return M[:2, :2], M[:2, 2]

    before, after = zoh(2.0, 0.5), zoh(1.0, 0.5)
    c = st.desired()
    zo = np.exp(st.observer * Ts)
    am1 = (1 + c[0] + c[1] + c[2]) / (1 - zo)
    theta, P = np.array(st.theta0), st.P0 * np.eye(2)
    x = np.zeros(2)
    v1 = u1 = y1 = 0.0
    r1 = r[0]
    out_th, out_u = np.empty((len(t), 2)), np.empty(len(t))
    for k in range(len(t)):
        y, v = x
        if k == 0:
            v1, y1, r1 = v, y, r[0]
        else:
            phi = np.array([v1, u1])
            Pphi = P @ phi
            K = Pphi / (st.forgetting + phi @ Pphi)
            theta = theta + K * (v - phi @ theta)
            P = (P - np.outer(K, Pphi)) / st.forgetting
            P = 0.5 * (P + P.T)
            tr = np.trace(P)
            if tr > st.max_trace:
                P *= st.max_trace / tr
        a = theta[0]
        A12 = -Ts * (1 - a) / np.log(a)
        B1 = theta[1] / (1 - a) * (Ts - A12)
        a1, a2, b0, b1 = -(1 + a), a, B1, A12 * theta[1] - a * B1
        R1, S0, S1 = np.linalg.solve(np.array([[1, b0, 0], [a1, b1, b0], [a2, 0, b1]]),
                                     [c[0] - a1, c[1] - a2, c[2]])
        T0 = am1 / (b0 + b1)
        u = -R1 * u1 + T0 * (r[k] - zo * r1) - S0 * y - S1 * y1
        out_th[k], out_u[k] = theta, u
        A, B = before if t[k] < 10.0 - 1e-9 else after
        x = A @ x + B * u
        v1, y1, u1, r1 = v, y, u, r[k]
    return out_th, out_u


def interleaved(fns: dict[str, Any], repeat: int) -> dict[str, dict[str, float]]:
    times: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {name: {"median_s": statistics.median(v), "min_s": min(v), "repeats": len(v)} for name, v in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, help="write the JSON here too")
    args = parser.parse_args()
    loaded = parse_spec(SPEC)
    spec, true = loaded.spec, plant_of(loaded)
    design = synthesize(spec, true)
    t0 = time.perf_counter()
    sim = build(spec, design, plant=true)
    first_build = time.perf_counter() - t0
    result = sim.run()
    from designkit.families.self_tuning import settings_from
    from designkit.families.self_tuning.runs import samples

    st = settings_from(design)
    s = samples(result, design)
    ref = np.asarray(result.desired)[:, 0][np.searchsorted(np.asarray(result.time), s.t)]
    th_np, u_np = numpy_loop(s.t, ref, st)
    u_dk = np.asarray(result.u_command)[np.searchsorted(np.asarray(result.time), s.t), 0]
    diff_theta = float(np.max(np.abs(th_np - s.theta) / np.abs(th_np)))
    diff_u = float(np.max(np.abs(u_np - u_dk)) / np.max(np.abs(u_np)))
    timings = interleaved({"designkit_run_warm": sim.run, "numpy_loop": lambda: numpy_loop(s.t, ref, st)}, REPEAT)
    run_s = timings["designkit_run_warm"]["median_s"]
    out = {
        "scenario": {"spec": SPEC, "samples": len(s.t), "steps": int(len(result.time) - 1),
                     "dt_s": float(result.settings["dt"]), "sampling_period_s": st.Ts},
        "compiled": dict(sim.compiled),
        "first_build_s": first_build,
        "checks": {"numpy_vs_designkit_theta_max_rel_diff": diff_theta, "numpy_vs_designkit_u_max_rel_diff": diff_u},
        "timings": timings,
        "goal": {"run_s": GOAL_RUN_S, "met": bool(run_s <= GOAL_RUN_S)},
        "ratio_numpy_over_designkit": timings["numpy_loop"]["median_s"] / run_s,
        "machine": {"python": platform.python_version(), "machine": platform.machine(),
                    "casadi": metadata.version("casadi")},
        "summary": (f"Simulator.run() warm {1e3 * run_s:.1f} ms median for {len(s.t)} samples at 1 kHz with an RLS "
                    f"update and a Diophantine solve each (goal {1e3 * GOAL_RUN_S:.0f} ms: "
                    f"{'met' if run_s <= GOAL_RUN_S else 'not met'}), "
                    f"{'compiled' if sim.compiled.get('compiled') else 'interpreted'}; the NumPy loop "
                    f"{1e3 * timings['numpy_loop']['median_s']:.0f} ms"),
    }
    text = json.dumps(out, indent=2)
    print(text)
    if args.out is not None:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
