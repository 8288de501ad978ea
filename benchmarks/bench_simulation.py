"""Benchmark: ``designkit.simulation.run.simulate`` against a plain-Python RK4 loop, same run.

Scenario: the POSSPEED link (Km 2, tau 0.5) under the PID servo with poles (-4, -5, -20) 1/s and
zero -3 1/s, a unit step and an actuator saturation at 20 N*m, default step dt = 1 ms.  The
baseline integrates the same closed loop with the same RK4 scheme (saturated law evaluated in
every stage) in a Python ``for`` loop, once over floats (hand-specialised, the fastest plain
Python) and once over NumPy vectors (the generic way); the trajectories (position, and the
commanded and applied controls, columns of the 2-D ``u_command``/``u_applied`` of
``SimulationResult``) are compared to make sure the same thing is timed.  ``simulate`` is timed
end to end (building the CasADi Functions included), and ``Simulator.run()`` alone (``build``
once, then run: what a repeated simulation costs), for several durations.

designkit runs with a private, initially empty code-generation cache (``DESIGNKIT_CACHE_DIR``), so
that the figures do not depend on which compiled steps happen to be cached on the machine; the
evaluation designkit chose (interpreted or compiled, and why) is recorded per row.

Run: ``python benchmarks/bench_simulation.py``; writes ``benchmarks/results/simulation.json``.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import casadi
import numpy as np

from designkit.families import synthesize
from designkit.schema.spec import Spec
from designkit.simulation.run import build, simulate

RESULTS = Path(__file__).resolve().parent / "results" / "simulation.json"
LIMIT = 20.0
DURATIONS = (4.0, 40.0)


def posspeed_spec(duration: float) -> Spec:
    return Spec.model_validate({
        "name": "posspeed-saturation-bench",
        "plant": {"kind": "link", "Km": 2.0, "tau": 0.5},
        "controller": {"kind": "pid_servo", "poles": [-4, -5, -20], "zero": -3},
        "simulation": {"duration": duration, "step": 1.0, "nonlinearity": {"kind": "saturation", "limit": LIMIT}},
    })


def python_loop(gains: dict[str, float], Km: float, tau: float, xD: float, dt: float,
                n: int) -> tuple[np.ndarray, np.ndarray]:
    """Plain-Python RK4 of the same saturated closed loop; positions and commands at the n recorded instants."""
    K1, K2, K3, K4 = gains["K1"], gains["K2"], gains["K3"], gains["K4"]
    a, b, ff = 1.0 / tau, Km / tau, K3 * K4 * xD

    def f(x1: float, x2: float, x3: float) -> tuple[float, float, float, float]:
        """(x1', x2', x3', command before the saturation)."""
        u = -K1 * (x1 - xD) - K2 * x2 - K3 * x3 + ff
        return x2, -a * x2 + b * min(max(u, -LIMIT), LIMIT), x1 - xD, u

    x1 = x2 = x3 = 0.0
    out = [0.0] * n
    cmd = [0.0] * n
    h = 0.5 * dt
    for k in range(n):
        out[k] = x1
        k1 = f(x1, x2, x3)
        cmd[k] = k1[3]
        k2 = f(x1 + h * k1[0], x2 + h * k1[1], x3 + h * k1[2])
        k3 = f(x1 + h * k2[0], x2 + h * k2[1], x3 + h * k2[2])
        k4 = f(x1 + dt * k3[0], x2 + dt * k3[1], x3 + dt * k3[2])
        x1 += dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
        x2 += dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
        x3 += dt / 6.0 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
    return np.array(out), np.array(cmd)


def numpy_loop(gains: dict[str, float], Km: float, tau: float, xD: float, dt: float, n: int) -> np.ndarray:
    """The same loop written the generic way, on NumPy state vectors (x1, x2, x3)."""
    K = np.array([gains["K1"], gains["K2"], gains["K3"]])
    A = np.array([[0.0, 1.0, 0.0], [0.0, -1.0 / tau, 0.0], [1.0, 0.0, 0.0]])
    B = np.array([0.0, Km / tau, 0.0])
    offset = np.array([xD, 0.0, 0.0])
    ff = gains["K3"] * gains["K4"] * xD

    def f(x: np.ndarray) -> np.ndarray:
        u = np.clip(-K @ (x - offset) + ff, -LIMIT, LIMIT)
        return A @ x + B * u - np.array([0.0, 0.0, xD])

    x = np.zeros(3)
    out = np.empty(n)
    for k in range(n):
        out[k] = x[0]
        k1 = f(x)
        k2 = f(x + 0.5 * dt * k1)
        k3 = f(x + 0.5 * dt * k2)
        k4 = f(x + dt * k3)
        x = x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return out


def gains_of(design) -> dict[str, float]:
    """The PID servo's scalar gains K1..K4."""
    return {k: float(design.gains[k]) for k in ("K1", "K2", "K3", "K4")}


def best_of(fn, repeat: int) -> tuple[float, float, object]:
    """Best and median wall time of ``repeat`` calls, and the last value."""
    times, value = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - t0)
    return min(times), statistics.median(times), value


