"""The MRAC's own checks, on the adaptive run (the generic ``lyapunov`` and ``frozen_final`` judge the frozen loops).

``adaptive_stability`` (order 126, required): the adaptive run stays bounded
(:func:`~designkit.families.mrac.runs.assess`: finite, ``|e| <= 10 x`` the reference's swing, the error's
RMS not growing by more than 10 % from one window to the next after the last change).  On failure it
finds, by a bounded bisection (:func:`~designkit.families.mrac.boundary.gamma_boundary`), the scale of
the adaptation gains that keeps the run bounded, and the linearized (Floquet) scale below which the
parameters converge, and says both.

``adaptation_error`` (order 127): RMS of ``e = ym - x1`` over the run with the adaptive law against the
same scenario simulated with the gains frozen at their initial values (a second simulator with
``law = freeze(initial)``), both against the same reference-model output.  **Required** when there is
something to adapt to -- the plant changes during the run, the true link is not the nominal one, the
initial parameters do not put the link on the model, or a perturbation acts -- and then it asserts
that adaptation lowers the RMS error (strictly).  Without any of these the fixed-gain loop *is* the
model and the check is informational (adaptation must not cost more than 5 %).

``parameter_convergence`` (order 128): the adapted parameters at the end of the run against the values
that put the final true link exactly on the model (within :data:`CONVERGED_REL`), and a
persistent-excitation indicator: the smallest eigenvalue ``rho`` of ``k Gamma^1/2 G Gamma^1/2`` with ``G``
the Gram matrix ``mean(S' Q S)`` of the sensitivities after the last change -- the slowest rate (1/s)
at which the averaged gradient rule ``alpha~' = -k Gamma G alpha~`` removes a parameter error.  When
``rho`` times the time left is at least :data:`EFOLDS` the excitation justifies expecting convergence
and the check is required; otherwise it is informational and says so.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.mrac import regressor_checks
from designkit.families.mrac.boundary import GammaRun, floquet_boundary, frozen_signal_bound, gamma_boundary
from designkit.families.mrac.data import RegressorData
from designkit.families.mrac.laws import KIND
from designkit.families.mrac.runs import (
    adapted,
    assess,
    change_in_run,
    final_link,
    gram,
    in_run,
    last_event,
    matching,
    model_position,
    plant_ratio,
    rms,
    simulate,
    window_masks,
)
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context

__all__ = ["CONVERGED_REL", "EFOLDS", "RULES", "diagnose", "fixed_comparison", "mismatch_reasons"]

CONVERGED_REL = 0.05
"""Converged: every adapted parameter within this fraction of its matching value."""
EFOLDS = 3.0
"""Excitation justifies convergence when the averaged rate times the time left is at least this."""
NO_COST = 0.05
"""Without a mismatch, adaptation may raise the RMS error by at most this fraction (informational)."""
BISECTION_ON_FAILURE = 6
"""Simulations the failing stability check spends to find the gains that would do."""


def _applies(design: Any, ctx: Context) -> bool:
    return design.kind == KIND and ctx.simulation is not None and design.linearization.kind == "frozen"


def _f(x: float | None, digits: int = 4) -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def mismatch_reasons(design: Any, spec: Any, plant: Any) -> list[str]:
    """Why the fixed-gain loop is not the model, in words (empty: it is)."""
    n = design.data
    Km, tau = float(plant.parameter("Km").value), float(plant.parameter("tau").value)
    out = []
    change = change_in_run(spec)
    if change is not None:
        moved = ", ".join(f"{k} {plant.parameter(k).value:g} → {v:g}" for k, v in change.values.items()
                          if plant.parameter(k).value != v)
        if moved:
            out.append(f"the link changes at t = {change.time:g} s ({moved})")
    if (Km, tau) != n.nominal:
        out.append(f"the true link (Km = {Km:g}, τ = {tau:g} s) is not the nominal one the gains are realised on "
                   f"(Km = {n.nominal_Km:g}, τ = {n.nominal_tau:g} s)")
    start = matching(design, (Km, tau))
    initial = design.data.initial
    if max(abs(a - b) / abs(b) for a, b in zip(initial, start, strict=True)) > 1e-9:
        out.append(f"the initial parameters ({initial[0]:.4g}, {initial[1]:.4g}) are not those that put the link on "
                   f"the model ({start[0]:.4g}, {start[1]:.4g})")
    if spec.simulation.perturbation is not None and in_run(spec, spec.simulation.perturbation.time):
        out.append(f"a perturbation acts from t = {spec.simulation.perturbation.time:g} s")
    return out


def fixed_comparison(design: Any, ctx: Context) -> dict[str, Any]:
    """The fixed-gain run (gains frozen at their initial values) in the same scenario, and both output errors
    against the adaptive run's reference-model output."""
    sim = ctx.simulation
    lin = design.linearization
    fixed = simulate(ctx.spec, design, ctx.true_plant(design), lin.freeze(lin.initial))
    t, ym = np.asarray(sim.time, dtype=float), model_position(sim)
    tf = np.asarray(fixed.time, dtype=float)
    same = tf.shape == t.shape and np.allclose(tf, t, rtol=0, atol=1e-12)
    ym_f = ym if same else np.interp(tf, t, ym)  # a fast reference model bounds the adaptive run's step only
    pos = fixed.positions[0]
    return {"fixed": fixed, "e_adaptive": np.asarray(sim.signals["e"], dtype=float),
            "e_fixed": ym_f - np.asarray(fixed.state, dtype=float)[:, pos], "time_fixed": tf}


