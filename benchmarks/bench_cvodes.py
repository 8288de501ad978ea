"""Benchmark: CVODES over the whole grid (``numerics.integrator: cvodes`` on a smooth loop) against the compiled
Dormand--Prince pair (the default of a smooth loop) and against the per-step CVODES, the path of a loop held per
step (goal: cvodes within 3x of the RK pair on smooth loops).

Scenarios (those of ``bench_floor.py``):

* **PUMA computed torque**, ``specs/puma560-computed-torque.yaml`` (six joints, exact model, the quintic of 3 s, 4 s
  at 1 ms).  Error: ``max |q - qD|`` (the exact solution is ``q = qD``).
* **SIMNOG** (``bench_simnog.SPEC``: the two-link arm under decentralized PID, a step, 10 s at 1 ms).  Error: the
  positions against scipy's DOP853 at ``rtol = 2.5e-14``, ``atol = 1e-16`` on ``bench_simnog``'s NumPy closed loop.

Runs, in one process, interleaved rounds (one call of each per round; medians and minima):

* ``dopri5``: the default run (``Simulator.run``, rtol 1e-10, atol 1e-12);
* ``cvodes``: the whole-grid CVODES (``Simulator.run`` on ``numerics.integrator: cvodes``, its method chosen by
  ``numerics.cvodes_method: auto``) at **matched accuracy**: of a ladder of tolerances (``rtol`` 1e-6 .. 1e-12 in
  half decades, ``atol = rtol / 100`` or ``rtol``), the fastest (median of three runs) whose error does not exceed
  the pair's;
* ``cvodes_other_iteration``: the same with the other nonlinear iteration of Adams (fixed-point against Newton):
  the evidence behind :data:`designkit.simulation.cvodes_grid.FIXED_POINT_RATIO`;
* ``cvodes_interpreted``: the same on CasADi's interpreted functions (``numerics.compile: never``): what compiling
  buys;
* ``cvodes_per_step``: the per-step CVODES (one CVODES call per output step, rolled by ``Function.mapaccum`` on the
  interpreted virtual machine: the path of a loop held per step) at the same rtol, fewer rounds (it takes seconds).

Also measured: the library's compile time on a cold cache (a temporary ``DESIGNKIT_CACHE_DIR``), with the Jacobian
at ``-O0`` (the module's choice) and at ``-O1``, and the run time with each (Adams with Newton iteration).

Run: ``python benchmarks/bench_cvodes.py``; writes ``benchmarks/results/cvodes.json``.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent))

from designkit.families import synthesize  # noqa: E402
from designkit.schema.loader import load_spec, parse_spec  # noqa: E402
from designkit.schema.spec import Spec  # noqa: E402
from designkit.simulation import cvodes_grid  # noqa: E402
from designkit.simulation.integrate import run_steps  # noqa: E402
from designkit.simulation.nonlinear import identity  # noqa: E402
from designkit.simulation.run import build  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).resolve().parent / "results" / "cvodes.json"
LADDER = tuple(m * 10.0 ** -k for k in range(6, 13) for m in (3.0, 1.0))[1:]  # 1e-6, 3e-7, ..., 1e-12
ATOL_OVER_RTOL = (1e-2, 1.0)
REPEAT, REPEAT_PER_STEP = 9, 3
GOAL = 3.0


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int, *, slow: tuple[str, ...] = (),
                slow_repeat: int = 1) -> dict[str, dict[str, float]]:
    """Median and min wall time of each function, one call of each per round (the ``slow`` ones only in the first
    ``slow_repeat`` rounds)."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for r in range(repeat):
        for name, fn in fns.items():
            if name in slow and r >= slow_repeat:
                continue
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: {"median_s": statistics.median(v), "min_s": min(v), "repeats": len(v)} for k, v in times.items()}


def with_numerics(spec: Spec, **numerics: object) -> Spec:
    return Spec.model_validate({**spec.model_dump(exclude={"numerics"}), "numerics": numerics})


