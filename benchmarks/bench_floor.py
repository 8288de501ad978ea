"""Benchmark: the simulation at its floor -- designkit's default runs against ``solve_ivp`` and against
the cost of the evaluations an adaptive 5th-order method needs.

Scenarios (both ``specs/``-like, run with designkit's defaults, ``numerics`` left out):

* **PUMA computed torque**, ``specs/puma560-computed-torque.yaml`` (six joints, friction and rotor inertias,
  exact model, the quintic of 3 s, 4 s run).  The exact solution is ``q(t) = qD(t)``: every integrator's error
  is its ``max |q - qD|``.  Contender: ``solve_ivp`` DOP853 on a NumPy right-hand side built on **Pinocchio**
  (``crba`` + ``nonLinearEffects`` of the same DH model, plus the reflected rotor inertias and the joint
  friction), the computed-torque law in NumPy; checked against designkit's closed loop at random points first.
* **SIMNOG** (the two-link arm under decentralized PID of ``bench_simnog.py``, 10 s on the 1 ms grid).
  Contender: ``solve_ivp`` DOP853 on ``bench_simnog``'s NumPy right-hand side (the notes' closed forms); error
  measured against DOP853 at ``rtol = 2.5e-14``, ``atol = 1e-16`` (scipy's floor is ``100 eps``).

"Matched accuracy": for each contender, the cheapest tolerance of a ladder (DOP853, ``rtol`` 1e-5 .. 1e-13,
``atol = 1e-2 rtol``) whose position error does not exceed designkit's; also DOP853 at ``rtol = 1e-10``.
The **adaptive floor**: designkit's own number of right-hand-side evaluations (the
Dormand--Prince pair's count) times the cost of one compiled evaluation of the closed loop's right-hand side
(``dk_rhs`` compiled with the pair's flags, mapped over 256 states, called through CasADi's zero-copy buffer
interface, timed).  Ratios are taken in one run,
interleaved rounds, medians.

Also timed: one-state ``Robot.inverse_dynamics`` on the PUMA against ``pinocchio.rnea`` (same DH model), per call
from Python (and the mass matrix, gravity and forward dynamics against ``crba``, ``computeGeneralizedGravity``,
``aba``).

Run: ``python benchmarks/bench_floor.py``; writes ``benchmarks/results/floor.json``.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from designkit.models.codegen import compile_function  # noqa: E402
from designkit.models.robots import robot  # noqa: E402
from designkit.pipeline import design as pipeline_design  # noqa: E402
from designkit.schema.loader import load_spec, parse_spec  # noqa: E402
from designkit.simulation.dopri5 import FLAGS, loop_functions  # noqa: E402
from designkit.simulation.nonlinear import identity  # noqa: E402
from designkit.simulation.run import build  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).resolve().parent / "results" / "floor.json"
LADDER = (*(10.0 ** -k for k in range(5, 13)), 3e-13, 1e-13)
REPEAT = 7
MAP_STATES = 256
GOALS = {"puma_vs_dop853": 10.0, "puma_vs_floor": 2.0, "simnog_vs_solve_ivp": 10.0}


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, dict[str, float]]:
    """Median and min wall time of each function, one call of each per round."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: {"median_s": statistics.median(v), "min_s": min(v), "repeats": repeat} for k, v in times.items()}


def evaluation_cost(sim: Any) -> dict[str, float]:
    """Cost (s) of one compiled evaluation of the loop's right-hand side, mapped over MAP_STATES states."""
    rhs, _, _, n_ref = loop_functions(sim.plant, sim.law, identity(len(sim.plant.inputs)))
    compiled = compile_function(rhs.map(MAP_STATES), flags=FLAGS)
    rng = np.random.default_rng(1)
    s = sim.z0[:rhs.size1_in(0), None] + rng.normal(0, 1e-2, (rhs.size1_in(0), MAP_STATES))
    a = np.repeat(sim.inputs[:n_ref, :1], MAP_STATES, axis=1)
    q = np.repeat(sim.inputs[3 * n_ref:, :1], MAP_STATES, axis=1)
    f = compiled.function
    out = np.zeros((f.size1_out(0), MAP_STATES))
    args = [np.asfortranarray(v) for v in (s, a, q)]  # CasADi's buffers are column-major
    buf, evaluate = f.buffer()
    for k, v in enumerate(args):
        buf.set_arg(k, memoryview(v.ravel(order="F")))
    out_flat = out.ravel(order="F")
    buf.set_res(0, memoryview(out_flat))
    evaluate()
    rounds = []
    for _ in range(20):
        t0 = time.perf_counter()
        for _ in range(50):
            evaluate()
        rounds.append((time.perf_counter() - t0) / (50 * MAP_STATES))
    return {"per_evaluation_s": statistics.median(rounds), "compiled": bool(compiled.compiled),
            "flags": " ".join(FLAGS)}


