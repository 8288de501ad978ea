"""The robot form's checks (the link's names, run by :mod:`~designkit.families.sliding_mode_identification.checks`
on a robot), on the run recomputed from the record
(:mod:`~designkit.families.sliding_mode_identification.arm_analysis`).

``switching_condition``: each joint's switching gain ``k_j`` above the largest error of the observer's model term,
``|[Mh^-1 (u - hh)]_j - qdd_j|``, the true arm's forward dynamics at the sample's state and command (after a
``simulation.plant_change``, the new arm's).

``identification_lyapunov``: on each segment with a fixed arm, ``V = theta~' Gamma^-1 theta~`` obeys the sampled
inequality ``V(k) - V(k-1) <= (Ts/m2) (-2 |e|^2 + 2 |e| |r| + s (|e| + |r|)^2)`` at every sample (to :data:`V_TOL`
of ``V`` at the segment's start), with the sampled step ``s < 2``: so ``V`` does not increase at any sample where
``|e| >= x*(s) |r|``, and the band where it may is reported with its largest rise.

``determinant_condition`` (generalised): at one instant ``Phi`` has rank at most ``2n``; with more parameters the
pointwise determinant of section 5.5 vanishes identically, so the condition is judged over windows of
:data:`WINDOW_FACTOR` ``D``: a window excites every direction when its contraction ``kappa`` (the largest
``V(end)/V(start)`` the update can leave, for any error) is at most ``1 -`` :data:`~.checks.DET_REL`; the condition
holds when at least :data:`~.checks.DET_FRACTION` of the windows do.  The smallest eigenvalue of
``Gamma^1/2 Gbar Gamma^1/2`` (``Gbar`` the window's mean two-point information matrix) is reported with it.

``identification_convergence``: every identified parameter within :data:`~.checks.CONVERGED_REL` of its true value at
the end, measured against ``max(|theta_i|, 0.01 s_i)`` with ``s_i = rms(u)/rms(Y_i)`` over the last segment (the
value of ``theta_i`` that alone would carry the rms torque: a parameter whose true value is 0, a Coulomb friction
the arm does not have, is judged by the torque its error adds, :data:`ZERO_SCALE`).  Required when the last
segment's contraction is at most ``exp(-2`` :data:`~.checks.EFOLDS` ``)`` (every direction's error shrinks by
``e^-5`` at least).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.numbers import unit
from designkit.families.sliding_mode_identification.arm import parameter_unit
from designkit.families.sliding_mode_identification.arm_analysis import (
    ArmRun,
    arm_run,
    band_factor,
    counted,
    segment_rate,
    segments_of,
    window_rates,
)
from designkit.families.sliding_mode_identification.checks import CONVERGED_REL, DET_FRACTION, DET_REL, EFOLDS
from designkit.verification.check import Check

__all__ = ["V_TOL", "WINDOW_FACTOR", "ZERO_SCALE", "determinant_condition", "diagnose", "identification_convergence",
           "identification_lyapunov", "run_of", "switching_condition", "tolerances"]

V_TOL = 1e-9
"""The sampled inequality of ``V`` holds to this fraction of ``V`` at the segment's start (rounding)."""
WINDOW_FACTOR = 20
"""The excitation windows last this many ``D``."""
ZERO_SCALE = 0.01
"""A parameter is judged against ``max(|theta_i|, ZERO_SCALE s_i)``: one whose true value is 0 (a Coulomb
friction the arm does not have) must end with an error adding at most ``CONVERGED_REL ZERO_SCALE`` (0.02 %) of the
rms torque."""

_CACHE: dict[int, tuple[Any, ArmRun]] = {}


def run_of(design: Any, ctx_or_result: Any) -> ArmRun:
    """The recomputed run (cached per simulation record)."""
    sim = ctx_or_result.simulation
    plant = ctx_or_result.plant if getattr(ctx_or_result, "plant", None) is not None else design.plant
    spec = ctx_or_result.spec if hasattr(ctx_or_result, "spec") else ctx_or_result.loaded.spec
    key = id(sim)
    hit = _CACHE.get(key)
    if hit is None or hit[0] is not sim:
        _CACHE.clear()
        _CACHE[key] = (sim, arm_run(design, spec, plant, sim))
    return _CACHE[key][1]