def per_step_records(sim: Any) -> np.ndarray:
    """The per-step CVODES run: the simulator's own step (built with one CVODES call per step on a cvodes spec)
    rolled by ``mapaccum`` (the run's records, ``(nrec, N)``)."""
    return run_steps(sim.step, sim.z0, sim.inputs, chunk=200)


def scenario(name: str, spec: Spec, error: Callable[[np.ndarray], float]) -> dict[str, Any]:
    """The runs of one scenario; ``error(states)`` of the ``(N, nx)`` plant states."""
    design = synthesize(spec)
    pair = build(spec, design)
    res = pair.run()
    target = error(res.state)
    ladder, candidates = [], []
    for rtol in LADDER:
        for factor in ATOL_OVER_RTOL:
            sim = build(with_numerics(spec, integrator="cvodes", rtol=rtol, atol=rtol * factor), design)
            out = sim.run()
            row = {"rtol": rtol, "atol": rtol * factor, "error": error(out.state),
                   "work": out.settings["integrator_work"], "method": sim.cvodes.method.words,
                   "failure": out.settings.get("integrator_failure")}
            if row["error"] <= target and not row["failure"]:
                row["median_of_3_s"] = interleaved({"run": sim.run}, 3)["run"]["median_s"]
                candidates.append((row["median_of_3_s"], rtol, rtol * factor, sim, out))
            ladder.append(row)
    if not candidates:
        raise RuntimeError(f"{name}: no tolerance of the ladder reaches the pair's error {target:.3g}")
    _, rtol, atol, cv, out = min(candidates, key=lambda c: c[0])
    numerics = {"integrator": "cvodes", "rtol": rtol, "atol": atol}
    interp = build(with_numerics(spec, compile="never", **numerics), design)
    other_iteration = "newton" if cv.cvodes.method.iteration == "functional" else "functional"
    other = cvodes_grid.build_cvodes_grid(
        cv.plant, cv.law, identity(len(cv.plant.inputs)), cv.time, rtol=rtol, atol=atol,
        method=cvodes_grid.Method("adams", other_iteration, "benchmark"))
    other_out = other.run(cv.z0, cv.inputs)
    nx = len(cv.plant.states)
    fns = {"dopri5": pair.run, "cvodes": cv.run, "cvodes_other_iteration": lambda: other.run(cv.z0, cv.inputs),
           "cvodes_interpreted": interp.run, "cvodes_per_step": lambda: per_step_records(cv)}
    per_step = per_step_records(cv)
    timing = interleaved(fns, REPEAT, slow=("cvodes_per_step",), slow_repeat=REPEAT_PER_STEP)
    d = timing["dopri5"]["median_s"]
    return {
        "scenario": name, "dopri5": {"integrator": res.settings["integrator"], "work": res.settings["integrator_work"],
                                     "error": target},
        "cvodes": {"rtol": rtol, "atol": atol, "integrator": out.settings["integrator"],
                   "work": out.settings["integrator_work"], "error": error(out.state), "ladder": ladder},
        "cvodes_other_iteration": {"iteration": other_iteration, "error": error(other_out[:nx].T),
                                   "work": other.work_words(cv.time.size - 1)},
        "cvodes_interpreted": {"error": error(interp.run().state)},
        "cvodes_per_step": {"rtol": rtol, "atol": atol, "error": error(per_step[:nx].T)},
        "timing": timing,
        "ratios_over_dopri5": {k: v["median_s"] / d for k, v in timing.items()},
        "ratios_over_dopri5_min": {k: v["min_s"] / timing["dopri5"]["min_s"] for k, v in timing.items()},
        "per_step_over_whole_grid": timing["cvodes_per_step"]["median_s"] / timing["cvodes"]["median_s"],
        "compiling_buys": timing["cvodes_interpreted"]["median_s"] / timing["cvodes"]["median_s"],
        "breakdown_s": breakdown(cv),
    }


