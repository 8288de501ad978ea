"""Benchmark: PUMA 560 computed torque, 10 s at 1 kHz on the full nonlinear arm, against ``solve_ivp``; and the
generated C of the law.

Scenario: the PUMA 560 of ``specs/puma560-computed-torque.yaml`` (designkit's ``puma560`` with joint friction,
viscous and Coulomb, and the reflected rotor inertias), computed torque with an exact model, damping 1 and
natural frequency 20 rad/s on every joint (K1 = 400 1/s^2, K2 = 40 1/s), the same quintic motion of all six
joints (3 s) from the table-top pose, simulated for 10 s at ``dt = 1 ms`` (10,000 classical RK4 steps).

Timed (``time.perf_counter``; medians of interleaved rounds, all in the same run):

(a) the default API path, ``designkit.simulation.run.build(spec, design).run()`` (``numerics.compile``
    default ``auto``), with a private code-generation cache that is empty at the start:

    * first run, cold cache: ``build`` (which generates and compiles the C of the rolled step, once) + ``run``;
    * first run, cached library, same process: ``build`` (looks the library up) + ``run``;
    * first run in a fresh Python process with the cache warm: imports, design, ``build`` and ``run``, each
      timed inside the child process;
    * warm: ``Simulator.run()`` on a built simulator (what a repeated simulation costs), and ``simulate()``
      (build + run) with the library cached;
    * for context, the interpreted step (``numerics.compile: never``).

(b) the baseline: ``scipy.integrate.solve_ivp`` (RK45, default tolerances ``rtol = 1e-3``, ``atol = 1e-6``,
    ``t_eval`` on the 1 ms grid) on a NumPy right-hand side built on the **same model**: the quintic
    reference in NumPy, the computed-torque law in NumPy calling the robot's CasADi ``inverse_dynamics``,
    the arm through the robot's CasADi ``forward_dynamics`` (each called from Python with NumPy arrays, as a
    user would); and the same right-hand side in a Python fixed-step RK4 loop (same scheme and steps as
    designkit).  Before timing, the NumPy right-hand side is compared with designkit's (``plant.ode`` and the
    law's ``command``) at random points, and the NumPy RK4 trajectory with designkit's.  With an exact model
    the exact solution is ``q(t) = qD(t)``, so every integrator's error is its ``max |q - qD|``; a DOP853 run at
    ``rtol = 1e-10`` is timed too, for an accuracy closer to designkit's.

(c) the generated C of the law (``designkit codegen SPEC``): ``<name>_command`` called from a small C harness
    compiled with the system C compiler (``-O2``; and ``-O3 -march=native``), on 1,024 states and references
    taken along the simulated trajectory, cycled; the harness's outputs are compared with the Python law.

Goals: (a) <= 100 ms, (b) >= 100x faster than ``solve_ivp``, (c) <= 1 us per evaluation; each
reported as met or not.

Run: ``python benchmarks/bench_computed_torque.py``; writes ``benchmarks/results/computed_torque.json``.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import scipy
from scipy.integrate import solve_ivp

from designkit.families import family
from designkit.models.codegen import find_compiler
from designkit.pipeline import design as pipeline_design
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build, simulate

RESULTS = Path(__file__).resolve().parent / "results" / "computed_torque.json"
SPEC = """\
name: puma560-ct-bench
plant: {kind: robot, robot: puma560, motor_inertia: true}
controller: {kind: computed_torque, damping: 1.0, natural_frequency: 20}
simulation:
  duration: 10.0
  dt: 0.001
  initial_position: [0, 0.785, -3.1416, 0, 0.785, 0]
  trajectory: {kind: quintic, amplitude: [1.0, 0.5, 0.8, 1.0, -0.8, 1.5], duration: 3.0}
"""
Q0 = np.array([0, 0.785, -3.1416, 0, 0.785, 0])
AMPLITUDE = np.array([1.0, 0.5, 0.8, 1.0, -0.8, 1.5])
MOVE_S = 3.0
GOAL_RUN_S = 0.100
GOAL_RATIO = 100.0
GOAL_C_US = 1.0
REPEAT = 15  # rounds of the warm designkit timings
REPEAT_BASELINE = 5  # rounds including the (slow) baselines
C_EVALUATIONS = 2_000_000
C_ROUNDS = 7
C_POOL = 1024
ROUTES = ("plain", "buffer")


# --------------------------------------------------------------------------- timing helpers


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, dict[str, Any]]:
    """Median and min wall time of each function, timed round-robin (one call of each per round)."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: {"median_s": statistics.median(v), "min_s": min(v), "repeats": repeat} for k, v in times.items()}


def clocked(fn: Callable[[], Any]) -> tuple[Any, float]:
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


# --------------------------------------------------------------------------- NumPy right-hand side (baseline)


