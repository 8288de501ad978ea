"""Benchmark: the SIMNOG two-link arm under decentralized PID, 10 s at a 1 ms step, against ``solve_ivp``.

Scenario (the notes' SIMNOG simulator): the planar two-link arm ``planar2r`` (default parameters),
one PID servo per joint with poles (-4, -5, -20) 1/s and zero -3 1/s, gravity feed-forward
``g^(q)``, a step of (1.0, 0.5) rad, 10 s at ``dt = 1 ms`` (10,000 RK4 steps).

Timed (``time.perf_counter``, median of several repeats, all in the same run):

(a) ``Simulator.run()`` alone: the step function already built, what a repeated simulation costs;
(b) ``simulate(spec, design)`` end to end (build + run);
(c) the baseline: ``scipy.integrate.solve_ivp`` on a NumPy right-hand side of the same arm and
    law, written here from the closed forms of the notes (``models/robots/planar2r.py``
    docstring): ``D(q)``, Coriolis/centrifugal ``h = (m2/2) d1 d2 sin q2``, gravity
    ``g [(m2 + m1/2) d1 cos q1 + (m2/2) d2 cos(q1 + q2)]``, viscous friction ``f_i qd_i``,
    joint 2 relative; ``t_eval`` on the 1 ms grid.  "At matched accuracy": every trajectory is
    compared with a very accurate reference (``solve_ivp`` DOP853, ``rtol = 1e-12``); for RK45
    and DOP853 the cheapest (rtol, atol) of a ladder whose joint-position error does not exceed
    designkit's RK4 error is kept, and the faster of the two is the baseline.

Before timing, the NumPy right-hand side is checked against designkit's (``design.plant.rhs``
and the law's ``command``) at random points, and a NumPy fixed-step RK4 of it against the
designkit trajectory (same scheme, same steps): the same thing is timed.  That fixed-step NumPy
RK4 loop is also timed, as a second, same-scheme baseline.

Goals: (a) <= 20 ms and >= 100x faster than the baseline, reported as met or not.
The ``profile`` section measures where the time goes (cost per step and per CasADi instruction,
chunk size of ``run_steps``, instruction mix, what CSE or generated C of the same step would
change -- diagnostics, not what the API does), and ``where_the_time_goes`` says it in words.

Run: ``python benchmarks/bench_simnog.py``; writes ``benchmarks/results/simnog.json``.
"""

from __future__ import annotations

import json
import math
import os
import platform
import shutil
import statistics
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
from designkit.models.codegen import compile_function
from designkit.models.robots.planar2r import DEFAULTS
from designkit.models.summary import operation_counts
from designkit.pipeline import design as pipeline_design
from designkit.schema.loader import parse_spec
from designkit.simulation.integrate import run_steps
from designkit.simulation.run import build, simulate

RESULTS = Path(__file__).resolve().parent / "results" / "simnog.json"
SPEC = """\
name: simnog-bench
plant: {kind: robot, robot: planar2r}
controller: {kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}
simulation: {duration: 10, dt: 0.001, step: [1.0, 0.5]}
"""
STEP = (1.0, 0.5)
GOAL_RUN_S = 0.020
GOAL_RATIO = 100.0
REPEAT = 15  # rounds of the interleaved timings
PROFILE_ROUNDS = 7
REFERENCE_TOL = (1e-12, 1e-14)  # (rtol, atol) of the reference solution, DOP853
CHECK_TOL = (1e-13, 1e-15)  # a tighter one, to bound the reference's own error
RTOL_LADDER = tuple(10.0 ** (-k / 2) for k in range(6, 23))  # 1e-3 .. 1e-11, half decades
ATOL_FACTORS = (1.0, 1e-3)  # atol = factor * rtol


# --------------------------------------------------------------------------- NumPy model