def breakdown(sim: Any) -> dict[str, Any]:
    """Where a whole-grid run's time goes (medians): the run, the CVODES call alone, the records alone, and -- when
    the loop's ``u`` is constant over the run (a step reference, no breakpoint) -- the same CVODES call on every
    tenth grid point (the difference is CasADi's cost per output point)."""
    import casadi as ca

    grid = sim.cvodes
    segments, A, Q = grid._prepare(sim.inputs)
    n = sim.time.size
    X = np.zeros((A.shape[0], grid.ns))
    s0 = np.array(sim.z0[:grid.ns], dtype=float)
    keep: list[Any] = []

    def call(length: int, U: np.ndarray, out: np.ndarray, f: Any = None) -> Callable[[], None]:
        f = grid.integrator(length)[0] if f is None else f
        buf, evaluate = f.buffer()
        buf.set_arg(0, memoryview(s0))
        buf.set_arg(3, memoryview(U.ravel()))
        buf.set_res(0, memoryview(out.ravel()))
        keep.append((f, buf, U, out))
        return evaluate

    fns: dict[str, Callable[[], Any]] = {"run": sim.run}
    if len(segments) == 1:
        _, b, U = segments[0]
        fns["cvodes_call"] = call(b, U, X[:n])
        if np.all(U[:1] == U):
            coarse = [k * grid.dt for k in range(0, n, 10)]
            f = ca.integrator("coarse", "cvodes", grid.oracle, 0.0, coarse, grid.options)
            fns["cvodes_call_every_10th_point"] = call(len(coarse) - 1, np.ascontiguousarray(U[:len(coarse)]),
                                                       np.zeros((len(coarse), grid.ns)), f)
    records, rbuf_eval = grid.records, grid.records.buffer()
    R = np.zeros((A.shape[0], records.size1_out(0)))

    def all_records() -> None:
        rbuf, evaluate = rbuf_eval
        for j in range(0, A.shape[0], cvodes_grid.RECORD_CHUNK):
            for k, arg in enumerate((X, A, Q)):
                rbuf.set_arg(k, memoryview(arg[j:j + cvodes_grid.RECORD_CHUNK].ravel()))
            rbuf.set_res(0, memoryview(R[j:j + cvodes_grid.RECORD_CHUNK].ravel()))
            evaluate()

    fns["records"] = all_records
    timing = interleaved(fns, REPEAT)
    out = {k: v["median_s"] for k, v in timing.items()}
    if "cvodes_call_every_10th_point" in out:
        out["per_output_point_s"] = (out["cvodes_call"] - out["cvodes_call_every_10th_point"]) / (0.9 * (n - 1))
    return out


def compile_costs(spec: Spec) -> dict[str, Any]:
    """Cold compile of the library (a fresh cache) with the Jacobian at -O0 and -O1, and the run with each (Adams,
    Newton iteration, rtol 1e-10)."""
    design = synthesize(spec)
    sim = build(spec, design)
    out: dict[str, Any] = {}
    method = cvodes_grid.Method("adams", "newton", "benchmark")
    saved, saved_env = cvodes_grid.JACOBIAN_FLAGS, os.environ.get("DESIGNKIT_CACHE_DIR")
    try:
        for flags in (("-O0", "-fPIC"), ("-O1", "-fPIC")):
            with tempfile.TemporaryDirectory() as tmp:
                os.environ["DESIGNKIT_CACHE_DIR"] = tmp
                cvodes_grid.JACOBIAN_FLAGS = flags
                t0 = time.perf_counter()
                grid = cvodes_grid.build_cvodes_grid(sim.plant, sim.law, identity(len(sim.plant.inputs)), sim.time,
                                                     rtol=1e-10, atol=1e-12, method=method)
                built = time.perf_counter() - t0
                assert grid.compiled_now
                runs = []
                for _ in range(REPEAT):
                    t0 = time.perf_counter()
                    grid.run(sim.z0, sim.inputs)
                    runs.append(time.perf_counter() - t0)
                out[f"jacobian {flags[0]}"] = {"build_and_compile_s": built, "run_median_s": statistics.median(runs),
                                               "run_min_s": min(runs), "work": grid.work_words(sim.time.size - 1)}
        with tempfile.TemporaryDirectory() as tmp:  # fixed-point iteration: no Jacobian compiled
            os.environ["DESIGNKIT_CACHE_DIR"] = tmp
            t0 = time.perf_counter()
            cvodes_grid.build_cvodes_grid(sim.plant, sim.law, identity(len(sim.plant.inputs)), sim.time, rtol=1e-10,
                                          atol=1e-12, method=cvodes_grid.Method("adams", "functional", "benchmark"))
            out["no jacobian (fixed-point iteration)"] = {"build_and_compile_s": time.perf_counter() - t0}
    finally:
        cvodes_grid.JACOBIAN_FLAGS = saved
        if saved_env is None:
            os.environ.pop("DESIGNKIT_CACHE_DIR", None)
        else:
            os.environ["DESIGNKIT_CACHE_DIR"] = saved_env
    return out


