"""The self-tuning regulator's own checks, on the sampled run (its contract has no continuous linear loop).

``characteristic_polynomial`` (order 130, required): at every sample where the controller was redesigned,
the closed-loop characteristic polynomial of the *estimated* model, ``A R + B S`` (pole placement) or
``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3`` on the estimated link (PID), equals the requested one
to :data:`POLY_TOL` (relative to its largest coefficient); also says how many samples held the previous
controller and the Sylvester matrix's condition number along the run.

``excitation`` (order 131, required): the smallest eigenvalue of the information matrix ``sum phi phi'``
over the last ``controller.excitation_window``, scaled to a unit diagonal (dimensionless, 0 when the
regressors are collinear), at least :data:`EXCITATION_MIN`: below it the estimator has lost excitation
and its estimates are not determined by the data -- reported, not silently trusted.

``estimate_convergence`` (order 132): the final estimates against the exactly discretized parameters of
the final true link, each within :data:`CONVERGED_REL`; required when the excitation check passes.

``parameter_step`` (order 133, with ``simulation.plant_change``, required): after the change, the time the
estimates take to come within :data:`CONVERGED_REL` of the new link's parameters and stay there.

``true_loop`` (order 134, pole placement, required when the estimates converged): the discrete closed loop of
the *true* sampled link under the final controller, its poles mapped to ``s = ln(z)/Ts`` against the
requested ones (and the observer pole) within :data:`POLE_REL`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.self_tuning.arx_runs import arx_true_loop_poles, wanted_poles
from designkit.families.self_tuning.laws import KIND
from designkit.families.self_tuning.runs import (
    characteristic_error,
    designed_response,
    excitation,
    position_models,
    samples,
    sylvester_condition,
    true_theta,
)
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context

__all__ = ["CONVERGED_REL", "EXCITATION_MIN", "POLE_REL", "POLY_TOL", "RULES", "diagnose", "true_loop_poles"]

POLY_TOL = 1e-8
"""Largest relative coefficient error of the estimated closed-loop polynomial."""
EXCITATION_MIN = 1e-4
"""Smallest accepted normalized eigenvalue of the windowed information matrix."""
CONVERGED_REL = 0.05
"""Converged: every estimate within this fraction of its true value."""
POLE_REL = 0.10
"""The true loop's poles (as ``ln z / Ts``) within this fraction of the requested ones."""
POLE_Z = 0.05
"""ARX form: the true loop's poles within this distance of the requested ones in the z-plane."""


def _applies(design: Any, ctx: Context) -> bool:
    return design.kind == KIND and ctx.simulation is not None


def _f(x: float | None, digits: int = 4) -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def _window(design: Any) -> int:
    return max(1, int(round(design.data.excitation_window / design.data.settings.Ts)))


def _pid_error(s: Any, design: Any) -> np.ndarray:
    x = design.data
    m = position_models(s.theta, x.settings.Ts, x.settings.form)
    a = np.clip(s.theta[:, 0], 1e-9, 1 - 1e-12)
    tau = -x.settings.Ts / np.log(a)
    Km = (m[:, 2] + m[:, 3]) / (x.settings.Ts * (1 - a))
    K1, K2, K3 = s.coefs[:, 0], s.coefs[:, 1], s.coefs[:, 2]
    got = np.column_stack([(1 + Km * K2) / tau, Km * K1 / tau, Km * K3 / tau])
    want = np.real(np.poly(list(x.settings.poles)))[1:]
    err = np.max(np.abs(got - want), axis=1) / max(1.0, float(np.max(np.abs(want))))
    err[s.held] = np.nan
    return err