def numpy_closed_loop(gains: Any, params: dict[str, float], qD: tuple[float, float]) -> dict[str, Callable]:
    """The SIMNOG arm and the decentralized PID law, in NumPy/``math`` from the notes' closed forms.

    Returns ``arm(q1, q2, qd1, qd2, u1, u2) -> (qdd1, qdd2)``, ``law(q1, q2, qd1, qd2, x31, x32) ->
    (u1, u2)`` and the closed loop ``rhs(t, s)``, ``s = (q1, q2, qd1, qd2, x3_1, x3_2)``.
    """
    m1, m2, d1, d2, I1, I2, f1, f2, g = (params[k] for k in ("m1", "m2", "d1", "d2", "I1", "I2", "f1", "f2", "g"))
    # D11 = m1 d1^2/4 + m2 (d1^2 + d2^2/4 + d1 d2 cos q2) + I1 + I2
    # D12 = m2 (d2^2/4 + d1 d2/2 cos q2) + I2,  D22 = m2 d2^2/4 + I2
    d11_0, d11_c = m1 * d1**2 / 4 + m2 * (d1**2 + d2**2 / 4) + I1 + I2, m2 * d1 * d2
    d12_0, d12_c = m2 * d2**2 / 4 + I2, 0.5 * m2 * d1 * d2
    d22 = m2 * d2**2 / 4 + I2
    h_c = 0.5 * m2 * d1 * d2  # h(q2) = (m2/2) d1 d2 sin q2
    g1_c, g2_c = g * (m2 + m1 / 2) * d1, g * (m2 / 2) * d2
    K1, K2, K3, K4 = (tuple(float(v) for v in np.ravel(gains[k])) for k in ("K1", "K2", "K3", "K4"))
    qD1, qD2 = qD
    ff1, ff2 = K3[0] * K4[0] * qD1, K3[1] * K4[1] * qD2
    cos, sin = math.cos, math.sin

    def gravity(q1: float, q2: float) -> tuple[float, float]:
        c12 = g2_c * cos(q1 + q2)
        return g1_c * cos(q1) + c12, c12

    def arm(q1: float, q2: float, qd1: float, qd2: float, u1: float, u2: float) -> tuple[float, float]:
        c2 = cos(q2)
        D11, D12 = d11_0 + d11_c * c2, d12_0 + d12_c * c2
        h = h_c * sin(q2)
        G1, G2 = gravity(q1, q2)
        r1 = u1 + h * (2.0 * qd1 * qd2 + qd2 * qd2) - G1 - f1 * qd1  # u - C(q, qd) qd - g(q) - F qd
        r2 = u2 - h * qd1 * qd1 - G2 - f2 * qd2
        det = D11 * d22 - D12 * D12
        return (d22 * r1 - D12 * r2) / det, (D11 * r2 - D12 * r1) / det

    def law(q1: float, q2: float, qd1: float, qd2: float, x31: float, x32: float) -> tuple[float, float]:
        G1, G2 = gravity(q1, q2)  # gravity feed-forward g^(q), measured q, nominal model
        u1 = -K1[0] * (q1 - qD1) - K2[0] * qd1 - K3[0] * x31 + ff1 + G1
        u2 = -K1[1] * (q2 - qD2) - K2[1] * qd2 - K3[1] * x32 + ff2 + G2
        return u1, u2

    def rhs(t: float, s: np.ndarray) -> np.ndarray:
        q1, q2, qd1, qd2, x31, x32 = s
        u1, u2 = law(q1, q2, qd1, qd2, x31, x32)
        a1, a2 = arm(q1, q2, qd1, qd2, u1, u2)
        return np.array([qd1, qd2, a1, a2, q1 - qD1, q2 - qD2])

    return {"arm": arm, "law": law, "rhs": rhs}


def check_model(design: Any, model: dict[str, Callable], rng: np.random.Generator, n: int = 500) -> dict[str, float]:
    """Largest relative difference of the NumPy arm and law from designkit's at random points."""
    law = family(design.kind).law(design)
    r = np.array([*STEP, 0.0, 0.0, 0.0, 0.0])
    worst_plant = worst_law = 0.0
    for _ in range(n):
        x, u, xc = rng.uniform(-3, 3, 4), rng.uniform(-100, 100, 2), rng.uniform(-1, 1, 2)
        ours = np.array([x[2], x[3], *model["arm"](*x, *u)])
        theirs = np.asarray(design.plant.rhs(x, u), dtype=float).ravel()
        worst_plant = max(worst_plant, float(np.abs(ours - theirs).max() / max(1.0, np.abs(theirs).max())))
        ours_u = np.array(model["law"](*x, *xc))
        theirs_u = np.asarray(law.command(x, xc, np.zeros(0), r), dtype=float).ravel()
        worst_law = max(worst_law, float(np.abs(ours_u - theirs_u).max() / max(1.0, np.abs(theirs_u).max())))
    return {"points": n, "plant_rhs_max_rel_diff": worst_plant, "law_max_rel_diff": worst_law}


def numpy_rk4(rhs: Callable, t: np.ndarray, dt: float) -> np.ndarray:
    """Fixed-step classical RK4 of the NumPy closed loop, states at the instants ``t`` ``(N, 6)``."""
    out = np.empty((t.size, 6))
    s = np.zeros(6)
    h = 0.5 * dt
    for k in range(t.size):
        out[k] = s
        k1 = rhs(0.0, s)
        k2 = rhs(0.0, s + h * k1)
        k3 = rhs(0.0, s + h * k2)
        k4 = rhs(0.0, s + dt * k3)
        s = s + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return out