def ladder(rhs: Callable, t: np.ndarray, s0: np.ndarray, error: Callable[[np.ndarray], float],
           target: float) -> dict[str, Any]:
    rows = []
    for rtol in LADDER:
        sol = solve_ivp(rhs, (t[0], t[-1]), s0, method="DOP853", rtol=rtol, atol=1e-2 * rtol, t_eval=t)
        rows.append({"rtol": rtol, "atol": 1e-2 * rtol, "nfev": int(sol.nfev), "error": error(sol.y.T),
                     "success": bool(sol.success)})
    ok = [r for r in rows if r["success"] and r["error"] <= target]
    return {"ladder": rows, "matched": min(ok, key=lambda r: r["nfev"]) if ok else None}


# --------------------------------------------------------------------------- PUMA with Pinocchio


def pinocchio_loop(dsn: Any) -> Callable[[float, np.ndarray], np.ndarray]:
    """The PUMA computed-torque loop in NumPy on Pinocchio (the arm = the model: exact compensation)."""
    import pinocchio as pin
    from bench_computed_torque import quintic
    from tests.models.support import pinocchio_model

    d = robot("puma560").description
    model, _ = pinocchio_model(d)
    data = model.createData()
    Ia = np.array([link.gear_ratio ** 2 * link.motor_inertia for link in d.links])
    fv = np.array([link.viscous for link in d.links])
    fc = np.array([link.coulomb for link in d.links])
    K1, K2 = (np.asarray(dsn.gains[k], dtype=float) for k in ("K1", "K2"))

    def rhs(t: float, s: np.ndarray) -> np.ndarray:
        q, qd = s[:6], s[6:]
        pos, vel, acc = quintic(t)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T + np.diag(Ia)
        h = pin.nonLinearEffects(model, data, q, qd) + fv * qd + fc * np.sign(qd)
        u = M @ (acc + K1 * (pos - q) + K2 * (vel - qd)) + h  # the law, on the exact model
        return np.concatenate([qd, np.linalg.solve(M, u - h)])  # the arm

    return rhs


def check_loop(sim: Any, rhs: Callable, n: int = 200) -> float:
    """Largest scaled difference of the contender's closed-loop derivative from designkit's, random points."""
    from bench_computed_torque import quintic

    f, _, _, n_ref = loop_functions(sim.plant, sim.law, identity(len(sim.plant.inputs)))
    q_held = sim.inputs[3 * n_ref:, 0]
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(n):
        t = float(rng.uniform(0, 3))
        s = np.concatenate([sim.z0[:6] + rng.uniform(-0.3, 0.3, 6), rng.uniform(-1, 1, 6)])
        ours = np.asarray(f(s, np.concatenate(quintic(t)), q_held)).ravel()
        worst = max(worst, float(np.max(np.abs(rhs(t, s) - ours) / (1 + np.abs(ours)))))
    return worst


