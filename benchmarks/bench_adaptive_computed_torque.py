"""Benchmark: adaptive computed torque against ``solve_ivp`` at matched accuracy, in one run.

1. SIMNOG (``specs/adaptive-ct-simnog.yaml``, measured by default): the planar two-link arm under Craig's adaptive
   computed torque, m1 and m2 adapted from 7 and 4.5 kg (gain 5), an ideal accelerometer, the projection with
   hysteresis on the box; a sine of 1 and 1.2 rad at 0.5 Hz on both joints; 20 s on the 0.25 ms output grid (80,001
   points, 6 states). The loop is smooth and its projection a reset (``Law.project_resets``), so the compiled
   Dormand--Prince pair integrates it, the projection applied at every grid instant. The baseline is
   ``scipy.integrate.solve_ivp`` (RK45 and DOP853) on a NumPy right-hand side of the same loop (the arm's dynamics
   from Pinocchio's CRBA and non-linear effects, friction by hand, the m1 and m2 regressor columns as unit point
   masses at the origins of DH frames 1 and 2), checked against designkit's closed loop at random points first,
   sampled on the same grid (``t_eval``), the projection applied at the same grid instants (solve_ivp started again
   from the reset state; it acts once on this run). Matched accuracy: every trajectory is compared with DOP853 at
   ``rtol = 2.5e-14``; of a ladder of tolerances (rtol 1e-3 to 1e-13 in half decades, atol rtol/100) the cheapest
   whose errors (positions, estimates) do not exceed designkit's is timed. Goal: ``solve_ivp`` / designkit >= 10
   against both methods.
2. PUMA 560 (``--puma``): ``specs/adaptive-ct-puma560.yaml`` without the projection, shortened: the PUMA 560 with
   joint friction and rotor inertias, adapting m2, Ia1, Ia2, Ia3 from 22 kg, 1.2, 3.0, 0.9 kg*m^2 with the gain 20;
   every joint follows a 0.5 Hz sine; 10 s at ``dt = 1 ms``, ``numerics: {compile: always}``; against RK45 on a
   NumPy + Pinocchio right-hand side at matched accuracy (the ladder stops at the first match; the goal there is
   a run <= 200 ms).

Timed with ``time.perf_counter``: medians of interleaved repeats.  The machine's load average is recorded before
and after (the machine is shared: compare the ratios, each measured within one run).

Run: ``python benchmarks/bench_adaptive_computed_torque.py [--puma] [--out results.json]`` (prints the JSON and
writes ``benchmarks/results/adaptive_computed_torque.json``, or ``--out``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from designkit.families import synthesize
from designkit.models.robots import robot
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from designkit.synthesis.closed_loop import loop_functions

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.models.support import pinocchio_model  # noqa: E402  (the DH model in Pinocchio, built with NumPy)

Q0 = [0.0, 0.785, -3.1416, 0.0, 0.785, 0.0]
AMP = np.array([0.8, 0.5, -0.7, 0.5, 0.5, 0.5])
FREQ = 0.5
INITIAL = np.array([22.0, 1.2, 3.0, 0.9])
GAIN = 20.0
K1, K2, PSI = 100.0, 20.0, 0.1
SPEC = f"""\
name: adaptive-ct-bench
plant: {{kind: robot, robot: puma560, motor_inertia: true}}
controller: {{kind: adaptive_computed_torque, poles: [-10, -10], adapt: [m2, Ia1, Ia2, Ia3],
             initial: {{m2: 22.0, Ia1: 1.2, Ia2: 3.0, Ia3: 0.9}}, gain: {GAIN}}}
simulation:
  duration: 10.0
  dt: 0.001
  initial_position: {Q0}
  trajectory: {{kind: sine, amplitude: {AMP.tolist()}, frequency: {FREQ}}}