def quintic(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The reference in NumPy: ``qD = q0 + A (10 s^3 - 15 s^4 + 6 s^5)``, ``s = clip(t / T, 0, 1)``, and its
    derivatives (zero outside the move)."""
    s = min(max(t / MOVE_S, 0.0), 1.0)
    pos = Q0 + AMPLITUDE * (10 * s**3 - 15 * s**4 + 6 * s**5)
    if not 0.0 < t / MOVE_S < 1.0:
        return pos, np.zeros(6), np.zeros(6)
    vel = AMPLITUDE * (30 * s**2 - 60 * s**3 + 30 * s**4) / MOVE_S
    acc = AMPLITUDE * (60 * s - 180 * s**2 + 120 * s**3) / MOVE_S**2
    return pos, vel, acc


def _buffered(f: ca.Function, arrays: list[np.ndarray], out: np.ndarray) -> Callable[[], None]:
    """``f`` evaluated through CasADi's zero-copy ``FunctionBuffer`` on fixed NumPy arrays (inputs, output)."""
    buf, evaluate = f.buffer()
    for k, a in enumerate(arrays):
        buf.set_arg(k, memoryview(a))
    buf.set_res(0, memoryview(out))
    evaluate.keep = (buf, arrays, out)  # type: ignore[attr-defined]  # the buffers must outlive the closure
    return evaluate


def numpy_closed_loop(design: Any, route: str) -> dict[str, Callable]:
    """Law and arm in NumPy around the robot's own CasADi functions, one state at a time.

    ``law(q, qd, t)``: ``a = qD'' + K1 (qD - q) + K2 (qD' - qd)``, ``u = inverse_dynamics(q, qd, a, p^)``;
    ``arm(q, qd, u)``: ``forward_dynamics(q, qd, u, p)``; ``rhs(t, s)`` of ``s = (q, qd)``.  ``route``:
    ``"plain"`` calls the Functions as a user does (``f(q, qd, a, p)`` with NumPy arrays, a ``DM`` back);
    ``"buffer"`` through CasADi's zero-copy ``FunctionBuffer`` (the cheapest call from Python).
    """
    robot = design.plant.robot
    inverse, forward = robot.functions["inverse_dynamics"], robot.functions["forward_dynamics"]
    p = np.asarray(design.plant.parameter_vector, dtype=float)  # exact model: the controller's = the arm's
    K1, K2 = (np.asarray(design.gains[k], dtype=float) for k in ("K1", "K2"))

    if route == "plain":
        def inverse_call(q: np.ndarray, qd: np.ndarray, a: np.ndarray) -> np.ndarray:
            return inverse(q, qd, a, p).full().ravel()

        def forward_call(q: np.ndarray, qd: np.ndarray, u: np.ndarray) -> np.ndarray:
            return forward(q, qd, u, p).full().ravel()
    else:
        q_b, qd_b, a_b, u_b, u_in, qdd_b = (np.zeros(6) for _ in range(6))
        inverse_eval = _buffered(inverse, [q_b, qd_b, a_b, p], u_b)
        forward_eval = _buffered(forward, [q_b, qd_b, u_in, p], qdd_b)

        def inverse_call(q: np.ndarray, qd: np.ndarray, a: np.ndarray) -> np.ndarray:
            q_b[:], qd_b[:], a_b[:] = q, qd, a
            inverse_eval()
            return u_b.copy()

        def forward_call(q: np.ndarray, qd: np.ndarray, u: np.ndarray) -> np.ndarray:
            q_b[:], qd_b[:], u_in[:] = q, qd, u
            forward_eval()
            return qdd_b.copy()

    def law(q: np.ndarray, qd: np.ndarray, t: float) -> np.ndarray:
        pos, vel, acc = quintic(t)
        return inverse_call(q, qd, acc + K1 * (pos - q) + K2 * (vel - qd))

    def rhs(t: float, s: np.ndarray) -> np.ndarray:
        q, qd = s[:6], s[6:]
        return np.concatenate([qd, forward_call(q, qd, law(q, qd, t))])

    return {"law": law, "arm": forward_call, "rhs": rhs}


def check_model(design: Any, model: dict[str, Callable], res: Any, rng: np.random.Generator, n: int = 300
                ) -> dict[str, float]:
    """Largest scaled differences of the NumPy reference, law and arm from designkit's."""
    plant = design.plant
    law = family(design.kind).law(design)
    ode = plant.ode()
    p = np.asarray(plant.parameter_vector, dtype=float)
    ref = np.array([np.stack(quintic(float(t)), axis=1) for t in res.time])  # (N, 6, 3)
    ref_diff = float(np.abs(ref - np.asarray(res.reference)).max())
    worst_rhs = worst_law = 0.0
    for _ in range(n):
        t = float(rng.uniform(0.0, 4.0))
        x = np.concatenate([Q0 + rng.uniform(-0.5, 0.5, 6), rng.uniform(-2.0, 2.0, 6)])
        r = np.concatenate(quintic(t))
        u_dk = law.command(x, np.zeros(0), np.zeros(0), r).full().ravel()
        u_np = model["law"](x[:6], x[6:], t)
        worst_law = max(worst_law, float(np.max(np.abs(u_np - u_dk) / (1 + np.abs(u_dk)))))
        xdot_dk = ode(x, u_dk, np.zeros(6), p).full().ravel()
        xdot_np = model["rhs"](t, x)
        worst_rhs = max(worst_rhs, float(np.max(np.abs(xdot_np - xdot_dk) / (1 + np.abs(xdot_dk)))))
    return {"points": n, "reference_max_abs_diff": ref_diff, "law_max_scaled_diff": worst_law,
            "rhs_max_scaled_diff": worst_rhs}


def numpy_rk4(rhs: Callable, t: np.ndarray, dt: float, s0: np.ndarray) -> np.ndarray:
    """Fixed-step classical RK4 of the NumPy closed loop, states at the instants ``t`` ``(N, 12)``."""
    out = np.empty((t.size, s0.size))
    s = s0.copy()
    h = 0.5 * dt
    for k in range(t.size):
        out[k] = s
        tk = float(t[k])
        k1 = rhs(tk, s)
        k2 = rhs(tk + h, s + h * k1)
        k3 = rhs(tk + h, s + h * k2)
        k4 = rhs(tk + dt, s + dt * k3)
        s = s + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return out


def ivp(rhs: Callable, t: np.ndarray, s0: np.ndarray, method: str = "RK45", **tol: float) -> Any:
    sol = solve_ivp(rhs, (float(t[0]), float(t[-1])), s0, method=method, t_eval=t, **tol)
    if not sol.success:
        raise RuntimeError(f"solve_ivp {method} {tol} failed: {sol.message}")
    return sol


def tracking_error(states: np.ndarray, reference: np.ndarray) -> float:
    """``max |q - qD|`` (rad): the error of an integrator, the exact solution being ``q = qD``."""
    return float(np.abs(states[:, :6] - reference[:, :, 0]).max())


# --------------------------------------------------------------------------- (a) the default path


CHILD = """\
import json, statistics, sys, time
t0 = time.perf_counter()
from designkit.pipeline import design
from designkit.simulation.run import build
from designkit.schema.loader import parse_spec
t1 = time.perf_counter()
loaded = parse_spec(sys.stdin.read())
d = design(loaded)
t2 = time.perf_counter()
sim = build(loaded.spec, d)
t3 = time.perf_counter()
sim.run()
t4 = time.perf_counter()
warm = []
for _ in range(5):
    a = time.perf_counter(); sim.run(); warm.append(time.perf_counter() - a)
print(json.dumps({"import_s": t1 - t0, "design_s": t2 - t1, "build_s": t3 - t2, "first_run_s": t4 - t3,
                  "first_total_s": t4 - t0, "build_plus_first_run_s": t4 - t2,
                  "warm_run_median_s": statistics.median(warm), "evaluation": dict(sim.compiled)}))
"""


def fresh_process() -> dict[str, Any]:
    """The first simulation in a new Python process, the code-generation cache already warm."""
    out = subprocess.run([sys.executable, "-c", CHILD], input=SPEC, capture_output=True, text=True, check=True,
                         env=os.environ.copy())
    return json.loads(out.stdout.strip().splitlines()[-1])


def default_path(loaded: Any) -> dict[str, Any]:
    spec = loaded.spec
    design, design_s = clocked(lambda: pipeline_design(loaded))
    sim, build_cold_s = clocked(lambda: build(spec, design))
    res, run_first_s = clocked(sim.run)
    sim2, build_cached_s = clocked(lambda: build(spec, design))
    _, run_first_cached_s = clocked(sim2.run)
    child = fresh_process()
    never = parse_spec(SPEC + "numerics: {compile: never}\n").spec
    sim_never, build_never_s = clocked(lambda: build(never, design))
    res_never = sim_never.run()
    fns = {"run": sim.run, "simulate": lambda: simulate(spec, design)}
    for fn in fns.values():
        fn()
    warm = interleaved(fns, REPEAT)
    interp = interleaved({"run_interpreted": sim_never.run}, 3)["run_interpreted"]
    states = np.hstack([res.state, res.controller_state])
    return {
        "design": design, "simulator": sim, "result": res,
        "figures": {
            "design_s": design_s,
            "first_run_cold_cache": {"build_s": build_cold_s, "run_s": run_first_s,
                                     "total_s": build_cold_s + run_first_s, "evaluation": dict(sim.compiled)},
            "first_run_cached_library": {"build_s": build_cached_s, "run_s": run_first_cached_s,
                                         "total_s": build_cached_s + run_first_cached_s,
                                         "evaluation": dict(sim2.compiled)},
            "fresh_process_cached_library": child,
            "warm_run": warm["run"],
            "warm_simulate_build_plus_run": warm["simulate"],
            "interpreted_run_numerics_compile_never": {**interp, "build_s": build_never_s,
                                                       "evaluation": dict(sim_never.compiled)},
            "compiled_equals_interpreted_bitwise": bool(np.array_equal(
                states, np.hstack([res_never.state, res_never.controller_state]))),
            "steps": int(res.time.size - 1), "dt_s": float(res.settings["dt"]),
            "integrator": res.settings["integrator"],
            "step_instructions": int(sim.step.n_instructions()),
            "max_abs_q_minus_qD_rad": tracking_error(res.state, np.asarray(res.reference)),
        },
    }


# --------------------------------------------------------------------------- (c) generated C


HARNESS = r"""
/* Timing harness: NAME_command on a pool of (y, r) samples read from a binary file, cycled. */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "HEADER"

#define NY NAME_N_Y
#define NR NAME_N_R
#define NU NAME_N_U

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc != 5) return 2;
    long pool = atol(argv[2]), evals = atol(argv[3]), rounds = atol(argv[4]);
    FILE *f = fopen(argv[1], "rb");
    if (!f) return 3;
    double *in = malloc(sizeof(double) * pool * (NY + NR));
    if (!in || fread(in, sizeof(double), pool * (NY + NR), f) != (size_t)(pool * (NY + NR))) return 4;
    fclose(f);
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    if (NAME_command_work(&sz_arg, &sz_res, &sz_iw, &sz_w)) return 5;
    const casadi_real **arg = malloc((sz_arg + 1) * sizeof *arg);
    casadi_real **res = malloc((sz_res + 1) * sizeof *res);
    casadi_int *iw = malloc((sz_iw + 1) * sizeof *iw);
    casadi_real *w = malloc((sz_w + 1) * sizeof *w);
    double *out = malloc(sizeof(double) * pool * NU);
    if (!arg || !res || !iw || !w || !out) return 6;
    int mem = NAME_command_checkout();
    /* the outputs of every sample once, for the comparison with the Python law */
    for (long k = 0; k < pool; ++k) {
        arg[0] = in + k * (NY + NR); arg[1] = NULL; arg[2] = NULL; arg[3] = arg[0] + NY; res[0] = out + k * NU;
        if (NAME_command(arg, res, iw, w, mem)) return 7;
    }
    double u[NU], sink = 0.0;
    printf("{\"u\": [");
    for (long k = 0; k < pool * NU; ++k) printf("%.17g%s", out[k], k + 1 < pool * NU ? ", " : "");
    printf("], \"ns_per_eval\": [");
    for (long j = 0; j < rounds; ++j) {
        double t0 = now();
        for (long k = 0; k < evals; ++k) {
            const double *s = in + (k % pool) * (NY + NR);
            arg[0] = s; arg[1] = NULL; arg[2] = NULL; arg[3] = s + NY; res[0] = u;
            NAME_command(arg, res, iw, w, mem);
            sink += u[k % NU];
        }
        double t1 = now();
        printf("%.6g%s", 1e9 * (t1 - t0) / evals, j + 1 < rounds ? ", " : "");
    }
    printf("], \"sink\": %.17g}\n", sink);
    NAME_command_release(mem);
    return 0;
}
"""


def generated_c(design: Any, res: Any, tmp: Path) -> dict[str, Any]:
    """``designkit codegen`` of the spec, then ``<name>_command`` timed from a C harness."""
    cc = find_compiler()
    if cc is None:
        return {"status": "no C compiler on PATH"}
    spec_file = tmp / "spec.yaml"
    spec_file.write_text(SPEC)
    out_dir = tmp / "codegen"
    cmd = [sys.executable, "-m", "designkit.cli", "codegen", str(spec_file), "--out", str(out_dir)]
    t0 = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True)
    codegen_s = time.perf_counter() - t0
    if run.returncode != 0:
        return {"status": f"designkit codegen exited {run.returncode}: {run.stderr.strip()}"}
    headers = sorted(out_dir.rglob("*.h"))
    header = headers[0]
    name = header.stem
    source = header.with_suffix(".c")
    harness = tmp / "harness.c"
    harness.write_text(HARNESS.replace("HEADER", header.name).replace("NAME", name))

    # the pool: states and references along the simulated trajectory, perturbed so the feedback acts
    rng = np.random.default_rng(0)
    idx = np.linspace(0, res.time.size - 1, C_POOL).astype(int)
    y = np.asarray(res.state)[idx] + rng.normal(0.0, 0.01, (C_POOL, 12))
    r = np.asarray(res.reference)[idx].transpose(0, 2, 1).reshape(C_POOL, 18)  # positions, velocities, accels
    pool = np.ascontiguousarray(np.hstack([y, r]), dtype=np.float64)
    data = tmp / "pool.bin"
    pool.tofile(data)
    law = family(design.kind).law(design)
    expected = np.array([law.command(pool[k, :12], np.zeros(0), np.zeros(0), pool[k, 12:]).full().ravel()
                         for k in range(C_POOL)])

    out: dict[str, Any] = {"status": "ok", "compiler": cc, "codegen_command_s": codegen_s, "symbol": f"{name}_command",
                           "source_bytes": source.stat().st_size, "pool": C_POOL, "evaluations": C_EVALUATIONS,
                           "rounds": C_ROUNDS, "command_instructions": int(law.command.n_instructions()),
                           "variants": {}}
    for label, flags in (("-O2", ["-O2"]), ("-O3 -march=native", ["-O3", "-march=native"])):
        exe = tmp / f"harness{len(out['variants'])}"
        t0 = time.perf_counter()
        comp = subprocess.run([cc, "-std=c99", *flags, f"-I{header.parent}", "-o", str(exe), str(harness),
                               str(source), "-lm"], capture_output=True, text=True)
        compile_s = time.perf_counter() - t0
        if comp.returncode != 0:
            out["variants"][label] = {"status": f"compile failed: {comp.stderr.strip()[:500]}"}
            continue
        got = json.loads(subprocess.run([str(exe), str(data), str(C_POOL), str(C_EVALUATIONS), str(C_ROUNDS)],
                                        capture_output=True, text=True, check=True).stdout)
        u = np.array(got["u"]).reshape(C_POOL, -1)
        ns = got["ns_per_eval"]
        out["variants"][label] = {
            "status": "ok", "compile_s": compile_s, "ns_per_eval_rounds": ns,
            "us_per_eval_median": 1e-3 * statistics.median(ns), "us_per_eval_min": 1e-3 * min(ns),
            "max_scaled_diff_vs_python_law": float(np.max(np.abs(u - expected) / (1 + np.abs(expected)))),
        }
    # the same law called from Python (interpreted CasADi, one call per state), for context
    s = pool[0]
    t_py = interleaved({"py": lambda: law.command(s[:12], np.zeros(0), np.zeros(0), s[12:])}, 2000)["py"]
    out["python_call_us"] = {"median": 1e6 * t_py["median_s"], "min": 1e6 * t_py["min_s"]}
    return out