def _f(x: float | None, digits: int = 4) -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def _json(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _spec(ctx: Any) -> Any:
    return ctx.spec


def switching_condition(design: Any, ctx: Any) -> tuple[Check, ...]:
    """``k_j > max |model_j - qdd_j|`` per joint (module docstring)."""
    run = run_of(design, ctx)
    k = np.asarray(run.ident.switching, dtype=float)
    err = np.abs(run.true_accel_error[1:]) if len(run.t) > 1 else np.zeros((0, k.size))
    worst = err.max(axis=0) if err.size else np.zeros(k.size)
    at = [float(run.t[1:][int(np.argmax(err[:, j]))]) if err.size else 0.0 for j in range(k.size)]
    ok = bool(np.all(k > worst)) and bool(np.all(np.isfinite(worst)))
    ratio = float(np.min(np.where(worst > 0, k / np.maximum(worst, 1e-300), np.inf)))
    joints = "; ".join(f"joint {j + 1}: {_f(float(worst[j]))} rad/s² at t = {at[j]:.3g} s "
                       f"(k{j + 1} = {_f(float(k[j]))} rad/s²)" for j in range(k.size))
    detail = (f"largest error of the estimated model's acceleration M̂⁻¹(u − ĥ) against the true arm's along the run: "
              f"{joints}; the observers' condition {'holds' if ok else 'is violated'}")
    cert = {"max_model_error": worst.tolist(), "at_s": at, "gains": k.tolist(),
            "chattering_band": (run.ident.Ts * k).tolist()}
    return (Check("switching_condition", ok, "> 1 (min over the joints of k_j / max |model_j − q̈_j|)", _json(ratio),
                  _json(ratio - 1.0), "1 (ratio)", detail, cert),)


def identification_lyapunov(design: Any, ctx: Any) -> tuple[Check, ...]:
    """The sampled inequality of ``V`` and ``s < 2`` on every fixed-arm segment (module docstring)."""
    run = run_of(design, ctx)
    worst, where, rises, rise_max, band_n, total, r_max = -math.inf, None, 0, 0.0, 0, 0, 0.0
    band = run.e < band_factor(run.step) * run.r
    for m in segments_of(_spec(ctx), run.t, run.ident.window, run.ident.Ts):
        idx = np.flatnonzero(m)
        idx = idx[1:] if idx.size and idx[0] == 0 else idx
        if idx.size == 0:
            continue
        v0 = max(float(run.V[idx[0] - 1]), 1e-300)
        excess = (run.dV[idx] - run.bound[idx]) / v0
        j = int(np.argmax(excess))
        if excess[j] > worst:
            worst, where = float(excess[j]), float(run.t[idx[j]])
        up = run.dV[idx] > V_TOL * v0
        rises += int(np.sum(up & ~band[idx]))
        band_n += int(np.sum(band[idx]))
        r_max = max(r_max, float(np.max(run.r[idx])))
        total += idx.size
        if np.any(up):
            rise_max = max(rise_max, float(np.max(run.dV[idx][up])) / v0)
    step = float(np.max(run.step)) if run.step.size else 0.0
    finite = bool(np.all(np.isfinite(run.V)))
    ok = bool(worst <= V_TOL) and step < 2 and rises == 0 and finite
    normalised = float(np.mean(run.m2 > 1.0)) if run.m2.size else 0.0
    detail = (f"V = (θ − θ̂)ᵀ Γ⁻¹ (θ − θ̂) from {_f(float(run.V[0]))} to {_f(float(run.V[-1]))} N²·m²·s; at every "
              f"sample of the segments with a fixed arm V(k) − V(k−1) ≤ (Ts/m²)(−2|e|² + 2|e||r| + s(|e| + |r|)²) "
              f"{'holds' if worst <= V_TOL else 'fails'} (the left side minus the right is at most {_f(worst, 3)} "
              f"of V at the segment's start, {V_TOL:g} allowed for rounding); the sampled step "
              f"s = Ts λmax(Γ½ Φ Γ½)/m² peaks at {_f(step, 3)} (V decreases "
              f"only below 2; the normalisation m² > 1 acted on {_f(100 * normalised, 3)} % of the samples, the step "
              f"without it peaks at {_f(float(np.max(run.raw_step)) if run.raw_step.size else 0.0, 3)}); "
              f"V rose at {rises} samples outside the residual band |e| < x*(s)|r| and lies in it at "
              f"{_f(100 * band_n / max(total, 1), 3)} % of them (residual torque |r| up to "
              f"{_f(r_max, 3)} N·m)")
    if rise_max > 0:
        detail += f"; its largest rise, inside the band, is {_f(rise_max, 3)} of V at the segment's start"
    if where is not None and worst > V_TOL:
        detail += f"; the inequality fails at t = {where:.4g} s"
    detail += (f"; the recorded torque errors agree with their recomputation from the record to {_f(run.eps_gap, 2)} "
               "N·m")
    cert = {"V_initial": _json(float(run.V[0])), "V_final": _json(float(run.V[-1])), "largest_excess": _json(worst),
            "at_s": where, "sampled_step_peak": step, "sampled_step_limit": 2.0, "rises_outside_band": rises,
            "band_fraction": band_n / max(total, 1), "largest_rise_in_band": rise_max,
            "normalised_fraction": normalised, "recorded_error_gap": run.eps_gap}
    target = (f"≤ {V_TOL:g} (excess of V(k) − V(k−1) over its sampled bound, in V0; with s < 2 and no rise outside "
              "the residual band)")
    return (Check("identification_lyapunov", ok, target, _json(worst), _json(V_TOL - worst), "1 (relative)", detail,
                  cert),)


def _least_excited(run: ArmRun, mask: np.ndarray) -> tuple[str, ...]:
    """The identified parameters weighing most in the least excited direction of the segment."""
    idx = counted(run, mask)
    if idx.size == 0:
        return run.ident.names
    root = np.sqrt(np.asarray(run.ident.gamma, dtype=float))
    with np.errstate(all="ignore"):
        G = (run.phi[idx] / run.m2[idx, None, None]).mean(axis=0)
        H = root[:, None] * G * root[None, :]
    if not np.all(np.isfinite(H)):  # a diverged run: no direction can be told apart
        return run.ident.names
    _, vec = np.linalg.eigh(H)
    w = np.abs(vec[:, 0])
    return tuple(run.ident.names[i] for i in np.argsort(w)[::-1] if w[i] >= 0.3 * w.max())


def determinant_condition(design: Any, ctx: Any) -> tuple[Check, ...]:
    """Every direction excited over windows of :data:`WINDOW_FACTOR` ``D`` (module docstring)."""
    run = run_of(design, ctx)
    length = WINDOW_FACTOR * run.ident.window
    kappas, rates = [], []
    for m in segments_of(_spec(ctx), run.t, run.ident.window, run.ident.Ts):
        _, k, rate = window_rates(run, m, length)
        kappas += k.tolist()
        rates += rate.tolist()
    kappa = np.asarray(kappas)
    frac = float(np.mean(kappa <= 1 - DET_REL)) if kappa.size else 0.0
    ok = bool(kappa.size > 0 and frac >= DET_FRACTION)
    p, n = len(run.ident.names), run.ident.n
    detail = (f"over {kappa.size} windows of {length:g} s (20 D) after the first D, every direction of the {p} "
              f"identified parameters is excited (V shrinks by at least {100 * DET_REL:g} % over the window whatever "
              f"the error) in {_f(100 * frac, 3)} % of them")
    if kappa.size:
        detail += (f" (contraction κ from {_f(float(kappa.min()), 3)} to {_f(float(kappa.max()), 3)}: the best window "
                   f"shrinks V by {_f(100 * (1 - float(kappa.min())), 3)} % at least, {100 * DET_REL:g} % needed; the "
                   "smallest "
                   f"eigenvalue of Γ½ Ḡ Γ½ per window from {_f(max(min(rates), 0.0), 3)} to {_f(max(rates), 3)} 1/s)")
    if p > 2 * n:
        detail += (f"; at one instant the two-point information matrix has rank at most 2n = {2 * n} < {p}, so §5.5's "
                   "pointwise determinant vanishes identically and the condition is judged over windows")
    weakest = ()
    if not ok:
        weakest = _least_excited(run, segments_of(_spec(ctx), run.t, run.ident.window, run.ident.Ts)[-1])
        detail += ("; the least excited direction is mostly " + ", ".join(weakest) + ": the motion does not tell "
                   "these parameters apart")
    cert = {"window_s": length, "windows": int(kappa.size), "fraction": frac, "kappa": kappa.tolist(),
            "rate_per_window": rates, "threshold": 1 - DET_REL, "least_excited": list(weakest)}
    target = f"≥ {DET_FRACTION:g} (fraction of the {length:g}-s windows exciting every direction, κ ≤ {1 - DET_REL:g})"
    return (Check("determinant_condition", ok, target, frac, frac - DET_FRACTION, "1 (fraction)", detail, cert),)


def tolerances(run: ArmRun, mask: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``max(|theta_i|, ZERO_SCALE s_i)``, ``s_i = rms(u)/rms(Y_i)`` over the counted samples of ``mask`` (module
    docstring)."""
    idx = counted(run, mask)
    theta = np.abs(run.theta[-1])
    if idx.size == 0:
        return np.maximum(theta, 1e-300)
    col = np.sqrt(np.einsum("kpp->kp", run.phi[idx]).mean(axis=0) / 2.0)  # rms of Y_i over the joints and points
    torque = float(np.sqrt(np.mean(np.sum(u[idx] ** 2, axis=1))))
    scale = np.where(col > 0, torque / np.maximum(col, 1e-300), np.inf)
    return np.maximum(theta, ZERO_SCALE * scale)


def identification_convergence(design: Any, ctx: Any) -> tuple[Check, ...]:
    """Every identified parameter within :data:`~.checks.CONVERGED_REL` at the end (module docstring)."""
    run = run_of(design, ctx)
    sim = ctx.simulation
    last = segments_of(_spec(ctx), run.t, run.ident.window, run.ident.Ts)[-1]
    kappa, rate, span = segment_rate(run, last)
    efolds = -0.5 * math.log(max(kappa, 1e-300))
    excited = bool(efolds >= EFOLDS)
    u = np.asarray(sim.u_command, dtype=float)[run.rows]
    scale = tolerances(run, last, u)
    err = run.estimate[-1] - run.theta[-1]
    rel = np.abs(err) / scale
    k = int(np.argmax(rel))
    ok = bool(np.all(rel <= CONVERGED_REL))
    names = run.ident.names
    detail = (f"{int(np.sum(rel <= CONVERGED_REL))} of {len(names)} identified parameters within "
              f"{100 * CONVERGED_REL:g} % at the end; the furthest is {names[k]} = {_f(float(run.estimate[-1, k]))} "
              f"against {_f(float(run.theta[-1, k]))} {unit(parameter_unit(names[k]))} "
              f"({_f(100 * float(rel[k]), 3)} % of {_f(float(scale[k]), 3)}); over the last segment the update "
              f"contracts every error by at least κ = {_f(kappa, 3)} in V ({_f(efolds, 3)} time constants of the "
              "slowest direction; averaged rate "
              f"{_f(rate, 3)} 1/s over {span:.4g} s)")
    detail += (f" (≥ {EFOLDS:g}: convergence expected)" if excited else
               f" (< {EFOLDS:g}: the excitation does not justify expecting convergence; reported)")
    cert = {"names": list(names), "final": run.estimate[-1].tolist(), "true": run.theta[-1].tolist(),
            "scale": scale.tolist(), "relative_error": rel.tolist(), "kappa": kappa, "efolds": efolds,
            "averaged_rate": rate, "excited": excited}
    target = f"≤ {CONVERGED_REL:g} (largest error relative to max(|θi|, {ZERO_SCALE:g} rms u / rms Yi))"
    return (Check("identification_convergence", ok, target, float(rel.max()), CONVERGED_REL - float(rel.max()),
                  "1 (relative)", detail, cert, required=excited),)


def diagnose(result: Any, check: Any) -> tuple[str, str] | None:
    """Why a robot-form identification check failed, and what would fix it."""
    c = check.certificate
    if check.name == "switching_condition":
        need = ", ".join(f"k{j + 1} > {1.5 * e:.4g}" for j, e in enumerate(c["max_model_error"]))
        return ("An observer's switching gain is below the error of the estimated model's acceleration it must "
                "dominate, so its sliding variable leaves zero: " + check.detail + ".",
                f"Use controller.switching_gain with {need} rad/s² (1.5 times the errors of this run), or start "
                "from initial estimates closer to the arm (the model error shrinks with the estimation error). The "
                "estimates themselves do not depend on it: the acceleration is the sample-exact equivalent control.")
    if check.name == "determinant_condition":
        weak = ", ".join(c.get("least_excited") or ()) or "some parameters"
        return ("The arm's motion does not excite every direction of the identified parameters within the windows: "
                + check.detail + ".",
                f"Move every joint through a range of speeds and accelerations (a multisine reference with an "
                f"amplitude on each joint, e.g. simulation.trajectory: {{kind: multisine, amplitude: [1.0, 1.2], "
                f"period: 5, harmonics: 3}}), or identify fewer parameters: leave {weak} out of "
                "controller.identify (known at the model's values).")
    if check.name == "identification_convergence":
        return ("The estimates did not reach the arm's base parameters although the excitation justifies it: "
                + check.detail + ".", "Run longer or raise the adaptation gains; check the Lyapunov and switching "
                "checks.")
    if check.name == "identification_lyapunov":
        return ("The Lyapunov function of the estimation error does not obey its sampled bound: " + check.detail
                + ".", "Lower the adaptation gains or the sampling period so that the sampled step stays below 2.")
    return None