def _characteristic(design: Any, ctx: Context) -> tuple[Check, ...]:
    s = samples(ctx.simulation, design)
    pp = design.data.settings.design == "pole_placement"
    err = characteristic_error(s, design) if pp else _pid_error(s, design)
    cond = sylvester_condition(s, design)
    finite = err[np.isfinite(err)]
    worst = float(finite.max()) if finite.size else float("nan")
    held = int(s.held.sum())
    diverged = not np.all(np.isfinite(s.theta))
    passed = bool(finite.size) and worst <= POLY_TOL and not diverged
    what = "A R + B S of the estimated model" if pp else "the PID loop's polynomial on the estimated link"
    detail = (f"{what} against the requested one over {finite.size} redesigns: largest relative coefficient error "
              f"{_f(worst, 3)} (at most {POLY_TOL:g}); {held} of {len(s.t)} samples kept the previous controller; "
              f"Sylvester condition number {_f(float(np.nanmin(cond)) if cond.size else None, 3)} to "
              f"{_f(float(np.nanmax(cond)) if cond.size else None, 3)}, {_f(float(cond[-1]) if cond.size else None, 3)}"
              " at the end")
    if diverged:
        detail += "; the estimates are not finite (the estimator diverged)"
    cert = {"max_error": worst if math.isfinite(worst) else None, "redesigns": int(finite.size), "held": held,
            "samples": len(s.t), "sylvester_condition": {"min": _num(np.nanmin(cond)), "max": _num(np.nanmax(cond)),
                                                         "final": _num(cond[-1])} if cond.size else None}
    return (Check("characteristic_polynomial", passed, f"≤ {POLY_TOL:g}", worst if math.isfinite(worst) else None,
                  POLY_TOL - worst if math.isfinite(worst) else None, "", detail, cert,
                  data={"t": s.t, "error": err, "condition": cond}),)