numerics: {{compile: always}}
"""
GOAL_RUN_S = 0.200
REPEAT = 5
REFERENCE_TOL = (1e-10, 1e-12)
RTOL_LADDER = tuple(10.0 ** (-k / 2) for k in range(6, 19))  # 1e-3 .. 1e-9, half decades


class Loop:
    """The adaptive loop in NumPy + Pinocchio, state ``s = (q, qd, m2^, Ia1^, Ia2^, Ia3^)``."""

    def __init__(self) -> None:
        import pinocchio as pin

        self.pin = pin
        d = robot("puma560").description
        self.model, _ = pinocchio_model(d)
        links = [dataclasses.replace(link, mass=1.0 if i == 1 else 0.0, com=(0.0, 0.0, 0.0),
                                     inertia=(0.0,) * 6) for i, link in enumerate(d.links)]
        self.point, _ = pinocchio_model(dataclasses.replace(d, links=tuple(links)))
        self.data, self.point_data = self.model.createData(), self.point.createData()
        self.fv = np.array([link.viscous for link in d.links])
        self.fc = np.array([link.coulomb for link in d.links])
        self.Ia = np.array([link.gear_ratio**2 * link.motor_inertia for link in d.links])
        self.m2 = float(d.links[1].mass)
        self.true = np.array([self.m2, *self.Ia[:3]])

    def _mass(self, model: Any, data: Any, q: np.ndarray) -> np.ndarray:
        M = self.pin.crba(model, data, q)
        return np.triu(M) + np.triu(M, 1).T

    def __call__(self, t: float, s: np.ndarray) -> np.ndarray:
        pin = self.pin
        q, qd, p = s[:6], s[6:12], s[12:]
        w = 2 * np.pi * FREQ
        qD, qDd, qDdd = Q0 + AMP * np.sin(w * t), AMP * w * np.cos(w * t), -AMP * w * w * np.sin(w * t)
        M0 = self._mass(self.model, self.data, q)
        n0 = pin.nonLinearEffects(self.model, self.data, q, qd)
        Mp = self._mass(self.point, self.point_data, q)
        npt = pin.nonLinearEffects(self.point, self.point_data, q, qd)
        friction = self.fv * qd + self.fc * np.sign(qd)
        M = M0 + np.diag(self.Ia)
        h = n0 + friction
        dm2 = p[0] - self.m2
        Ia_hat = self.Ia.copy()
        Ia_hat[:3] = p[1:]
        M_hat = M0 + dm2 * Mp + np.diag(Ia_hat)
        e, ed = qD - q, qDd - qd
        u = M_hat @ (qDdd + K1 * e + K2 * ed) + h + dm2 * npt
        qdd = np.linalg.solve(M, u - h)
        Wa = np.zeros((6, 4))
        Wa[:, 0] = Mp @ qdd + npt
        Wa[0, 1], Wa[1, 2], Wa[2, 3] = qdd[0], qdd[1], qdd[2]
        pdot = GAIN * (Wa.T @ np.linalg.solve(M_hat, e + PSI * ed))
        return np.concatenate([qd, qdd, pdot])


def initial_state() -> np.ndarray:
    return np.concatenate([Q0, np.zeros(6), INITIAL])


def ivp(f: Loop, t: np.ndarray, method: str, rtol: float, atol: float) -> tuple[np.ndarray, int]:
    sol = solve_ivp(f, (float(t[0]), float(t[-1])), initial_state(), method=method, rtol=rtol, atol=atol, t_eval=t)
    if not sol.success:
        raise RuntimeError(f"solve_ivp {method} rtol={rtol:g}: {sol.message}")
    return sol.y.T, sol.nfev


def errors(states: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    """Largest absolute errors on the grid: joint positions (rad) and estimates (kg, kg*m^2)."""
    e = np.abs(states - reference).max(axis=0)
    return {"position_rad": float(e[:6].max()), "m2_kg": float(e[12]), "Ia_kg_m2": float(e[13:16].max())}


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, dict[str, float]]:
    """Median and min wall time of each function, timed round-robin."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: {"median_s": statistics.median(v), "min_s": min(v), "repeats": repeat} for k, v in times.items()}


def check_rhs(design: Any, f: Loop, rng: np.random.Generator, n: int = 100) -> float:
    """Largest relative difference of the NumPy right-hand side from designkit's closed loop at random points."""
    fns = loop_functions(design.plant, design.law)
    p = design.plant.model_parameters()
    worst = 0.0
    w = 2 * np.pi * FREQ
    for _ in range(n):
        t = float(rng.uniform(0, 10))
        s = np.concatenate([np.asarray(Q0) + rng.uniform(-0.5, 0.5, 6), rng.uniform(-1, 1, 6),
                            INITIAL * rng.uniform(0.8, 1.2, 4)])
        r = np.concatenate([Q0 + AMP * np.sin(w * t), AMP * w * np.cos(w * t), -AMP * w * w * np.sin(w * t)])
        theirs = np.asarray(fns.loop(s, r, np.zeros(6), p)[0], dtype=float).ravel()
        ours = f(t, s)
        worst = max(worst, float(np.abs(ours - theirs).max() / max(1.0, np.abs(theirs).max())))
    return worst