# --------------------------------------------------------------------------- main


def main() -> None:
    # A private, empty code-generation cache: the default path's first run depends on what is cached.
    cache = tempfile.mkdtemp(prefix="ct-bench-cache-")
    tmp = Path(tempfile.mkdtemp(prefix="ct-bench-"))
    previous = os.environ.get("DESIGNKIT_CACHE_DIR")
    os.environ["DESIGNKIT_CACHE_DIR"] = cache
    try:
        measure(tmp)
    finally:
        if previous is None:
            os.environ.pop("DESIGNKIT_CACHE_DIR", None)
        else:
            os.environ["DESIGNKIT_CACHE_DIR"] = previous
        shutil.rmtree(cache, ignore_errors=True)
        shutil.rmtree(tmp, ignore_errors=True)


def measure(tmp: Path) -> None:
    load_start = os.getloadavg() if hasattr(os, "getloadavg") else None
    loaded = parse_spec(SPEC)

    # (a)
    a = default_path(loaded)
    design, sim, res, fig = a["design"], a["simulator"], a["result"], a["figures"]
    t, dt = res.time, fig["dt_s"]
    reference = np.asarray(res.reference)

    # (b) the same thing: reference, law, right-hand side (both call routes), then the same-scheme trajectory
    models = {route: numpy_closed_loop(design, route) for route in ROUTES}
    checks = {route: check_model(design, m, res, np.random.default_rng(0)) for route, m in models.items()}
    for c in checks.values():
        assert c["reference_max_abs_diff"] < 1e-12, c
        assert c["law_max_scaled_diff"] < 1e-12 and c["rhs_max_scaled_diff"] < 1e-12, c
    rhs = {route: m["rhs"] for route, m in models.items()}
    s0 = np.concatenate([Q0, np.zeros(6)])
    rk4_states, rk4_first_s = clocked(lambda: numpy_rk4(rhs["buffer"], t, dt, s0))
    rk4_diff = float(np.abs(rk4_states - res.state).max())
    assert rk4_diff < 1e-9, f"designkit and the NumPy RK4 disagree by {rk4_diff:g}"
    sols = {f"rk45_default_{route}": ivp(rhs[route], t, s0) for route in ROUTES}
    sols["dop853_rtol_1e-10_buffer"] = ivp(rhs["buffer"], t, s0, "DOP853", rtol=1e-10, atol=1e-12)
    base_fns: dict[str, Callable[[], Any]] = {"run": sim.run}
    for route in ROUTES:
        base_fns[f"rk45_default_{route}"] = lambda route=route: ivp(rhs[route], t, s0)
    base_fns["dop853_rtol_1e-10_buffer"] = lambda: ivp(rhs["buffer"], t, s0, "DOP853", rtol=1e-10, atol=1e-12)
    bt = interleaved(base_fns, REPEAT_BASELINE)
    rk4_loop = interleaved({"rk4": lambda: numpy_rk4(rhs["buffer"], t, dt, s0)}, 3)["rk4"]
    rhs_call = {route: interleaved({"rhs": lambda f=f: f(1.0, s0)}, 2000)["rhs"] for route, f in rhs.items()}
    run_med = fig["warm_run"]["median_s"]
    run_in_round = bt["run"]["median_s"]
    baseline: dict[str, Any] = {
        "what": "scipy.integrate.solve_ivp (t_eval on the 1 ms grid) on a NumPy right-hand side calling the robot's "
                "own CasADi inverse_dynamics (the law, at a* = qD'' + K1 e + K2 e') and forward_dynamics (the arm) "
                "from Python, one state at a time; the quintic reference in NumPy. Two call routes: 'plain' "
                "(f(q, qd, a, p) with NumPy arrays, as a user calls them) and 'buffer' (CasADi's zero-copy "
                "FunctionBuffer, the cheapest call from Python)",
        "run_in_the_same_rounds": bt["run"],
        "numpy_rk4_loop_buffer": {**rk4_loop, "first_run_s": rk4_first_s, "nfev": 4 * (t.size - 1),
                                  "max_abs_q_minus_qD_rad": tracking_error(rk4_states, reference),
                                  "max_abs_diff_vs_designkit": rk4_diff},
        "rhs_evaluation_us": {route: {"median": 1e6 * v["median_s"], "min": 1e6 * v["min_s"]}
                              for route, v in rhs_call.items()},
        "checks": checks,
    }
    for key, sol in sols.items():
        method = "RK45" if key.startswith("rk45") else "DOP853"
        tol = {"rtol": 1e-3, "atol": 1e-6} if method == "RK45" else {"rtol": 1e-10, "atol": 1e-12}
        baseline[key] = {**bt[key], "method": method, **tol, "nfev": int(sol.nfev),
                         "max_abs_q_minus_qD_rad": tracking_error(sol.y.T, reference)}
    ratios = {f"{key}_over_warm_run": bt[key]["median_s"] / run_in_round for key in sols}
    for route in ROUTES:
        base = bt[f"rk45_default_{route}"]["median_s"]
        ratios[f"rk45_default_{route}_over_warm_simulate"] = base / fig["warm_simulate_build_plus_run"]["median_s"]
        ratios[f"rk45_default_{route}_over_first_run_cached_library"] = base / fig["first_run_cached_library"][
            "total_s"]
        ratios[f"rk45_default_{route}_over_first_run_cold_cache"] = base / fig["first_run_cold_cache"]["total_s"]
    ratios["numpy_rk4_loop_buffer_over_warm_run"] = rk4_loop["median_s"] / run_med
    ratios["interpreted_run_over_warm_run"] = fig["interpreted_run_numerics_compile_never"]["median_s"] / run_med

    # (c)
    c = generated_c(design, res, tmp)
    c_us = c["variants"]["-O2"]["us_per_eval_median"] if c.get("status") == "ok" else None

    goals = {
        "warm_run_at_most_s": GOAL_RUN_S, "warm_run_met": run_med <= GOAL_RUN_S,
        "first_run_cold_cache_met": fig["first_run_cold_cache"]["total_s"] <= GOAL_RUN_S,
        "first_run_cached_library_met": fig["first_run_cached_library"]["total_s"] <= GOAL_RUN_S,
        "ratio_at_least": GOAL_RATIO,
        **{f"ratio_vs_rk45_{route}_met": ratios[f"rk45_default_{route}_over_warm_run"] >= GOAL_RATIO
           for route in ROUTES},
        "c_command_at_most_us": GOAL_C_US, "c_command_met": c_us is not None and c_us <= GOAL_C_US,
    }
    load_end = os.getloadavg() if hasattr(os, "getloadavg") else None
    results = {
        "benchmark": "computed_torque",
        "scenario": "PUMA 560 (friction, rotor inertias) under computed torque with an exact model, damping 1, "
                    "natural frequency 20 rad/s, quintic of all six joints in 3 s, 10 s at dt = 1 ms "
                    "(10,000 RK4 steps)",
        "spec": SPEC,
        "gains": design.gains.to_json(),
        "timing": f"time.perf_counter, median (and min) of interleaved rounds ({REPEAT} for the warm designkit "
                  f"figures, {REPEAT_BASELINE} with the baselines), same process and run; a shared machine: compare "
                  "within this file",
        "designkit": fig,
        "baseline": baseline,
        "ratios": ratios,
        "generated_c": c,
        "goal": goals,
        "where_the_time_goes": explain(fig, baseline, ratios),
        "machine": {"python": platform.python_version(), "platform": platform.platform(),
                    "processor": platform.processor() or platform.machine(), "cpu_count": os.cpu_count(),
                    "cpus_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
                    "load_average_start": load_start, "load_average_end": load_end},
        "versions": {"designkit": metadata.version("designkit"), "casadi": ca.__version__,
                     "numpy": np.__version__, "scipy": scipy.__version__},
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=2, default=str) + "\n")
    report(results)