def evaluation_of(sim) -> object:
    """How designkit evaluates the steps (interpreted or compiled, and why), when it says so."""
    info = getattr(sim, "compiled", None) or sim.settings.get("compiled")
    return json.loads(json.dumps(info, default=str)) if info else None


def main() -> None:
    # a private, empty code-generation cache: what designkit runs may depend on what is cached
    cache = tempfile.mkdtemp(prefix="bench-simulation-cache-")
    previous = os.environ.get("DESIGNKIT_CACHE_DIR")
    os.environ["DESIGNKIT_CACHE_DIR"] = cache
    try:
        measure()
    finally:
        if previous is None:
            os.environ.pop("DESIGNKIT_CACHE_DIR", None)
        else:
            os.environ["DESIGNKIT_CACHE_DIR"] = previous
        shutil.rmtree(cache, ignore_errors=True)


def measure() -> None:
    rows = []
    for duration in DURATIONS:
        spec = posspeed_spec(duration)
        design = synthesize(spec)
        simulate(spec, design)  # warm-up (imports, first CasADi construction)
        t_sim, med_sim, res = best_of(lambda spec=spec, design=design: simulate(spec, design), 7)
        sim = build(spec, design)
        sim.run()
        t_run, med_run, _ = best_of(sim.run, 7)
        dt, n = res.settings["dt"], res.time.size
        assert res.u_command.shape == (n, 1) and res.u_applied.shape == (n, 1), res.u_command.shape
        assert res.reference.shape == (n, 1, 3) and res.position.shape == (n,)
        assert np.all(res.reference[:, 0, 0] == 1.0)
        t_py, med_py, (x_py, u_py) = best_of(
            lambda design=design, dt=dt, n=n: python_loop(gains_of(design), 2.0, 0.5, 1.0, dt, n), 3
        )
        t_np, med_np, x_np = best_of(
            lambda design=design, dt=dt, n=n: numpy_loop(gains_of(design), 2.0, 0.5, 1.0, dt, n), 3
        )
        diff = float(np.max(np.abs(res.position - x_py)))
        diff_np = float(np.max(np.abs(res.position - x_np)))
        assert max(diff, diff_np) < 1e-9, f"the simulations disagree by {max(diff, diff_np):g} rad"
        du_cmd = float(np.max(np.abs(res.u_command[:, 0] - u_py)))
        du_app = float(np.max(np.abs(res.u_applied[:, 0] - np.clip(u_py, -LIMIT, LIMIT))))
        assert max(du_cmd, du_app) < 1e-6, f"the controls disagree by {max(du_cmd, du_app):g} N*m"
        rows.append({
            "duration_s": duration, "dt_s": dt, "steps": n - 1, "evaluation": evaluation_of(sim),
            "simulate_best_s": t_sim, "simulate_median_s": med_sim,
            "run_best_s": t_run, "run_median_s": med_run,
            "python_loop_best_s": t_py, "python_loop_median_s": med_py,
            "numpy_loop_best_s": t_np, "numpy_loop_median_s": med_np,
            "speedup_vs_python_best": t_py / t_sim, "speedup_vs_numpy_best": t_np / t_sim,
            "speedup_run_vs_python_best": t_py / t_run, "speedup_run_vs_numpy_best": t_np / t_run,
            "max_position_difference_rad": max(diff, diff_np),
            "max_control_difference_Nm": {"u_command": du_cmd, "u_applied": du_app},
            "us_per_step_simulate": 1e6 * t_sim / (n - 1), "us_per_step_python": 1e6 * t_py / (n - 1),
            "us_per_step_numpy": 1e6 * t_np / (n - 1), "us_per_step_run": 1e6 * t_run / (n - 1),
        })
        print(f"| simulate POSSPEED + saturation, {n - 1} RK4 steps | designkit {1e3 * t_sim:.1f} ms "
              f"(run() alone {1e3 * t_run:.1f} ms) | Python floats loop {1e3 * t_py:.1f} ms ({t_py / t_sim:.1f}x; "
              f"{t_py / t_run:.1f}x vs run) | NumPy loop {1e3 * t_np:.1f} ms ({t_np / t_sim:.1f}x; "
              f"{t_np / t_run:.1f}x vs run) | max |dx1| {max(diff, diff_np):.1e} rad |")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps({
        "benchmark": "simulation", "scenario": "POSSPEED Km 2, tau 0.5, poles -4 -5 -20, zero -3, step 1 rad, "
                                               f"saturation {LIMIT:g} N*m",
        "baselines": "plain-Python RK4 loops, same scheme and law, measured in the same run: over Python "
                     "floats (hand-specialised) and over NumPy state vectors (generic)",
        "timing": "best of 7 (simulate, end to end incl. CasADi construction; Simulator.run alone) and best of 3 "
                  "(loops); medians also given. The machine was shared with other jobs: expect noise",
        "rows": rows,
        "machine": {"python": platform.python_version(), "platform": platform.platform(),
                    "processor": platform.processor() or platform.machine(), "cpu_count": os.cpu_count()},
        "versions": {"casadi": casadi.__version__, "numpy": np.__version__},
    }, indent=2) + "\n")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