def ivp(rhs: Callable, t: np.ndarray, method: str, rtol: float, atol: float) -> Any:
    """``solve_ivp`` of the closed loop from rest, dense output sampled on ``t``."""
    sol = solve_ivp(rhs, (float(t[0]), float(t[-1])), np.zeros(6), method=method, rtol=rtol, atol=atol, t_eval=t)
    if not sol.success:
        raise RuntimeError(f"solve_ivp {method} rtol={rtol:g} failed: {sol.message}")
    return sol


# --------------------------------------------------------------------------- timing helpers


def timed(fn: Callable[[], Any], repeat: int) -> dict[str, Any]:
    return interleaved({"fn": fn}, repeat)["fn"]


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, dict[str, Any]]:
    """Median and min wall time of each function, timed round-robin (one call of each per round), so that
    a change of the machine's load during the run affects every figure alike."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: {"median_s": statistics.median(v), "min_s": min(v), "repeats": repeat} for k, v in times.items()}


def errors(states: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    """Max absolute errors over the grid: joint positions (rad), velocities (rad/s), integrals (rad*s)."""
    e = np.abs(states - reference).max(axis=0)
    return {"position_rad": float(e[:2].max()), "velocity_rad_s": float(e[2:4].max()),
            "integral_rad_s": float(e[4:].max())}


# --------------------------------------------------------------------------- matched accuracy


def tolerance_scan(rhs: Callable, t: np.ndarray, reference: np.ndarray, target: float) -> dict[str, Any]:
    """For RK45 and DOP853: the ladder of tolerances, and the cheapest setting whose position error <= target."""
    out: dict[str, Any] = {}
    for method in ("RK45", "DOP853"):
        rows = []
        for rtol in RTOL_LADDER:
            for factor in ATOL_FACTORS:
                sol = ivp(rhs, t, method, rtol, factor * rtol)
                rows.append({"rtol": rtol, "atol": factor * rtol, "nfev": int(sol.nfev),
                             "errors": errors(sol.y.T, reference)})
        ok = [r for r in rows if r["errors"]["position_rad"] <= target]
        chosen = min(ok, key=lambda r: (r["nfev"], -r["rtol"])) if ok else None
        out[method] = {"ladder": rows, "chosen": chosen}
    return out


# --------------------------------------------------------------------------- profile of Simulator.run


def _buffer_loop(f: ca.Function, args: list[np.ndarray], n: int) -> Callable[[], None]:
    """``n`` evaluations of ``f`` one call at a time through a FunctionBuffer (no mapaccum)."""
    buf, evaluate = f.buffer()
    keep = [np.ascontiguousarray(a, dtype=float) for a in args]
    outs = [np.empty(f.nnz_out(k)) for k in range(f.n_out())]
    for k, a in enumerate(keep):
        buf.set_arg(k, memoryview(a))
    for k, o in enumerate(outs):
        buf.set_res(k, memoryview(o))

    def loop() -> None:
        for _ in range(n):
            evaluate()

    loop.keep = (buf, keep, outs)  # type: ignore[attr-defined]  # buffers must outlive the closure
    return loop


def profile(sim: Any) -> dict[str, Any]:
    """Where the time of ``Simulator.run()`` goes.

    Diagnostics: ``run`` and ``run_steps`` with the default chunk are the API's path; the other chunk
    sizes, the CSE'd step and the generated-C step are what-ifs, never designkit figures.
    """
    step, z0, inputs = sim.step, sim.z0, sim.inputs
    n_steps = inputs.shape[1]
    counts = operation_counts(step).__dict__

    # the SX virtual machine's speed on a synthetic chain of multiply-adds (no transcendental functions)
    xs = ca.SX.sym("x", 10)
    y = xs
    for _ in range(44):
        y = y * 0.999 + 0.001
    chain = ca.Function("chain", [xs], [y])
    # common-subexpression elimination of the same step (gravity is computed in the dynamics and again in g^(q))
    zi, wi = step.sx_in()
    cse = ca.Function("sim_step_cse", [zi, wi], list(step(zi, wi)), {"cse": True})

    fns: dict[str, Callable[[], Any]] = {
        "run": sim.run,
        "run_steps": lambda: run_steps(step, z0, inputs),
        "mapaccum_construction": lambda: step.mapaccum("acc", 200),
        "one_step_per_call": _buffer_loop(step, [z0, inputs[:, 0]], n_steps),
        "mul_add_chain": _buffer_loop(chain, [np.ones(10)], n_steps),
        "cse_run_steps": lambda: run_steps(cse, z0, inputs),
    }
    for chunk in (1, 20, 1000, 10_001):
        fns[f"chunk_{chunk}"] = lambda chunk=chunk: run_steps(step, z0, inputs, chunk=chunk)

    # generated C of the very same step (designkit.models.codegen, cache in a temp dir)
    tmp = tempfile.mkdtemp(prefix="simnog-bench-")
    generated: dict[str, Any]
    try:
        t0 = time.perf_counter()
        compiled = compile_function(step, directory=tmp)
        compile_s = time.perf_counter() - t0
        if compiled.compiled:
            c_diff = float(np.abs(run_steps(compiled.function, z0, inputs) - run_steps(step, z0, inputs)).max())
            generated = {"status": "ok", "compile_s": compile_s, "max_abs_diff_vs_interpreted": c_diff}
            fns["generated_c_run_steps"] = lambda: run_steps(compiled.function, z0, inputs)
        else:
            generated = {"status": compiled.reason}
        for fn in fns.values():
            fn()  # warm-up
        t = interleaved(fns, PROFILE_ROUNDS)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if "generated_c_run_steps" in t:
        c = t["generated_c_run_steps"]
        generated.update(c, us_per_step=1e6 * c["median_s"] / n_steps, us_per_step_min=1e6 * c["min_s"] / n_steps)

    med = {k: v["median_s"] for k, v in t.items()}
    low = {k: v["min_s"] for k, v in t.items()}
    us_step = 1e6 * med["run_steps"] / n_steps
    us_step_min = 1e6 * low["run_steps"] / n_steps
    return {
        "note": "diagnostics; run and run_steps (default chunk 200) are the API's path; other chunk sizes, the "
                "CSE'd step and the generated-C step are what-ifs, not designkit figures",
        "rounds": PROFILE_ROUNDS,
        "timings": t,
        "run_steps_share_of_run": {"median": med["run_steps"] / med["run"], "min": low["run_steps"] / low["run"]},
        "steps": n_steps,
        "rhs_evaluations": 4 * n_steps,
        "us_per_step": us_step,
        "us_per_step_min": us_step_min,
        "step_function": {"n_instructions": step.n_instructions(), "operation_counts": counts,
                          "sizes_in": [step.size1_in(0), step.size1_in(1)],
                          "sizes_out": [step.size1_out(0), step.size1_out(1)]},
        "ns_per_instruction": {"median": 1e3 * us_step / step.n_instructions(),
                               "min": 1e3 * us_step_min / step.n_instructions()},
        "sx_vm_ns_per_instruction_mul_add_chain": {
            "median": 1e9 * med["mul_add_chain"] / (n_steps * chain.n_instructions()),
            "min": 1e9 * low["mul_add_chain"] / (n_steps * chain.n_instructions())},
        "run_steps_s_by_chunk": {"1": t["chunk_1"], "20": t["chunk_20"], "200 (default)": t["run_steps"],
                                 "1000": t["chunk_1000"], "10001 (one mapaccum)": t["chunk_10001"]},
        "one_step_per_call_s": t["one_step_per_call"],
        "with_cse": {"operation_counts": operation_counts(cse).__dict__, **t["cse_run_steps"]},
        "generated_c": generated,
    }


def default_step() -> dict[str, Any]:
    """The step designkit would choose for this scenario without ``simulation.dt`` (build only, not run)."""
    text = SPEC.replace("dt: 0.001, ", "")
    assert "dt:" not in text
    loaded = parse_spec(text)
    settings = build(loaded.spec, pipeline_design(loaded)).settings
    return {"dt_s": float(settings["dt"]), "steps": int(settings["n_steps"]), "rule": settings["dt_source"]}


def explain(prof: dict[str, Any], run_t: dict[str, Any], base: dict[str, Any], base_method: str,
            dk_err: dict[str, float], default_dt: dict[str, Any], variants: dict[str, Any] | None,
            default_evaluation: Any) -> list[str]:
    """Where the time of ``Simulator.run()`` goes, in words, from the measured figures."""
    t = prof["timings"]
    ms = 1e3
    counts = prof["step_function"]["operation_counts"]
    n_eval = prof["rhs_evaluations"]
    us_eval_dk = 1e6 * run_t["median_s"] / n_eval
    us_eval_base = 1e6 * base["median_s"] / base["nfev"]
    gen = prof["generated_c"]
    cse = prof["with_cse"]
    out = [
        f"run() is essentially run_steps: run() {ms * t['run']['median_s']:.0f} ms median "
        f"({ms * t['run']['min_s']:.0f} best), run_steps alone {ms * t['run_steps']['median_s']:.0f} ms "
        f"({ms * t['run_steps']['min_s']:.0f} best), timed in alternation; building the chunk's mapaccum costs "
        f"{ms * t['mapaccum_construction']['median_s']:.1f} ms of it, assembling the SimulationResult about a "
        "millisecond.",
        "run_steps is the CasADi SX virtual machine evaluating the step function: "
        f"{prof['step_function']['n_instructions']} instructions per RK4 step ({counts['multiplications']} mul, "
        f"{counts['additions']} add, "
        f"{counts['divisions']} div, {counts['trigonometric']} sin/cos), {prof['us_per_step']:.2f} us per step "
        f"({prof['us_per_step_min']:.2f} best) = {prof['ns_per_instruction']['median']:.1f} ns per instruction "
        f"({prof['ns_per_instruction']['min']:.1f} best); the same VM runs a plain multiply-add chain at "
        f"{prof['sx_vm_ns_per_instruction_mul_add_chain']['median']:.1f} ns per instruction, the difference is the "
        f"transcendental calls. 10,000 steps x {prof['us_per_step']:.1f} us = {ms * t['run_steps']['median_s']:.0f} ms;"
        f" 20 ms would need <= 2 us per step, i.e. about 400 VM instructions per RK4 step (4 stages).",
        f"Chunking is not the bottleneck: one sim_step call per step through a FunctionBuffer costs "
        f"{ms * t['one_step_per_call']['median_s']:.0f} ms against {ms * t['run_steps']['median_s']:.0f} ms for "
        f"mapaccum chunks of 200; chunk 20 costs {ms * t['chunk_20']['median_s']:.0f} ms and chunk 1 "
        f"{ms * t['chunk_1']['median_s']:.0f} ms (Python per chunk), chunk 1000 "
        f"{ms * t['chunk_1000']['median_s']:.0f} ms and one mapaccum over all 10,001 steps "
        f"{ms * t['chunk_10001']['median_s']:.0f} ms (mapaccum construction grows faster than linearly). "
        "The default 200 is about the best.",
        f"The step repeats work: {counts['trigonometric']} sin/cos per step where 4 per RK4 stage (16) suffice -- "
        "gravity is computed inside the forward dynamics and again by the gravity feed-forward g^(q), with no "
        f"common-subexpression elimination. CSE of the same step (what-if): "
        f"{cse['operation_counts']['instructions']} instructions, {cse['operation_counts']['trigonometric']} sin/cos, "
        f"{ms * cse['median_s']:.0f} ms median ({ms * cse['min_s']:.0f} best) against "
        f"{ms * t['run_steps']['median_s']:.0f} ms ({ms * t['run_steps']['min_s']:.0f} best): "
        f"{100 * (1 - cse['operation_counts']['instructions'] / prof['step_function']['n_instructions']):.0f} % "
        "fewer instructions, within the noise in time -- nowhere near the 2.5-3x the goal needs.",
    ]
    if gen.get("status") == "ok":
        out.append(f"Generated C of the single step function, -O3 -march=native (designkit.models.codegen called "
                   f"directly, what-if): {ms * gen['median_s']:.1f} ms median ({ms * gen['min_s']:.1f} best), "
                   f"{gen['us_per_step']:.2f} us per step, compile {gen['compile_s']:.2f} s once: "
                   f"{t['run_steps']['median_s'] / gen['median_s']:.1f}x faster than the interpreted step.")
    out.append(
        f"The ratio to solve_ivp is bounded by the number of right-hand-side evaluations: designkit's fixed 1 ms "
        f"RK4 makes {n_eval} (10,000 steps x 4 stages), solve_ivp {base_method} at matched accuracy "
        f"{base['nfev']} ({n_eval / base['nfev']:.0f}x fewer) in {base['steps']} steps of "
        f"{ms * base['mean_step_s']:.0f} ms on average; its step is held by stability against the fast closed-loop "
        f"poles rather than by accuracy (nfev {base['nfev_at_loosest_rtol']['nfev']} already at rtol "
        f"{base['nfev_at_loosest_rtol']['rtol']:g}). Per evaluation designkit costs "
        f"{us_eval_dk:.2f} us, solve_ivp {us_eval_base:.1f} us (Python right-hand side, {base_method} "
        "machinery and the t_eval interpolation): "
        f"{us_eval_base / us_eval_dk:.0f}x, of which the step count takes back {n_eval / base['nfev']:.0f}x. "
        f"designkit's RK4 error at 1 ms is {dk_err['position_rad']:.1e} rad; 100x against this baseline would need "
        "both compiled code and far fewer steps.")
    if default_evaluation:
        out.insert(0, f"The default path (numerics.compile default, cold cache) evaluates: {default_evaluation}.")
    if variants is not None:
        vt, vr = variants["timings"], variants["ratios_baseline_over"]
        out.append(
            f"numerics.compile (designkit's own option): never {ms * vt['run_never']['median_s']:.0f} ms, always "
            f"{ms * vt['run_always']['median_s']:.1f} ms ({ms * vt['run_always']['min_s']:.1f} best; first build "
            f"{variants['builds']['always_first_build_s']:.2f} s with the compiler), auto once the library is cached "
            f"{ms * vt['run_auto_cached']['median_s']:.1f} ms; compiled equals interpreted bitwise: "
            f"{variants['compiled_equals_interpreted_bitwise']}. Compiled, run() "
            f"{'meets' if vt['run_always']['median_s'] <= GOAL_RUN_S else 'misses'} the 20 ms goal and is "
            f"{vr['run_always']:.1f}x the baseline ({'meets' if vr['run_always'] >= GOAL_RATIO else 'far from'} "
            "100x): the step count stays.")
    out.append(f"Without simulation.dt designkit would pick dt = {default_dt['dt_s']:g} s "
               f"({default_dt['steps']} steps) for this arm: {default_dt['steps'] // 10_000}x the work of the "
               "benchmarked 1 ms.")
    return out


# --------------------------------------------------------------------------- main


def main() -> None:
    # A private, empty code-generation cache: whether designkit runs a compiled step can depend on what is
    # already cached (numerics.compile: auto), so the benchmark starts cold, and leaves the user's cache alone.
    cache = tempfile.mkdtemp(prefix="simnog-bench-cache-")
    previous = os.environ.get("DESIGNKIT_CACHE_DIR")
    os.environ["DESIGNKIT_CACHE_DIR"] = cache
    try:
        measure(cache)
    finally:
        if previous is None:
            os.environ.pop("DESIGNKIT_CACHE_DIR", None)
        else:
            os.environ["DESIGNKIT_CACHE_DIR"] = previous
        shutil.rmtree(cache, ignore_errors=True)


def compile_info(sim: Any) -> Any:
    """How the simulator evaluates its steps (interpreted or compiled, and why), when designkit says so."""
    info = getattr(sim, "compiled", None) or sim.settings.get("compiled")
    return json.loads(json.dumps(info, default=str)) if info else None


def has_compile_option(spec: Any) -> bool:
    return "compile" in type(spec.numerics).model_fields


def compiled_variants(design: Any, base_fn: Callable[[], Any], cache: str) -> dict[str, Any]:
    """``numerics.compile``: never / always / auto once the library is cached, timed against the baseline."""
    specs = {mode: parse_spec(SPEC + f"numerics: {{compile: {mode}}}\n").spec for mode in ("never", "always")}
    sims, builds = {}, {}
    t0 = time.perf_counter()
    sims["never"] = build(specs["never"], design)
    builds["never_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    sims["always"] = build(specs["always"], design)  # cold cache: code generation + C compiler
    builds["always_first_build_s"] = time.perf_counter() - t0
    sims["auto_cached"] = build(parse_spec(SPEC).spec, design)  # the default path, library now cached
    r_never, r_always = sims["never"].run(), sims["always"].run()
    interp = np.hstack([r_never.state, r_never.controller_state])
    comp = np.hstack([r_always.state, r_always.controller_state])
    default_spec = parse_spec(SPEC).spec
    fns: dict[str, Callable[[], Any]] = {
        "run_never": sims["never"].run, "run_always": sims["always"].run, "run_auto_cached": sims["auto_cached"].run,
        "simulate_auto_cached": lambda: simulate(default_spec, design),
        "simulate_never": lambda: simulate(specs["never"], design), "baseline": base_fn,
    }
    for fn in fns.values():
        fn()
    t = interleaved(fns, REPEAT)
    base = t["baseline"]["median_s"]
    return {
        "what": "the public numerics.compile option (default auto); cache private to this run, cold at its start",
        "how_each_evaluates": {k: compile_info(v) for k, v in sims.items()},
        "builds": builds,
        "compiled_vs_interpreted_max_abs_diff": float(np.abs(comp - interp).max()),
        "compiled_equals_interpreted_bitwise": bool(np.array_equal(comp, interp)),
        "cache_files": sorted(p.name for p in Path(cache).rglob("*") if p.is_file()),
        "timings": t,
        "ratios_baseline_over": {k: base / v["median_s"] for k, v in t.items() if k != "baseline"},
        "goal_met": {k: {"run_at_most_20ms": t[k]["median_s"] <= GOAL_RUN_S,
                         "ratio_at_least_100": base / t[k]["median_s"] >= GOAL_RATIO}
                     for k in ("run_never", "run_always", "run_auto_cached")},
    }


def measure(cache: str) -> None:
    load_start = os.getloadavg() if hasattr(os, "getloadavg") else None
    loaded = parse_spec(SPEC)
    spec = loaded.spec
    design = pipeline_design(loaded)
    params = {p.name: p.value for p in design.plant.parameters}
    assert params == {k: float(v) for k, v in DEFAULTS.items()}, "the plant is not planar2r's DEFAULTS"
    model = numpy_closed_loop(design.gains, dict(DEFAULTS), STEP)
    rhs = model["rhs"]

    # 1. the same thing is timed: right-hand sides, then trajectories (same RK4 scheme and steps)
    model_check = check_model(design, model, np.random.default_rng(0))
    assert model_check["plant_rhs_max_rel_diff"] < 1e-12 and model_check["law_max_rel_diff"] < 1e-12, model_check
    sim = build(spec, design)
    default_evaluation = compile_info(sim)
    res = sim.run()
    t, dt = res.time, float(res.settings["dt"])
    assert res.state.shape == (t.size, 4) and res.controller_state.shape == (t.size, 2)
    ours = np.hstack([res.state, res.controller_state])
    t0 = time.perf_counter()
    same_scheme = numpy_rk4(rhs, t, dt)
    numpy_rk4_once = time.perf_counter() - t0
    rk4_diff = float(np.abs(same_scheme - ours).max())
    assert rk4_diff < 1e-9, f"designkit and the NumPy RK4 disagree by {rk4_diff:g}"

    # 2. accuracy: a very accurate reference, designkit's error, the matched solve_ivp tolerances
    reference = ivp(rhs, t, "DOP853", *REFERENCE_TOL)
    tighter = ivp(rhs, t, "DOP853", *CHECK_TOL)
    ref_states = reference.y.T
    ref_self = errors(tighter.y.T, ref_states)
    dk_err = errors(ours, ref_states)
    assert ref_self["position_rad"] < 1e-2 * dk_err["position_rad"], "reference not accurate enough"
    scan = tolerance_scan(rhs, t, ref_states, dk_err["position_rad"])

    # 3. timings
    sim.run()
    simulate(spec, design)
    fns: dict[str, Callable[[], Any]] = {"run": sim.run, "simulate": lambda: simulate(spec, design)}
    candidates = {}
    for method, entry in scan.items():
        c = entry["chosen"]
        if c is None:
            continue
        sol = ivp(rhs, t, method, c["rtol"], c["atol"])
        free = solve_ivp(rhs, (float(t[0]), float(t[-1])), np.zeros(6), method=method, rtol=c["rtol"],
                         atol=c["atol"])  # without t_eval: its own steps
        loosest = entry["ladder"][0]
        candidates[method] = {"rtol": c["rtol"], "atol": c["atol"], "nfev": int(sol.nfev),
                              "steps": int(free.t.size - 1), "mean_step_s": float(t[-1] / (free.t.size - 1)),
                              "nfev_at_loosest_rtol": {"rtol": loosest["rtol"], "nfev": loosest["nfev"]},
                              "errors": errors(sol.y.T, ref_states)}
        fns[method] = lambda method=method, c=c: ivp(rhs, t, method, c["rtol"], c["atol"])
    timings = interleaved(fns, REPEAT)
    run_t, sim_t = timings["run"], timings["simulate"]
    for method in candidates:
        candidates[method].update(timings[method])
    base_method = min(candidates, key=lambda m: candidates[m]["median_s"])
    base = candidates[base_method]
    rk4_loop_t = timed(lambda: numpy_rk4(rhs, t, dt), 3)

    ratio_run = base["median_s"] / run_t["median_s"]
    ratio_sim = base["median_s"] / sim_t["median_s"]
    goal_time = run_t["median_s"] <= GOAL_RUN_S
    goal_ratio = ratio_run >= GOAL_RATIO
    cache_after_default = sorted(p.name for p in Path(cache).rglob("*") if p.is_file())
    prof = profile(sim)
    best = candidates[base_method]
    variants = (compiled_variants(design, lambda: ivp(rhs, t, base_method, best["rtol"], best["atol"]), cache)
                if has_compile_option(spec) else None)
    default_dt = default_step()
    findings = explain(prof, run_t, base, base_method, dk_err, default_dt, variants, default_evaluation)
    load_end = os.getloadavg() if hasattr(os, "getloadavg") else None

    results = {
        "benchmark": "simnog",
        "scenario": "SIMNOG planar2r (default parameters) under decentralized_pid, poles (-4, -5, -20) 1/s, zero "
                    "-3 1/s, gravity feed-forward g^(q), step (1.0, 0.5) rad, 10 s at dt = 1 ms (10,000 RK4 steps)",
        "spec": SPEC,
        "gains": design.gains.to_json(),
        "timing": f"time.perf_counter, median (and min) of {REPEAT} rounds after a warm-up, each round timing "
                  "run(), simulate() and every solve_ivp candidate once (round-robin), same process and run; the "
                  "machine is shared with other jobs (see load averages): expect noise, compare within this file",
        "designkit": {
            "simulator_run": run_t,
            "simulate_end_to_end": sim_t,
            "build_s_estimate": max(0.0, sim_t["median_s"] - run_t["median_s"]),
            "integrator": res.settings["integrator"], "dt_s": dt, "steps": int(t.size - 1),
            "evaluation": default_evaluation,
            "codegen_cache_files_after_default_runs": cache_after_default,
            "errors_vs_reference": dk_err,
        },
        "baseline": {
            "what": "scipy.integrate.solve_ivp, NumPy/math right-hand side of the same arm and law (closed forms of "
                    "the notes), t_eval on the 1 ms grid, at matched accuracy: the cheapest (rtol, atol) of a "
                    "half-decade ladder whose joint-position error does not exceed designkit's; the faster method",
            "method": base_method, **base,
            "candidates": candidates,
        },
        "ratios": {
            "baseline_over_run": ratio_run,
            "baseline_over_simulate": ratio_sim,
            "baseline_over_run_min": base["min_s"] / run_t["min_s"],
            "baseline_over_simulate_min": base["min_s"] / sim_t["min_s"],
            "numpy_rk4_loop_over_run": rk4_loop_t["median_s"] / run_t["median_s"],
        },
        "goal": {
            "run_at_most_s": GOAL_RUN_S, "run_met": goal_time,
            "ratio_at_least": GOAL_RATIO, "ratio_met": goal_ratio,
            "met": goal_time and goal_ratio,
        },
        "same_scheme_baseline": {
            "what": "the NumPy right-hand side in a Python fixed-step RK4 loop, same scheme and steps as designkit",
            **rk4_loop_t, "first_run_s": numpy_rk4_once,
        },
        "checks": {
            **model_check,
            "numpy_rk4_vs_designkit_max_abs_diff": rk4_diff,
            "reference": {"method": "DOP853", "rtol": REFERENCE_TOL[0], "atol": REFERENCE_TOL[1],
                          "nfev": int(reference.nfev),
                          "self_check": {"against": {"rtol": CHECK_TOL[0], "atol": CHECK_TOL[1]}, **ref_self}},
        },
        "tolerance_scan": scan,
        "numerics_compile": variants,
        "where_the_time_goes": findings,
        "profile": prof,
        "machine": {"python": platform.python_version(), "platform": platform.platform(),
                    "processor": platform.processor() or platform.machine(), "cpu_count": os.cpu_count(),
                    "cpus_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
                    "load_average_start": load_start, "load_average_end": load_end},
        "versions": {"designkit": metadata.version("designkit"), "casadi": ca.__version__,
                     "numpy": np.__version__, "scipy": scipy.__version__},
    }
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=2) + "\n")

    ms = 1e3
    print("| SIMNOG 2-link arm, decentralized PID, 10 s at 1 ms | median | baseline | ratio | goal |")
    print("|---|---|---|---|---|")
    print(f"| (a) `Simulator.run()` | {ms * run_t['median_s']:.1f} ms | solve_ivp {base_method} rtol "
          f"{base['rtol']:.0e} atol {base['atol']:.0e}: {ms * base['median_s']:.1f} ms | {ratio_run:.2f}x | "
          f"<= 20 ms: {'met' if goal_time else 'NOT met'}; >= 100x: {'met' if goal_ratio else 'NOT met'} |")
    print(f"| (b) `simulate()` (build + run) | {ms * sim_t['median_s']:.1f} ms | same | {ratio_sim:.2f}x | |")
    print(f"| NumPy fixed-step RK4 loop (same scheme) | {ms * rk4_loop_t['median_s']:.0f} ms | | "
          f"{rk4_loop_t['median_s'] / run_t['median_s']:.1f}x vs (a) | |")
    print(f"errors vs reference (max |q - q_ref|): designkit RK4 {dk_err['position_rad']:.2e} rad, "
          f"solve_ivp {base['errors']['position_rad']:.2e} rad (nfev {base['nfev']} vs designkit "
          f"{prof['rhs_evaluations']} right-hand-side evaluations)")
    print(f"profile: {prof['us_per_step']:.2f} us/step, {prof['step_function']['n_instructions']} instructions/step "
          f"({prof['ns_per_instruction']['median']:.1f} ns each; SX VM mul-add chain "
          f"{prof['sx_vm_ns_per_instruction_mul_add_chain']['median']:.1f} ns), "
          f"run_steps {100 * prof['run_steps_share_of_run']['median']:.0f} % of run(); generated C: "
          f"{prof['generated_c'].get('median_s', float('nan')) * ms:.1f} ms")
    if variants is not None:
        vt, vr = variants["timings"], variants["ratios_baseline_over"]
        for key, label in (("run_never", "`run()`, numerics.compile: never (interpreted)"),
                           ("run_always", "`run()`, numerics.compile: always (compiled C)"),
                           ("run_auto_cached", "`run()`, default auto once the library is cached"),
                           ("simulate_auto_cached", "`simulate()`, default auto, library cached")):
            print(f"| {label} | {ms * vt[key]['median_s']:.1f} ms | {ms * vt['baseline']['median_s']:.1f} ms | "
                  f"{vr[key]:.2f}x | |")
        print(f"compile on first build: {variants['builds']['always_first_build_s']:.2f} s; compiled equals "
              f"interpreted bitwise: {variants['compiled_equals_interpreted_bitwise']}")
    for line in findings:
        print(f"- {line}")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