def explain(fig: dict[str, Any], b: dict[str, Any], ra: dict[str, Any]) -> list[str]:
    """Why the figures are what they are, in words, from the measured numbers."""
    ms = 1e3
    n_dk = 4 * fig["steps"]
    rk45 = b["rk45_default_buffer"]
    us_dk = 1e6 * fig["warm_run"]["median_s"] / n_dk
    us_plain, us_buf = b["rhs_evaluation_us"]["plain"]["median"], b["rhs_evaluation_us"]["buffer"]["median"]
    cold, cached = fig["first_run_cold_cache"], fig["first_run_cached_library"]
    return [
        f"designkit's warm run is the compiled RK4 step: {n_dk} right-hand-side evaluations (10,000 steps x 4 "
        f"stages, {fig['step_instructions']} CasADi instructions per step) at {us_dk:.2f} us each "
        f"({ms * fig['warm_run']['median_s']:.0f} ms median, {ms * fig['warm_run']['min_s']:.0f} ms best); the "
        f"interpreted step costs {ra['interpreted_run_over_warm_run']:.0f}x more.",
        f"solve_ivp RK45 at its default tolerances takes {rk45['nfev']} evaluations for the whole 10 s "
        f"({n_dk / rk45['nfev']:.0f}x fewer; about {6e3 * 10.0 / rk45['nfev']:.0f} ms per step on average, "
        "6 evaluations each, for a smooth closed loop whose exact solution is the quintic itself); its error is "
        f"{rk45['max_abs_q_minus_qD_rad']:.1e} rad against designkit's "
        f"{fig['max_abs_q_minus_qD_rad']:.1e}. Per evaluation the NumPy right-hand side costs {us_plain:.0f} us "
        "with plain CasADi calls (the call overhead dominates: the same functions cost "
        f"{us_buf:.0f} us through FunctionBuffer), i.e. "
        f"{us_plain / us_dk:.0f}x and {us_buf / us_dk:.0f}x designkit's; the step count takes back "
        f"{n_dk / rk45['nfev']:.0f}x, hence {ra['rk45_default_plain_over_warm_run']:.1f}x and "
        f"{ra['rk45_default_buffer_over_warm_run']:.2f}x. 100x against RK45 at default tolerances would need "
        f"the 10,000 steps in {ms * rk45['median_s'] / 100:.1f} ms (buffer rhs), about "
        f"{1e9 * rk45['median_s'] / 100 / fig['steps']:.0f} ns per step: not reachable at 1 kHz with RK4; at "
        f"an accuracy close to designkit's (DOP853, rtol 1e-10) the ratio is "
        f"{ra['dop853_rtol_1e-10_buffer_over_warm_run']:.1f}x.",
        f"First runs: with a cold cache the build generates and compiles the C of the rolled step "
        f"({cold['build_s']:.1f} s, once per design and machine: the library is cached by content); with the "
        f"library cached the build still rebuilds the CasADi graph and generates the C source to hash it "
        f"({ms * cached['build_s']:.0f} ms), and its first run is slower than the warm ones "
        f"({ms * cached['run_s']:.0f} ms against {ms * fig['warm_run']['median_s']:.0f} ms median).",
    ]