SIMNOG_SPEC = ROOT / "specs" / "adaptive-ct-simnog.yaml"
SIMNOG_AMP = np.array([1.0, 1.2])
SIMNOG_TRUE = np.array([5.0, 3.0])
SIMNOG_GAIN = 5.0
REFERENCE_TOL_SIMNOG = (2.5e-14, 2.5e-16)
RTOL_LADDER_SIMNOG = tuple(10.0 ** (-k / 2) for k in range(6, 27))  # 1e-3 .. 1e-13, half decades


class SimnogLoop:
    """``specs/adaptive-ct-simnog.yaml``'s loop in NumPy + Pinocchio, state ``s = (q, qd, m1^, m2^)``: the planar
    arm's CRBA and non-linear effects, joint friction by hand, the m1 and m2 columns of the regressor as the
    dynamics of a unit point mass at the origin of DH frame 1 and 2 (the regressor's parameters: a link's mass,
    first moment and inertia about its frame; the first moments and inertias known), Craig's law with the ideal
    accelerometer (``simnog`` applies the projection between integrations)."""

    def __init__(self) -> None:
        import pinocchio as pin

        self.pin = pin
        d = robot("planar2r").description
        self.model, _ = pinocchio_model(d)
        self.data = self.model.createData()
        self.units = []
        for i in range(2):
            links = tuple(dataclasses.replace(link, mass=1.0 if j == i else 0.0, com=(0.0, 0.0, 0.0),
                                              inertia=(0.0,) * 6) for j, link in enumerate(d.links))
            m, _ = pinocchio_model(dataclasses.replace(d, links=links))
            self.units.append((m, m.createData()))
        self.fv = np.array([link.viscous for link in d.links])

    def _mass(self, model: Any, data: Any, q: np.ndarray) -> np.ndarray:
        M = self.pin.crba(model, data, q)
        return np.triu(M) + np.triu(M, 1).T

    def __call__(self, t: float, s: np.ndarray) -> np.ndarray:
        pin = self.pin
        q, qd, p = s[:2], s[2:4], s[4:]
        w = 2 * np.pi * FREQ
        qD, qDd, qDdd = SIMNOG_AMP * np.sin(w * t), SIMNOG_AMP * w * np.cos(w * t), -SIMNOG_AMP * w * w * np.sin(w * t)
        M = self._mass(self.model, self.data, q)
        h = pin.nonLinearEffects(self.model, self.data, q, qd) + self.fv * qd
        Mu = [self._mass(m, dd, q) for m, dd in self.units]
        nu = [pin.nonLinearEffects(m, dd, q, qd) for m, dd in self.units]
        dp = p - SIMNOG_TRUE
        M_hat = M + dp[0] * Mu[0] + dp[1] * Mu[1]
        h_hat = h + dp[0] * nu[0] + dp[1] * nu[1]
        e, ed = qD - q, qDd - qd
        u = M_hat @ (qDdd + K1 * e + K2 * ed) + h_hat
        qdd = np.linalg.solve(M, u - h)
        Wa = np.stack([Mu[k] @ qdd + nu[k] for k in range(2)], axis=1)
        pdot = SIMNOG_GAIN * (Wa.T @ np.linalg.solve(M_hat, e + PSI * ed))
        return np.concatenate([qd, qdd, pdot])


def check_simnog_rhs(design: Any, f: SimnogLoop, rng: np.random.Generator, n: int = 100) -> float:
    """Largest relative difference of the NumPy right-hand side from designkit's closed loop at random points."""
    fns = loop_functions(design.plant, design.law)
    p = design.plant.model_parameters()
    worst = 0.0
    w = 2 * np.pi * FREQ
    for _ in range(n):
        t = float(rng.uniform(0, 20))
        s = np.concatenate([rng.uniform(-1.5, 1.5, 2), rng.uniform(-2, 2, 2), SIMNOG_TRUE * rng.uniform(0.8, 1.5, 2)])
        r = np.concatenate([SIMNOG_AMP * np.sin(w * t), SIMNOG_AMP * w * np.cos(w * t),
                            -SIMNOG_AMP * w * w * np.sin(w * t)])
        theirs = np.asarray(fns.loop(s, r, np.zeros(2), p)[0], dtype=float).ravel()
        worst = max(worst, float(np.abs(f(t, s) - theirs).max() / max(1.0, np.abs(theirs).max())))
    return worst