def main() -> None:
    from bench_simnog import SPEC, STEP, numpy_closed_loop

    puma_spec = load_spec(ROOT / "specs" / "puma560-computed-torque.yaml").spec
    ref_puma = build(puma_spec, synthesize(puma_spec)).reference[:, :, 0]

    def puma_error(states: np.ndarray) -> float:
        return float(np.abs(states[:, :6] - ref_puma).max())

    simnog_spec = parse_spec(SPEC).spec
    dsn = synthesize(simnog_spec)
    grid = build(simnog_spec, dsn).time
    rhs = numpy_closed_loop(dsn.gains, {q.name: q.value for q in dsn.plant.parameters}, STEP)["rhs"]
    exact = solve_ivp(rhs, (grid[0], grid[-1]), np.zeros(6), method="DOP853", rtol=2.5e-14, atol=1e-16,
                      t_eval=grid).y.T

    def simnog_error(states: np.ndarray) -> float:
        return float(np.abs(states[:, :2] - exact[:, :2]).max())

    out: dict[str, Any] = {"benchmark": "bench_cvodes"}
    out["puma"] = scenario("PUMA 560 computed torque (specs/puma560-computed-torque.yaml)", puma_spec, puma_error)
    out["simnog"] = scenario("SIMNOG decentralized PID (bench_simnog.SPEC)", simnog_spec, simnog_error)
    out["compile"] = {"puma": compile_costs(puma_spec), "simnog": compile_costs(simnog_spec)}
    ratios = {name: out[name]["ratios_over_dopri5"]["cvodes"] for name in ("puma", "simnog")}
    out["goal"] = {name: {"goal": GOAL, "ratio": ratio, "met": bool(ratio <= GOAL)} for name, ratio in ratios.items()}
    out["machine"] = {"platform": platform.platform(), "python": platform.python_version(), "cpus": os.cpu_count(),
                      "load": "2 cores shared with other engineers' jobs: ratios are in one run, absolute times are "
                              "not those of a quiet machine", "loadavg": os.getloadavg()}
    RESULTS.write_text(json.dumps(out, indent=1, default=float) + "\n")
    for name in ("puma", "simnog"):
        r = out[name]
        t = r["timing"]
        ratios = {k: round(v, 2) for k, v in r["ratios_over_dopri5"].items()}
        print(f"{name}: dopri5 {t['dopri5']['median_s'] * 1e3:.2f} ms (error {r['dopri5']['error']:.2g}); cvodes "
              f"rtol {r['cvodes']['rtol']:g} atol {r['cvodes']['atol']:g} {t['cvodes']['median_s'] * 1e3:.2f} ms "
              f"(error {r['cvodes']['error']:.2g}, {r['cvodes']['work']}); ratios {ratios}")
    print(json.dumps(out["compile"], indent=1))
    print(json.dumps(out["goal"], indent=1))


if __name__ == "__main__":
    main()
