"""Why a learning design failed, and what would fix it (``Family.diagnoses``): a diverging ``Q``, an error that
grew on the true plant, and a design too slow to meet the tracking requirement within its trials."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.ilc.checks import trial_analysis
from designkit.families.ilc.learning import IlcData, lifted_of, operator_of
from designkit.families.ilc.operators import contraction
from designkit.simulation.trials import MAX_TRIALS

__all__ = ["diagnose"]


def _contraction(result: Any) -> Any:
    sim = result.simulation
    lifted = lifted_of(result.design, None if sim is None else sim.time)
    return contraction(lifted, operator_of(result.design)), lifted


def _converging(c: Any, lifted: Any) -> str:
    r = c.alpha_range
    if c.kind == "adjoint":
        return (f"choose controller.learning.alpha in (0, {r['alpha_max']:.4g}) 1/s⁴ (proved below "
                f"{r['alpha_max_proved']:.4g}), e.g. {r['alpha_one_trial']:.4g} = 1/σ_max(H)², or leave it out "
                "to get that value")
    alpha = 1.0 / max(s.estimate for s in lifted.sigma_max) ** 2
    if lifted.integrator in ("zoh", "discrete"):
        return (f"switch to controller.learning: {{kind: adjoint}} (α = 1/σ_max(H)² = {alpha:.4g} is computed), the "
                "update with a monotone certificate for every plant, or lower the gain until ρ < 1 (this plant's "
                "symbol decides whether any P-type gain has one)")
    return (f"switch to controller.learning: {{kind: adjoint}} (α = 1/σ_max(H)² = {alpha:.4g} 1/s⁴ is computed), "
            "the update with a monotone certificate; no P-type gain has one")


def _fix(c: Any, lifted: Any) -> str:
    text = _converging(c, lifted)
    return text[0].upper() + text[1:] + "."


def _undecided(c: Any, lifted: Any) -> tuple[str, str]:
    """Why the contraction is undecided, and what would decide it."""
    from designkit.families.ilc.checks import near_one
    from designkit.verification.tolerances import BOUNDARY_REL

    where = f"[{near_one(c.lower, -c.excess)}, {near_one(c.upper, c.margin)}]"
    r = c.alpha_range
    if c.kind == "adjoint" and r.get("rho_optimal_margin", 1.0) <= BOUNDARY_REL:
        return (f"ρ = ‖I − Q H‖₂ is only known to lie in {where}, within {BOUNDARY_REL:g} of 1: below 1, but by less "
                "than the precision of its bounds. No α does better here: the smallest ρ, at α* = "
                f"{r['alpha_optimal']:.4g}, is {near_one(r['rho_optimal'], r['rho_optimal_margin'])}, since σ_min(H) = "
                f"{r['sigma_min']:.3g} (the lifted map's symbol near the Nyquist frequency) is "
                f"{r['sigma_max'] / r['sigma_min']:.3g} times below σ_max(H).",
                "The monotone certificate cannot be decided on this grid: judge the learning by its trials "
                "(ilc_error_decrease), or sample the trial more coarsely (simulation.dt) or shorten it, which raises "
                "σ_min(H).")
    return (f"ρ = ‖I − Q H‖₂ is only known to lie in {where}, which reaches 1.",
            "Move the learning gain away from the edge of its range: " + _converging(c, lifted) + ".")


def diagnose(result: Any, check: Any) -> tuple[str, str] | None:
    """``(cause, fix)`` for a failed ``ilc_convergence``, ``ilc_error_decrease`` or (with trials)
    ``tracking_error`` check, else None."""
    if check.passed is True or not isinstance(result.design.data, IlcData):
        return None
    c, lifted = _contraction(result)
    if check.name == "ilc_convergence":
        if check.passed is None:
            return _undecided(c, lifted)
        what = "α" if c.kind == "adjoint" else "γ"
        return (f"ρ = ‖I − Q H‖₂ = {c.rho:.4g} exceeds 1 by {c.rho - 1:.3g} for {what} = {c.value:.4g}: the "
                "learning amplifies part of the error every trial instead of removing it.",
                _fix(c, lifted))
    a = trial_analysis(result)
    if a is None:
        return None
    if check.name == "ilc_error_decrease":
        grew = np.flatnonzero(~(a.norms[1:] <= a.allowed))
        k = int(grew[0]) if grew.size else 0
        if not c.monotone:
            return (f"Without a contraction (ρ = {c.rho:.4g} ≥ 1) the error grew from trial {k} to {k + 1} "
                    f"(×{a.ratios[k]:.3g}).", _fix(c, lifted))
        mu = float(np.max(a.unexplained)) if a.unexplained.size else 0.0
        return (f"The certificate holds for the controller's model, but on the true plant the error grew from trial "
                f"{k} to {k + 1} (×{a.ratios[k]:.3g}): the lifted model leaves up to {100 * mu:.3g} % of a "
                "trial's change unexplained (the model mismatch and the coupling through M⁻¹M̂).",
                f"Lower the learning gain (e.g. to half, {c.value / 2:.4g}) so that the mismatch cannot turn the "
                "update around, or correct controller.model.")
    if check.name == "tracking_error" and check.achieved is not None:
        target = float(str(check.target).split()[1]) if str(check.target).startswith("<=") else None
        peaks = result.trials.max_tracking_errors
        tail = peaks[-min(5, peaks.size):]
        rate = (tail[-1] / tail[0]) ** (1.0 / (tail.size - 1)) if tail.size > 1 and tail[0] > 0 else 1.0
        if c.monotone is False and target is not None and not 0 < rate < 1:
            return (f"The error grows trial after trial (the largest error ×{rate:.3g} per trial over the last "
                    f"{tail.size} trials, {check.achieved:.4g} after {peaks.size}): ρ = ‖I − Q H‖₂ = {c.rho:.4g} > 1, "
                    "so no decrease is certified, and a spectral radius below 1 promises convergence only after a "
                    "transient growth.", _fix(c, lifted))
        if target is None or not 0 < rate < 1:
            return (f"The last trial still tracks to {check.achieved:.4g} rad and the largest error did not fall "
                    f"over the last {tail.size} trials (×{rate:.3g} per trial).",
                    "The learning has stopped improving: the error left is what the lifted model cannot learn "
                    "(mismatch, perturbation changing with the motion); correct controller.model.")
        more = math.ceil(math.log(target / check.achieved) / math.log(rate))
        total = peaks.size + more
        fix = (f"ask for about {total} trials (controller.trials)" if total <= MAX_TRIALS else
               f"more trials than the {MAX_TRIALS} allowed would be needed ({total}): raise the learning gain")
        return (f"The learning is slow: the largest error fell by ×{rate:.3g} per trial over the last {tail.size} "
                f"trials and is still {check.achieved:.4g} rad after {peaks.size} trials (required {target:g}).",
                f"At that rate the requirement is met about {more} trials later: {fix}"
                + (f" (α may go up to {c.alpha_range['alpha_max']:.4g} 1/s⁴)." if c.kind == "adjoint" else "."))
    return None