def simnog() -> dict[str, Any]:
    """The SIMNOG scenario (module docstring, second part)."""
    spec = parse_spec(SIMNOG_SPEC.read_text()).spec
    design = synthesize(spec)
    sim = build(spec, design)
    result = sim.run()
    t = np.asarray(result.time)
    ours = np.hstack([result.state, result.controller_state])
    f = SimnogLoop()
    rhs_diff = check_simnog_rhs(design, f, np.random.default_rng(0))
    assert rhs_diff < 1e-9, f"the NumPy loop is not designkit's (largest relative difference {rhs_diff:g})"
    s0 = ours[0].copy()
    lo, hi, delta = np.array([4.0, 2.5]), np.array([10.0, 6.0]), 0.05
    resets = int(np.sum((ours[1:, 4:] == lo) | (ours[1:, 4:] == hi)))

    def ivp_s(method: str, rtol: float, atol: float) -> tuple[np.ndarray, int]:
        """solve_ivp over the grid, the projection applied at the grid instants: from the first grid point where an
        estimate has left its box by delta, reset into it and integrated again from there."""
        out, k, s, nfev = np.empty((t.size, s0.size)), 0, s0, 0
        while True:
            sol = solve_ivp(f, (float(t[k]), float(t[-1])), s, method=method, rtol=rtol, atol=atol, t_eval=t[k:])
            if not sol.success:
                raise RuntimeError(f"solve_ivp {method} rtol={rtol:g}: {sol.message}")
            Y, nfev = sol.y.T, nfev + sol.nfev
            left = np.flatnonzero(np.any((Y[1:, 4:] <= lo - delta) | (Y[1:, 4:] >= hi + delta), axis=1))
            if left.size == 0:
                out[k:] = Y
                return out, nfev
            j = k + 1 + int(left[0])
            out[k:j] = Y[:j - k]
            s = Y[j - k].copy()
            s[4:] = np.where(s[4:] <= lo - delta, lo, np.where(s[4:] >= hi + delta, hi, s[4:]))
            out[j], k = s, j

    def errs(states: np.ndarray, reference: np.ndarray) -> dict[str, float]:
        e = np.abs(states - reference).max(axis=0)
        return {"position_rad": float(e[:2].max()), "estimates_kg": float(e[4:].max())}

    reference, ref_nfev = ivp_s("DOP853", *REFERENCE_TOL_SIMNOG)
    dk_err = errs(ours, reference)
    chosen = {}
    ladders = {}
    for method in ("RK45", "DOP853"):
        ladder = []
        for rtol in RTOL_LADDER_SIMNOG:
            states, nfev = ivp_s(method, rtol, 1e-2 * rtol)
            row = {"rtol": rtol, "atol": 1e-2 * rtol, "nfev": nfev, "errors": errs(states, reference)}
            ladder.append(row)
            if all(row["errors"][k] <= dk_err[k] for k in dk_err):
                break
        ok = [row for row in ladder if all(row["errors"][k] <= dk_err[k] for k in dk_err)]
        chosen[method] = (min(ok, key=lambda row: row["nfev"]) if ok else ladder[-1], bool(ok))
        ladders[method] = ladder
    fns = {"designkit_run_warm": sim.run}
    for method, (row, _) in chosen.items():
        fns[f"solve_ivp_{method.lower()}_matched"] = (
            lambda m=method, r=row: ivp_s(m, r["rtol"], r["atol"]))
    timings = interleaved(fns, REPEAT)
    run_s = timings["designkit_run_warm"]["median_s"]
    ratios = {m: timings[f"solve_ivp_{m.lower()}_matched"]["median_s"] / run_s for m in chosen}
    return {
        "scenario": {"spec": str(SIMNOG_SPEC.relative_to(ROOT)), "output_points": int(t.size),
                     "dt_s": float(result.settings["dt"]), "states": int(ours.shape[1])},
        "integrator": str(result.settings["integrator"]),
        "integrator_work": dict(sim.dopri5.stats) if sim.dopri5 is not None else None,
        "checks": {"numpy_rhs_vs_designkit_max_rel_diff": rhs_diff},
        "projection_resets_in_designkit_run": resets,
        "accuracy_vs_dop853_2.5e-14": {"designkit": dk_err,
                                       "solve_ivp_chosen": {m: {**r, "matched": ok} for m, (r, ok) in chosen.items()},
                                       "ladders": ladders, "reference_nfev": ref_nfev},
        "timings": timings,
        "ratio_solve_ivp_over_designkit": ratios,
        "goal_ratio": 10.0,
        "goal_met": bool(min(ratios.values()) >= 10.0),
    }