def puma() -> dict[str, Any]:
    loaded = load_spec(ROOT / "specs" / "puma560-computed-torque.yaml")
    dsn = pipeline_design(loaded)
    sim = build(loaded.spec, dsn)
    res = sim.run()
    t, ref = res.time, res.reference[:, :, 0]
    ours = float(np.abs(res.state[:, :6] - ref).max())
    rhs = pinocchio_loop(dsn)

    def err(states: np.ndarray) -> float:
        return float(np.abs(states[:, :6] - ref).max())

    scan = ladder(rhs, t, sim.z0[:12], err, ours)
    fns = {"designkit": sim.run}
    if scan["matched"] is not None:
        rt = scan["matched"]["rtol"]
        fns["dop853_matched"] = lambda: solve_ivp(rhs, (t[0], t[-1]), sim.z0[:12], method="DOP853", rtol=rt,
                                                  atol=1e-2 * rt, t_eval=t)
    fns["dop853_1e-10"] = lambda: solve_ivp(rhs, (t[0], t[-1]), sim.z0[:12], method="DOP853", rtol=1e-10,
                                            atol=1e-12, t_eval=t)
    timing = interleaved(fns, REPEAT)
    cost = evaluation_cost(sim)
    evals = sim.dopri5.stats["evaluations"] if sim.dopri5 is not None else 4 * (t.size - 1)
    floor = evals * cost["per_evaluation_s"]
    dk = timing["designkit"]["median_s"]
    return {"spec": "specs/puma560-computed-torque.yaml", "integrator": res.settings["integrator"],
            "integrator_work": res.settings.get("integrator_work"), "designkit_error_rad": ours,
            "contender_check_max_scaled_diff": check_loop(sim, rhs), "tolerance_scan": scan, "timing": timing,
            "evaluation": cost, "floor_s": floor, "evaluations": evals,
            "ratios": {"dop853_matched_over_designkit": (timing["dop853_matched"]["median_s"] / dk
                                                         if "dop853_matched" in timing else None),
                       "dop853_1e-10_over_designkit": timing["dop853_1e-10"]["median_s"] / dk,
                       "designkit_over_floor": dk / floor}}


# --------------------------------------------------------------------------- SIMNOG


def simnog() -> dict[str, Any]:
    from bench_simnog import SPEC, STEP, numpy_closed_loop

    loaded = parse_spec(SPEC)
    dsn = pipeline_design(loaded)
    sim = build(loaded.spec, dsn)
    res = sim.run()
    params = {q.name: q.value for q in dsn.plant.parameters}
    rhs = numpy_closed_loop(dsn.gains, params, STEP)["rhs"]
    t = res.time
    s0 = np.zeros(6)
    reference = solve_ivp(rhs, (t[0], t[-1]), s0, method="DOP853", rtol=2.5e-14, atol=1e-16, t_eval=t).y.T
    ours_states = np.hstack([res.state, res.controller_state])

    def err(states: np.ndarray) -> float:
        return float(np.abs(states[:, :2] - reference[:, :2]).max())

    ours = err(ours_states)
    scan = ladder(rhs, t, s0, err, ours)
    fns = {"designkit": sim.run}
    if scan["matched"] is not None:
        rt = scan["matched"]["rtol"]
        fns["dop853_matched"] = lambda: solve_ivp(rhs, (t[0], t[-1]), s0, method="DOP853", rtol=rt, atol=1e-2 * rt,
                                                  t_eval=t)
    fns["dop853_1e-10"] = lambda: solve_ivp(rhs, (t[0], t[-1]), s0, method="DOP853", rtol=1e-10, atol=1e-12,
                                            t_eval=t)
    timing = interleaved(fns, REPEAT)
    cost = evaluation_cost(sim)
    evals = sim.dopri5.stats["evaluations"] if sim.dopri5 is not None else 4 * (t.size - 1)
    floor = evals * cost["per_evaluation_s"]
    dk = timing["designkit"]["median_s"]
    return {"spec": "bench_simnog.SPEC", "integrator": res.settings["integrator"],
            "integrator_work": res.settings.get("integrator_work"), "designkit_error_rad": ours,
            "tolerance_scan": scan, "timing": timing, "evaluation": cost, "floor_s": floor, "evaluations": evals,
            "ratios": {"dop853_matched_over_designkit": (timing["dop853_matched"]["median_s"] / dk
                                                         if "dop853_matched" in timing else None),
                       "dop853_1e-10_over_designkit": timing["dop853_1e-10"]["median_s"] / dk,
                       "designkit_over_floor": dk / floor}}