def _met(ok: bool) -> str:
    return "met" if ok else "NOT met"


def report(r: dict[str, Any]) -> None:
    ms = 1e3
    d, b, ra, c, g = r["designkit"], r["baseline"], r["ratios"], r["generated_c"], r["goal"]
    cold, cached, child = d["first_run_cold_cache"], d["first_run_cached_library"], d["fresh_process_cached_library"]
    rk4 = b["numpy_rk4_loop_buffer"]
    print("| PUMA 560 computed torque, 10 s at 1 kHz (10,000 RK4 steps) | time | max abs(q - qD) | goal |")
    print("|---|---|---|---|")
    print(f"| (a) warm `Simulator.run()` (compiled step, library cached) | {ms * d['warm_run']['median_s']:.1f} ms "
          f"(best {ms * d['warm_run']['min_s']:.1f}) | {d['max_abs_q_minus_qD_rad']:.1e} rad | <= 100 ms: "
          f"{_met(g['warm_run_met'])} |")
    print(f"| (a) warm `simulate()` (build + run, library cached) | "
          f"{ms * d['warm_simulate_build_plus_run']['median_s']:.0f} ms | | |")
    print(f"| (a) first run, cold cache: build (C generated + compiled) + run | {cold['total_s']:.2f} s "
          f"(build {cold['build_s']:.2f} s, run {ms * cold['run_s']:.0f} ms) | | <= 100 ms: "
          f"{_met(g['first_run_cold_cache_met'])} |")
    print(f"| (a) first run, cached library, same process: build + run | {ms * cached['total_s']:.0f} ms "
          f"(build {ms * cached['build_s']:.0f}, run {ms * cached['run_s']:.0f}) | | <= 100 ms: "
          f"{_met(g['first_run_cached_library_met'])} |")
    print(f"| (a) fresh process, cached library: imports / design / build / first run | "
          f"{child['import_s']:.2f} s / {child['design_s']:.2f} s / {ms * child['build_s']:.0f} ms / "
          f"{ms * child['first_run_s']:.0f} ms | | |")
    print(f"| (a) interpreted step (`numerics.compile: never`), for context | "
          f"{ms * d['interpreted_run_numerics_compile_never']['median_s']:.0f} ms | | |")
    for route in ROUTES:
        v = b[f"rk45_default_{route}"]
        ratio = ra[f"rk45_default_{route}_over_warm_run"]
        print(f"| (b) solve_ivp RK45 default tolerances, NumPy rhs, {route} CasADi calls | {ms * v['median_s']:.0f} ms "
              f"(nfev {v['nfev']}) | {v['max_abs_q_minus_qD_rad']:.1e} rad | >= 100x: {ratio:.2f}x, "
              f"{_met(g[f'ratio_vs_rk45_{route}_met'])} |")
    v = b["dop853_rtol_1e-10_buffer"]
    print(f"| (b) solve_ivp DOP853 rtol 1e-10, buffer calls | {ms * v['median_s']:.0f} ms (nfev {v['nfev']}) | "
          f"{v['max_abs_q_minus_qD_rad']:.1e} rad | {ra['dop853_rtol_1e-10_buffer_over_warm_run']:.1f}x |")
    print(f"| (b) NumPy fixed-step RK4 loop, buffer calls, same steps | {ms * rk4['median_s']:.0f} ms (nfev "
          f"{rk4['nfev']}) | {rk4['max_abs_q_minus_qD_rad']:.1e} rad | "
          f"{ra['numpy_rk4_loop_buffer_over_warm_run']:.1f}x |")
    if c.get("status") == "ok":
        for label, v in c["variants"].items():
            if v.get("status") != "ok":
                print(f"| (c) C `{c['symbol']}`, cc {label} | {v['status']} | | |")
                continue
            goal = f"<= 1 us: {_met(v['us_per_eval_median'] <= GOAL_C_US)}"
            print(f"| (c) C `{c['symbol']}` per evaluation, cc {label} | {1e3 * v['us_per_eval_median']:.0f} ns "
                  f"(best {1e3 * v['us_per_eval_min']:.0f}) | vs Python law {v['max_scaled_diff_vs_python_law']:.1e} "
                  f"(scaled) | {goal} |")
        print(f"| (c) the same law called from Python (plain call, interpreted CasADi) | "
              f"{c['python_call_us']['median']:.1f} us | | |")
    else:
        print(f"| (c) generated C | {c.get('status')} | | |")
    for route in ROUTES:
        print(f"ratio RK45 default ({route} calls) / designkit: "
              f"{ra[f'rk45_default_{route}_over_warm_run']:.2f}x warm run, "
              f"{ra[f'rk45_default_{route}_over_warm_simulate']:.2f}x warm simulate(), "
              f"{ra[f'rk45_default_{route}_over_first_run_cached_library']:.2f}x first run with a cached library, "
              f"{ra[f'rk45_default_{route}_over_first_run_cold_cache']:.3f}x first run with a cold cache")
    rhs_us = b["rhs_evaluation_us"]
    print(f"per right-hand-side evaluation: NumPy rhs {rhs_us['plain']['median']:.1f} us (plain calls), "
          f"{rhs_us['buffer']['median']:.1f} us (buffer calls); designkit "
          f"{1e6 * d['warm_run']['median_s'] / (4 * d['steps']):.2f} us (a {d['step_instructions']}-instruction RK4 "
          f"step, 4 evaluations); RK45 needs {b['rk45_default_buffer']['nfev']} evaluations, designkit "
          f"{4 * d['steps']}. Compiled step equals interpreted bitwise: {d['compiled_equals_interpreted_bitwise']}")
    chk = b["checks"]
    print(f"same thing timed: NumPy rhs vs designkit (scaled) plain {chk['plain']['rhs_max_scaled_diff']:.1e}, "
          f"buffer {chk['buffer']['rhs_max_scaled_diff']:.1e}; law {chk['plain']['law_max_scaled_diff']:.1e}; "
          f"NumPy RK4 vs designkit trajectory {rk4['max_abs_diff_vs_designkit']:.1e} rad")
    for line in r["where_the_time_goes"]:
        print(f"- {line}")
    print(f"load average start {r['machine']['load_average_start']}, end {r['machine']['load_average_end']} "
          f"({r['machine']['cpus_usable']} CPUs usable)")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