def _num(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def excitation_summary(design: Any, ctx: Context) -> dict[str, Any]:
    """The indicator over the run and its value over the last window."""
    s = samples(ctx.simulation, design)
    w = _window(design)
    lam, norm = excitation(s, w)
    return {"samples": s, "window": w, "lam": lam, "norm": norm,
            "final": float(norm[-1]) if norm.size and np.isfinite(norm[-1]) else float("nan"),
            "final_lam": float(lam[-1]) if lam.size and np.isfinite(lam[-1]) else float("nan")}


def _excitation(design: Any, ctx: Context) -> tuple[Check, ...]:
    e = excitation_summary(design, ctx)
    v = e["final"]
    passed = math.isfinite(v) and v >= EXCITATION_MIN
    window_s = e["window"] * design.data.settings.Ts
    lost = np.flatnonzero(np.nan_to_num(e["norm"], nan=1.0) < EXCITATION_MIN)
    detail = (f"smallest eigenvalue of the windowed information matrix (last {window_s:g} s, {e['window']} samples), "
              f"normalized to a unit diagonal: {_f(v, 3)} (at least {EXCITATION_MIN:g}); unnormalized "
              f"{_f(e['final_lam'], 3)}")
    if len(e["norm"]) < e["window"]:
        detail = (f"the run has {len(e['norm'])} samples, fewer than the {e['window']} of the excitation window "
                  f"({window_s:g} s): the indicator is not defined; lengthen simulation.duration or shorten "
                  "controller.excitation_window")
    if lost.size:
        detail += (f"; below the threshold on {lost.size} of {len(e['norm'])} samples, first at "
                   f"t = {e['samples'].t[lost[0]]:.4g} s")
    if not passed and len(e["norm"]) >= e["window"]:
        detail += ": the estimator has lost excitation, its estimates are not determined by the data"
    return (Check("excitation", passed, f"≥ {EXCITATION_MIN:g}", v if math.isfinite(v) else None,
                  v - EXCITATION_MIN if math.isfinite(v) else None, "", detail,
                  {"final": _num(v), "final_unnormalized": _num(e["final_lam"]), "window_samples": e["window"],
                   "samples_below": int(lost.size)}, data={"t": e["samples"].t, "norm": e["norm"], "lam": e["lam"]}),)


def _relative(theta: np.ndarray, true: np.ndarray) -> np.ndarray:
    return np.abs(theta - true) / np.abs(true)


def _convergence(design: Any, ctx: Context) -> tuple[Check, ...]:
    s = samples(ctx.simulation, design)
    true = true_theta(ctx.spec, ctx.true_plant(design), design, s.t[-1:])[0]
    rel = _relative(s.theta[-1], true)
    worst = float(np.max(rel)) if np.all(np.isfinite(rel)) else float("inf")
    excited = excitation_summary(design, ctx)["final"] >= EXCITATION_MIN
    names = design.data.parameters
    parts = ", ".join(f"{n} {_f(a, 6)} against {_f(b, 6)}" for n, a, b in zip(names, s.theta[-1], true, strict=True))
    what = "plant" if design.data.settings.form == "arx" else "link"
    if not np.all(np.isfinite(true)):
        return (Check("estimate_convergence", None, f"≤ {CONVERGED_REL:g}", None, None, "",
                      "the ARX orders do not hold the true sampled plant exactly: there are no exact parameters to "
                      "converge to", {"theta_hat": [_num(v) for v in s.theta[-1]]}, required=False),)
    detail = (f"final estimates against the exactly discretized true {what}: {parts}; largest relative error "
              f"{_f(worst, 3)}")
    if not excited:
        detail += " (informational: the excitation over the last window is too low to expect convergence)"
    return (Check("estimate_convergence", worst <= CONVERGED_REL, f"≤ {CONVERGED_REL:g}",
                  worst if math.isfinite(worst) else None, CONVERGED_REL - worst if math.isfinite(worst) else None, "",
                  detail, {"theta_hat": [_num(v) for v in s.theta[-1]], "theta_true": [float(v) for v in true],
                           "relative_error": [_num(v) for v in rel]}, required=bool(excited)),)


def reconvergence_time(design: Any, ctx: Context) -> tuple[float | None, float]:
    """``(seconds after simulation.plant_change until the estimates stay within CONVERGED_REL, change time)``."""
    s = samples(ctx.simulation, design)
    t0 = float(ctx.spec.simulation.plant_change.time)
    true = true_theta(ctx.spec, ctx.true_plant(design), design, s.t)
    ok = np.all(_relative(s.theta, true) <= CONVERGED_REL, axis=1) & (s.t >= t0)
    bad = np.flatnonzero(~ok & (s.t >= t0))
    if not ok[-1]:
        return None, t0
    first = bad[-1] + 1 if bad.size else int(np.flatnonzero(s.t >= t0)[0])
    return float(s.t[first] - t0), t0


def _parameter_step(design: Any, ctx: Context) -> tuple[Check, ...]:
    if design.data.settings.form == "arx":
        s = samples(ctx.simulation, design)
        if not np.all(np.isfinite(true_theta(ctx.spec, ctx.true_plant(design), design, s.t))):
            return (Check("parameter_step", None, "re-converged", None, None, "",
                          "the ARX orders do not hold the true sampled plant exactly (before or after the change): "
                          "there are no exact parameters to re-converge to", {}, required=False),)
    took, t0 = reconvergence_time(design, ctx)
    left = float(ctx.simulation.time[-1]) - t0
    change = ctx.spec.simulation.plant_change
    moved = ", ".join(f"{k} → {v:g}" for k, v in change.values.items())
    if took is None:
        detail = (f"the link changes at t = {t0:g} s ({moved}); the estimates are not within {CONVERGED_REL:.0%} of "
                  f"the new link's parameters at the end of the run ({left:.4g} s later)")
    else:
        detail = (f"the link changes at t = {t0:g} s ({moved}); the estimates are within {CONVERGED_REL:.0%} of the "
                  f"new link's parameters {took:.4g} s later and stay there")
    if design.data.settings.design == "pole_placement":
        ts, x1, ym = designed_response(ctx.simulation, design, ctx.spec, ctx.true_plant(design))
        after = ts >= t0
        tail = ts >= ts[-1] - design.data.excitation_window
        if after.any():
            dev = np.abs(x1 - ym)
            peak, last = _f(float(np.max(dev[after])), 3), _f(float(np.max(dev[tail])), 3)
            detail += (f"; the loop leaves the response the requested poles give on the new link by at most {peak} "
                       f"rad after the change and by {last} rad over the last excitation window")
    return (Check("parameter_step", took is not None, f"re-converged within the {left:.4g} s left",
                  took if took is not None else "never", left - took if took is not None else None,
                  "s" if took is not None else "", detail,
                  {"reconvergence_time": took, "change_time": t0}),)


def true_loop_poles(design: Any, theta_true: np.ndarray, coefs: np.ndarray) -> np.ndarray:
    """Poles ``z`` of the true sampled link ``B/A`` (exact ``theta_true``) under ``R u = T r - S y``."""
    x = design.data
    if x.settings.form == "arx":
        return arx_true_loop_poles(design, theta_true, coefs)
    a1, a2, b0, b1 = position_models(np.asarray(theta_true, dtype=float)[None, :], x.settings.Ts, x.settings.form)[0]
    R1, S0, S1 = (float(v) for v in coefs[:3])
    return np.roots([1.0, a1 + R1 + b0 * S0, a2 + a1 * R1 + b1 * S0 + b0 * S1, a2 * R1 + b1 * S1])


def _true_loop(design: Any, ctx: Context) -> tuple[Check, ...]:
    x = design.data
    s = samples(ctx.simulation, design)
    true = true_theta(ctx.spec, ctx.true_plant(design), design, s.t[-1:])[0]
    if x.settings.form == "arx":
        return _true_loop_z(design, s, true)
    z = true_loop_poles(design, true, s.coefs[-1])
    with np.errstate(all="ignore"):
        got = np.log(z.astype(complex)) / x.settings.Ts
    want = list(x.settings.poles) + [complex(x.settings.observer)]
    rel = []
    pool = list(got)
    for p in want:
        k = int(np.argmin([abs(q - p) for q in pool]))
        rel.append(abs(pool.pop(k) - p) / abs(p))
    worst = float(max(rel)) if all(math.isfinite(r) for r in rel) else float("inf")
    stable = bool(np.all(np.abs(z) < 1))
    conv = np.max(_relative(s.theta[-1], true)) <= CONVERGED_REL
    detail = (f"poles of the true sampled link under the final controller, as ln(z)/Ts: "
              f"{_poles(got)} 1/s against the requested {_poles(want)}"
              f" 1/s; largest relative distance {_f(worst, 3)}; |z| max {_f(float(np.max(np.abs(z))), 6)}")
    return (Check("true_loop", stable and worst <= POLE_REL, f"≤ {POLE_REL:g}", worst if math.isfinite(worst) else None,
                  POLE_REL - worst if math.isfinite(worst) else None, "", detail,
                  {"z": [[float(p.real), float(p.imag)] for p in z], "stable": stable},
                  required=bool(conv)),)


def _true_loop_z(design: Any, s: Any, true: np.ndarray) -> tuple[Check, ...]:
    """The ARX form's true loop, in the z-plane: the poles of the true sampled plant under the final controller
    against the roots of ``Am Ao`` (and, zeros cancelled, of the true ``B``), each within :data:`POLE_Z` (a deadbeat
    observer's ``z = 0`` has no ``ln z``)."""
    if not np.all(np.isfinite(true)):
        return (Check("true_loop", None, f"≤ {POLE_Z:g}", None, None, "",
                      "the ARX orders do not hold the true sampled plant exactly: no exact true model to close the "
                      "loop with", {}, required=False),)
    if not np.all(np.isfinite(s.coefs[-1])):
        return (Check("true_loop", False, f"≤ {POLE_Z:g}", None, None, "", "the final controller is not finite",
                      {}, required=True),)
    z = true_loop_poles(design, true, s.coefs[-1])
    want = list(wanted_poles(design, true))
    pool = list(z)
    dist = []
    for p in want:
        k = int(np.argmin([abs(q - p) for q in pool]))
        dist.append(abs(pool.pop(k) - p))
    worst = float(max(dist)) if dist else 0.0
    stable = bool(np.all(np.abs(z) < 1))
    conv = np.max(_relative(s.theta[-1], true)) <= CONVERGED_REL
    detail = (f"poles z of the true sampled plant under the final controller: {_poles(z)} against the requested "
              f"{_poles(np.asarray(want))} (roots of Am Ao{' and of the true B' if design.data.settings.cancel else ''}"
              f"); largest distance {_f(worst, 3)}; |z| max {_f(float(np.max(np.abs(z))), 6)}")
    return (Check("true_loop", stable and worst <= POLE_Z, f"≤ {POLE_Z:g}", worst, POLE_Z - worst, "", detail,
                  {"z": [[float(p.real), float(p.imag)] for p in z], "stable": stable}, required=bool(conv)),)


def _poles(ps: Any) -> str:
    """Poles in words: a conjugate pair once, as ``a ± bj``."""
    return ", ".join(_fmt_pole(p) for p in ps if p.imag >= -1e-9 * max(1.0, abs(p)))


def _fmt_pole(p: complex) -> str:
    return f"{p.real:.4g}" if abs(p.imag) < 1e-9 * max(1.0, abs(p)) else f"{p.real:.4g} ± {abs(p.imag):.4g}j"


def _diagnose_own(result: Any, check: Any) -> tuple[str, str] | None:
    if check.passed is not False:
        return None
    if check.name == "excitation":
        return ("The reference does not excite the estimator over the last window: " + check.detail + ".",
                "Use a reference that keeps moving (a square wave or a PRBS, simulation.trajectory), or a longer "
                "controller.excitation_window.")
    if check.name == "estimate_convergence":
        return ("The estimates did not reach the true link's parameters: " + check.detail + ".",
                "Lower controller.forgetting (e.g. 0.98) if the link changed, raise controller.initial_covariance if "
                "the estimator started too confident, or run longer.")
    if check.name == "parameter_step":
        return ("The estimator did not follow the change of the link: " + check.detail + ".",
                "Lower controller.forgetting below 1 (forgetting lets new data outweigh the old; with λ = 1 the "
                "estimator's memory is the whole run)" + _with_forgetting(result) + ".")
    if check.name == "characteristic_polynomial":
        return ("The estimated closed loop is not the requested one: " + check.detail + ".",
                "Look at the Sylvester condition number: a near-common factor of A and B makes the design ill-posed; "
                "a longer controller.sampling_period separates the poles of the sampled link.")
    if check.name == "true_loop":
        return ("The final controller does not place the true loop's poles: " + check.detail + ".",
                "The estimates have not converged (see the convergence check): excite longer or forget faster.")
    return None


SUGGESTED_FORGETTING = 0.99
"""The forgetting factor a failed re-convergence is re-simulated with."""


def _with_forgetting(result: Any) -> str:
    """``": with lambda = 0.99 the estimates re-converge ... (re-simulated)"`` when the spec forgets nothing."""
    spec = result.loaded.spec
    if spec.controller.forgetting < 1 or result.simulation is None:
        return ""
    from designkit.families.self_tuning import synthesize
    from designkit.families.self_tuning.runs import simulate
    from designkit.verification.suite import Context

    plant = result.plant if result.plant is not None else result.design.plant
    other = spec.model_copy(update={"controller": spec.controller.model_copy(
        update={"forgetting": SUGGESTED_FORGETTING})})
    design = synthesize(other, plant)
    took, _ = reconvergence_time(design, Context(other, simulate(other, design, plant), other.numerics.solver, plant))
    if took is None:
        return f": λ = {SUGGESTED_FORGETTING:g} was re-simulated and does not re-converge either"
    return f": with λ = {SUGGESTED_FORGETTING:g} (re-simulated) the estimates re-converge {took:.3g} s after the change"


def diagnose(result: Any, check: Any) -> tuple[str, str] | None:
    """Why one of the family's checks failed, and what would fix it."""
    return _diagnose_own(result, check)


def _has_change(design: Any, ctx: Context) -> bool:
    return _applies(design, ctx) and ctx.spec.simulation.plant_change is not None


def _pole_placement(design: Any, ctx: Context) -> bool:
    return _applies(design, ctx) and design.data.settings.design == "pole_placement"


RULES = (
    CheckRule(name="characteristic_polynomial", order=130, applies=_applies, run=_characteristic,
              label="Closed-loop polynomial of the estimated model", diagnose=_diagnose_own,
              glossary=(("A R + B S", "characteristic polynomial of the estimated sampled link under the controller "
                                      "designed for it"),)),
    CheckRule(name="excitation", order=131, applies=_applies, run=_excitation, label="Excitation of the estimator",
              diagnose=_diagnose_own,
              glossary=(("information matrix", "sum of φ φᵀ over the window, φ the regressor of each sample"),)),
    CheckRule(name="estimate_convergence", order=132, applies=_applies, run=_convergence,
              label="Estimates against the true sampled link", diagnose=_diagnose_own),
    CheckRule(name="parameter_step", order=133, applies=_has_change, run=_parameter_step,
              label="Re-convergence after the parameter step", diagnose=_diagnose_own),
    CheckRule(name="true_loop", order=134, applies=_pole_placement, run=_true_loop,
              label="Poles of the true sampled loop under the final controller", diagnose=_diagnose_own),
)
"""The family's own check rules, in report order."""