def puma() -> dict[str, Any]:
    spec = parse_spec(SPEC).spec
    design = synthesize(spec)
    t0 = time.perf_counter()
    sim = build(spec, design)
    first_build = time.perf_counter() - t0
    result = sim.run()
    t = np.asarray(result.time)
    ours = np.hstack([result.state, result.controller_state])
    f = Loop()
    rhs_diff = check_rhs(design, f, np.random.default_rng(0))

    reference, ref_nfev = ivp(f, t, "DOP853", *REFERENCE_TOL)
    dk_err = errors(ours, reference)
    ladder = []
    for rtol in RTOL_LADDER:
        states, nfev = ivp(f, t, "RK45", rtol, 1e-3 * rtol)
        row = {"rtol": rtol, "atol": 1e-3 * rtol, "nfev": nfev, "errors": errors(states, reference)}
        ladder.append(row)
        if all(row["errors"][k] <= dk_err[k] for k in dk_err):
            break
    ok = [row for row in ladder if all(row["errors"][k] <= dk_err[k] for k in dk_err)]
    chosen = min(ok, key=lambda row: row["nfev"]) if ok else ladder[-1]

    fns = {
        "designkit_run_warm": sim.run,
        "solve_ivp_rk45_matched": lambda: ivp(f, t, "RK45", chosen["rtol"], chosen["atol"]),
    }
    timings = interleaved(fns, REPEAT)
    run_s = timings["designkit_run_warm"]["median_s"]
    base_s = timings["solve_ivp_rk45_matched"]["median_s"]
    out = {
        "integrator": str(result.settings["integrator"]),
        "scenario": {"spec": SPEC, "steps": int(t.size - 1), "dt_s": float(result.settings["dt"]),
                     "states": int(ours.shape[1])},
        "compiled": dict(sim.compiled),
        "first_build_s": first_build,
        "checks": {"numpy_rhs_vs_designkit_max_rel_diff": rhs_diff},
        "accuracy_vs_dop853_1e-10": {"designkit": dk_err, "solve_ivp_chosen": chosen,
                                     "matched": bool(ok), "ladder": ladder, "reference_nfev": ref_nfev},
        "timings": timings,
        "goal": {"run_s": GOAL_RUN_S, "met": bool(run_s <= GOAL_RUN_S)},
        "ratio_solve_ivp_over_designkit": base_s / run_s,
        "machine": {"python": platform.python_version(), "machine": platform.machine(),
                    "casadi": metadata.version("casadi"), "scipy": metadata.version("scipy")},
        "summary": (f"Simulator.run() warm {1e3 * run_s:.1f} ms median (goal {1e3 * GOAL_RUN_S:.0f} ms: "
                    f"{'met' if run_s <= GOAL_RUN_S else 'not met'}), "
                    f"{'compiled' if sim.compiled.get('compiled') else 'interpreted'}; "
                    f"solve_ivp RK45 at {'matched' if ok else 'the tightest tried (not matched)'} accuracy "
                    f"(rtol {chosen['rtol']:.3g}, {chosen['nfev']} evaluations) {1e3 * base_s:.0f} ms: "
                    f"{base_s / run_s:.0f} x"),
    }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--puma", action="store_true", help="also the PUMA 560 scenario")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "adaptive_computed_torque.json",
                        help="where to write the JSON")
    args = parser.parse_args()
    load_before = os.getloadavg()
    out: dict[str, Any] = {"simnog": simnog()}
    if args.puma:
        out["puma560"] = puma()
    out["load_average_before_after"] = [round(load_before[0], 2), round(os.getloadavg()[0], 2)]
    out["machine"] = {"python": platform.python_version(), "machine": platform.machine(), "cores": os.cpu_count(),
                      "casadi": metadata.version("casadi"), "scipy": metadata.version("scipy")}
    text = json.dumps(out, indent=2)
    print(text)
    args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