def one_state(calls: int = 2000) -> dict[str, Any]:
    """One-state PUMA model calls from Python against Pinocchio on the same DH model, per call, interleaved.

    ``Robot.inverse_dynamics`` against ``pinocchio.rnea`` (the goal's ratio), and ``mass_matrix``,
    ``gravity_torque``, ``forward_dynamics`` against ``crba``, ``computeGeneralizedGravity``, ``aba``.  The
    robot's default path: its first call loads the cached library, or compiles after
    ``one_state.COMPILE_CALLS`` calls (inside the first round, so not in the medians); ``path`` says which runs.
    """
    import pinocchio as pin
    from tests.models.support import pinocchio_model

    r = robot("puma560")
    model, _ = pinocchio_model(r.description)
    data = model.createData()
    q, qd, qdd = np.random.default_rng(2).normal(size=(3, 6))
    pairs = {"inverse_dynamics": (lambda: r.inverse_dynamics(q, qd, qdd), lambda: pin.rnea(model, data, q, qd, qdd)),
             "mass_matrix": (lambda: r.mass_matrix(q), lambda: pin.crba(model, data, q)),
             "gravity_torque": (lambda: r.gravity_torque(q), lambda: pin.computeGeneralizedGravity(model, data, q)),
             "forward_dynamics": (lambda: r.forward_dynamics(q, qd, qdd), lambda: pin.aba(model, data, q, qd, qdd))}
    diff = float(np.abs(r.inverse_dynamics(q, qd, qdd) - pin.rnea(model, data, q, qd, qdd)).max())

    def repeated(fn: Callable[[], Any]) -> Callable[[], None]:
        def run() -> None:
            for _ in range(calls):
                fn()
        return run

    out: dict[str, Any] = {}
    for name, (ours, theirs) in pairs.items():
        timing = interleaved({"designkit": repeated(ours), "pinocchio": repeated(theirs)}, REPEAT)
        per = {k: v["median_s"] / calls for k, v in timing.items()}
        out[name] = {"per_call_s": per, "ratio_designkit_over_pinocchio": per["designkit"] / per["pinocchio"],
                     "path": r.one_state(name).why}
    first = out["inverse_dynamics"]
    return {**first, "max_abs_diff_Nm": diff, "functions": out}


def main() -> None:
    out = {"benchmark": "bench_floor", "puma": puma(), "simnog": simnog(), "one_state": one_state()}
    p, s = out["puma"]["ratios"], out["simnog"]["ratios"]
    out["goals"] = {
        "puma_10x_dop853_pinocchio": {"goal": GOALS["puma_vs_dop853"], "ratio": p["dop853_matched_over_designkit"],
                                      "met": bool((p["dop853_matched_over_designkit"] or 0) >= 10)},
        "puma_within_2x_floor": {"goal": GOALS["puma_vs_floor"], "ratio": p["designkit_over_floor"],
                                 "met": bool(p["designkit_over_floor"] <= 2)},
        "simnog_10x_solve_ivp": {"goal": GOALS["simnog_vs_solve_ivp"], "ratio": s["dop853_matched_over_designkit"],
                                 "met": bool((s["dop853_matched_over_designkit"] or 0) >= 10)},
        "one_state_within_2x_pinocchio": {"goal": 2.0, "ratio": out["one_state"]["ratio_designkit_over_pinocchio"],
                                          "met": bool(out["one_state"]["ratio_designkit_over_pinocchio"] <= 2)},
    }
    out["machine"] = {"platform": platform.platform(), "python": platform.python_version(), "cpus": os.cpu_count(),
                      "load": "2 cores shared with up to 7 engineers' jobs: ratios are in one run, absolute times "
                              "are not those of a quiet machine", "loadavg": os.getloadavg()}
    RESULTS.write_text(json.dumps(out, indent=1, default=float) + "\n")
    for name in ("puma", "simnog"):
        r = out[name]
        print(f"{name}: designkit {r['timing']['designkit']['median_s'] * 1e3:.2f} ms ({r['integrator_work']}); "
              f"error {r['designkit_error_rad']:.3g} rad; floor {r['floor_s'] * 1e3:.2f} ms "
              f"({r['evaluation']['per_evaluation_s'] * 1e6:.3g} us/eval); ratios {r['ratios']}")
    print(json.dumps(out["goals"], indent=1))


if __name__ == "__main__":
    main()