def _regressor(design: Any) -> bool:
    return isinstance(design.data, RegressorData)


def _adaptation_error(design: Any, ctx: Context) -> tuple[Check, ...]:
    if _regressor(design):
        return regressor_checks.adaptation_error(design, ctx)
    sim = ctx.simulation
    cmp = fixed_comparison(design, ctx)
    ea, ef = cmp["e_adaptive"], cmp["e_fixed"]
    ra, rf = rms(ea), rms(ef)
    reasons = mismatch_reasons(design, ctx.spec, ctx.true_plant(design))
    t = np.asarray(sim.time, dtype=float)
    t0 = last_event(ctx.spec, float(t[-1]))
    after = t >= t0 - 1e-12
    masks = window_masks(sim, t0)
    cert: dict[str, Any] = {
        "error_rms": {"adaptive": ra if math.isfinite(ra) else None, "fixed": rf if math.isfinite(rf) else None},
        "ratio": ra / rf if rf > 0 and math.isfinite(ra) else None,
        "after_last_change": {"from_s": t0, "adaptive": _json(rms(ea[after])), "fixed": _json(rms(ef[after]))},
        "reasons": reasons}
    if masks is not None:
        last = masks[0]
        cert["last_window"] = {"from_s": float(t[last][0]), "adaptive": _json(rms(ea[last])),
                               "fixed": _json(rms(ef[last]))}
    data = {"time": cmp["time_fixed"], "fixed_position": np.asarray(cmp["fixed"].position, dtype=float),
            "fixed_error": ef, "fixed_u": np.asarray(cmp["fixed"].u_command, dtype=float)[:, 0]}
    target = "RMS(e) with adaptation < RMS(e) with the gains frozen at their initial values"
    if not math.isfinite(ra):
        return (Check("adaptation_error", False, target, None, None, "rad",
                      f"the adaptive run's output error is not finite (the fixed-gain loop's RMS is {_f(rf)} rad)",
                      cert, data=data),)
    if reasons:
        ok = bool(ra < rf)
        share = f" ({_f(100 * ra / rf, 3)} %)" if rf > 0 else ""
        detail = (f"RMS of e = ym − x1 over the run: {_f(ra)} rad with adaptation, {_f(rf)} rad with the gains frozen "
                  f"at their initial values{share}, because {'; '.join(reasons)}")
        if not ok:
            detail += ": adaptation did not lower the error"
        return (Check("adaptation_error", ok, target, ra, rf - ra, "rad", detail, cert, data=data),)
    ok = bool(ra <= (1 + NO_COST) * rf + 1e-12 * max(1.0, rf))
    detail = (f"nothing to adapt to (the fixed-gain loop is the model): RMS of e = {_f(ra)} rad with adaptation, "
              f"{_f(rf)} rad without; reported")
    return (Check("adaptation_error", ok, f"RMS(e) with adaptation <= {1 + NO_COST:g} x without (no mismatch)",
                  ra, (1 + NO_COST) * rf - ra, "rad", detail, cert, required=False, data=data),)


def _json(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _convergence(design: Any, ctx: Context) -> tuple[Check, ...]:
    if _regressor(design):
        return regressor_checks.convergence(design, ctx, CONVERGED_REL, EFOLDS)
    sim, spec = ctx.simulation, ctx.spec
    plant = ctx.true_plant(design)
    link = final_link(spec, plant)
    want = np.asarray(matching(design, link))
    alpha = adapted(sim)
    final = alpha[-1]
    t = np.asarray(sim.time, dtype=float)
    t0 = last_event(spec, float(t[-1]))
    span = float(t[-1]) - t0
    G = gram(sim, design.data.Q, t0)
    k = plant_ratio(design, link)
    root = np.diag(np.sqrt(np.asarray(design.data.gamma, dtype=float)))
    with np.errstate(all="ignore"):
        eig = np.linalg.eigvalsh(k * root @ G @ root) if np.all(np.isfinite(G)) else np.array([np.nan, np.nan])
    rate = float(eig[0])
    efolds = rate * span
    excited = bool(np.isfinite(efolds) and efolds >= EFOLDS)
    rel = np.abs(final - want) / np.abs(want)
    worst = float(np.max(rel)) if np.all(np.isfinite(rel)) else math.inf
    converged = bool(worst <= CONVERGED_REL)
    masks = window_masks(sim, t0)
    drift = None
    if masks is not None and np.all(np.isfinite(alpha[masks[0]])):
        seg = alpha[masks[0]]
        drift = float(np.max((seg.max(axis=0) - seg.min(axis=0)) / np.abs(want)))
    cert = {"final": _list(final), "matching": want.tolist(), "relative_error": _list(rel),
            "gram": G.tolist() if np.all(np.isfinite(G)) else None, "rate_per_s": _json(rate),
            "efolds": _json(efolds), "window_s": [t0, float(t[-1])], "excited": excited,
            "conditioning": _json(float(eig[0] / eig[1])) if eig[1] > 0 else None, "last_window_drift": drift,
            "plant_ratio_k": k, "final_link": {"Km": link[0], "tau": link[1]}}
    words = (f"a1, a2 end at {_f(final[0])}, {_f(final[1])}; the link at the end is on the model at "
             f"{want[0]:.4g}, {want[1]:.4g} (largest relative error {_f(100 * worst, 3)} %)")
    pe = (f"excitation after t = {t0:g} s: slowest averaged rate ρ = λmin(k Γ½ G Γ½) = {_f(rate, 3)} 1/s, "
          f"{_f(efolds, 3)} time constants in the {span:.4g} s left")
    target = f"parameters within {100 * CONVERGED_REL:g} % of the values matching the model"
    if excited:
        detail = f"{words}; {pe} (≥ {EFOLDS:g}: convergence expected)"
        if not converged:
            detail += ": they did not converge although the excitation justifies it"
        return (Check("parameter_convergence", converged, target, _json(worst), _json(CONVERGED_REL - worst),
                      "1 (relative)", detail, cert),)
    detail = (f"{words}; {pe} (< {EFOLDS:g}: the excitation does not justify expecting convergence; reported, "
              f"{'converged anyway' if converged else 'not converged'})")
    return (Check("parameter_convergence", converged, target, _json(worst), _json(CONVERGED_REL - worst),
                  "1 (relative)", detail, cert, required=False),)


def _list(v: np.ndarray) -> list[float | None]:
    return [float(x) if math.isfinite(x) else None for x in np.asarray(v, dtype=float)]


def _stability(design: Any, ctx: Context) -> tuple[Check, ...]:
    if _regressor(design):
        return regressor_checks.stability(design, ctx)
    sim, spec = ctx.simulation, ctx.spec
    a = assess(sim, spec)
    cert: dict[str, Any] = {"finite": a.finite, "peak_error": _json(a.peak), "bound": a.bound, "growth": a.growth,
                            "growth_limit": 1.1, "window_s": a.window, "diverged_at_s": a.diverged_at}
    target = "the adaptive run stays bounded (finite, |e| ≤ 10 × the reference swing, error not growing)"
    achieved = a.growth if a.growth is not None else (None if not math.isfinite(a.peak) else a.peak / a.bound)
    if a.stable:
        margin = 1.1 - a.growth if a.growth is not None else 1.0 - a.peak / a.bound
        return (Check("adaptive_stability", True, target, achieved, margin, "1 (ratio)", a.reason, cert),)
    plant = ctx.true_plant(design)
    known = GammaRun(1.0, False, rms(sim.signals["e"]), a.growth, (math.nan, math.nan), a.reason)
    bd = gamma_boundary(spec, design, plant, known=known, max_runs=BISECTION_ON_FAILURE)
    frozen = frozen_signal_bound(sim, design, spec, plant)
    floquet = floquet_boundary(sim, design, spec, plant, around=frozen["scale"] if frozen else None)
    gamma = np.asarray(design.data.gamma, dtype=float)
    fix = []
    if bd.lo is not None:
        fix.append(f"scaling the adaptation gains by {bd.lo:.3g} (γ = {_gammas(bd.lo * gamma)}) keeps the run "
                   f"bounded (simulated; {_f(bd.hi, 3)} × does not)")
    if floquet is not None:
        fix.append(f"below {floquet['scale']:.3g} × (γ = {_gammas(floquet['scale'] * gamma)}) the linearized "
                   "adaptive loop is stable and the parameters converge (Floquet multipliers of one period)")
    cert.update({"bracket": [bd.lo, bd.hi], "runs": [[r.scale, r.stable] for r in bd.runs],
                 "frozen_signal_scale": frozen["scale"] if frozen else None,
                 "floquet_scale": floquet["scale"] if floquet else None,
                 "gamma_bounded_at": (bd.lo * gamma).tolist() if bd.lo is not None else None})
    detail = f"the gradient rule lost stability: {a.reason}"
    if fix:
        detail += "; " + "; ".join(fix)
    return (Check("adaptive_stability", False, target, achieved, None, "1 (ratio)", detail, cert,
                  data={"boundary": bd, "frozen": frozen, "floquet": floquet}),)


def _gammas(g: np.ndarray) -> str:
    return ", ".join(f"{v:.4g}" for v in g)


def _diagnose_own(result: Any, check: Any) -> tuple[str, str] | None:
    cert = check.certificate
    if check.name == "adaptive_stability" and check.passed is False:
        cause = (f"The gradient (MIT) rule is unstable at these adaptation gains: {check.detail.split('; ')[0]}. "
                 "Its stability depends on γ times the squared reference amplitude (and on Q and the link's gain).")
        fix = ("Lower γ: the boundary study of this report judges each γ by every required check on a grid refined "
               "where the outcome changes (the outcome is not monotone in γ, so a bounded run at one γ says nothing of "
               "the γ below it) and recommends a value only where its neighbourhood passes too")
        if cert.get("floquet_scale"):
            fix += (f"; linearized about the matched trajectory, the parameters stop converging at "
                    f"{cert['floquet_scale']:.3g} × the current γ")
        return cause + "", fix + ". Lowering the reference amplitude acts the same way: the boundary scales as " \
            "1/amplitude²."
    if check.name == "adaptation_error" and check.passed is False:
        return ("Adaptation did not lower the output error against the fixed-gain loop: " + check.detail + ".",
                "Raise γ if the parameters moved too little (see the convergence check), lower it if they "
                "oscillate, or use a more exciting reference (square wave, PRBS).")
    if check.name == "parameter_convergence" and check.passed is False:
        return ("The adapted parameters did not reach the values that put the link on the model although the "
                f"excitation justifies it ({check.detail}).",
                "Lower γ if they oscillate about those values (the loop is near its stability boundary), or run "
                "longer.")
    return None


def diagnose(result: Any, check: Any) -> tuple[str, str] | None:
    """Why a generic linear check of an MRAC design failed (the frozen loops), and what would fix it."""
    if check.passed is not False:
        return None
    if check.name == "frozen_final":
        final = check.certificate.get("final")
        return (f"The adaptation ended on parameters {final} whose fixed-gain loop is unstable on the true link.",
                "Lower γ so that the parameters converge instead of wandering (see the adaptive stability check).")
    return None


RULES = (
    CheckRule(name="adaptive_stability", order=126, applies=_applies, run=_stability,
              label="Boundedness of the adaptive run", diagnose=_diagnose_own,
              glossary=(("growth", "RMS of the output error over the last window over the window before"),)),
    CheckRule(name="adaptation_error", order=127, applies=_applies, run=_adaptation_error,
              label="Output error with against without adaptation", diagnose=_diagnose_own,
              glossary=(("e", "reference-model position minus link position, ym − x1"),)),
    CheckRule(name="parameter_convergence", order=128, applies=_applies, run=_convergence,
              label="Convergence of the adapted parameters", diagnose=_diagnose_own,
              glossary=(("ρ", "smallest eigenvalue of k Γ½ G Γ½, G = mean(Sᵀ Q S): the slowest averaged "
                              "convergence rate of the gradient rule"),)),
)
"""The family's own check rules, in report order."""
