"""The diagnosis of a run, assembled: what the run shows (computed once), then one finding per failing check.

:func:`diagnose` measures the run (:mod:`~designkit.analysis.diagnosis.divergence`), asks the module of
the simulation's nonlinear element (:mod:`designkit.analysis.elements`) why a diverged run diverged, what a
limit cycle should be and what settling time the actuator allows, asks the owners of a failing check --
its rule's ``diagnose`` and the family's ``diagnoses`` -- for their cause and fix (and the changes of the spec
that realize the fix, which :func:`~designkit.analysis.diagnosis.fixes.check_fixes` re-runs), and writes each
:class:`~designkit.analysis.diagnosis.findings.Finding` from those pieces.  No table here names an element,
a check or a family.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.analysis.diagnosis.comparison import compare
from designkit.analysis.diagnosis.divergence import (
    CYCLE_WINDOW,
    Divergence,
    describe,
    divergence_of,
    measure_oscillation,
)
from designkit.analysis.diagnosis.findings import Diagnosis, Finding, LimitCycle, shortfall
from designkit.analysis.diagnosis.fixes import check_fixes
from designkit.analysis.elements import analysis_of
from designkit.display.numbers import TARGET, fmt_number, plain_complex, quantity, unit
from designkit.synthesis.spec_change import SpecChange, explanation

__all__ = ["diagnose"]

_TIME_DOMAIN = ("overshoot", "settling_time", "rise_time", "steady_state_error", "tracking_error", "max_control")
_STABILITY = ("routh_hurwitz", "lyapunov", "pole_placement", "robust_box", "robust_grid", "robustness",
              "error_poles", "hurwitz")
_LABELS = {"overshoot": "overshoot", "settling_time": "settling time", "rise_time": "rise time",
           "steady_state_error": "steady-state error", "tracking_error": "tracking error",
           "max_control": "peak |u| commanded", "routh_hurwitz": "Routh-Hurwitz", "lyapunov": "Lyapunov",
           "pole_placement": "pole placement"}


@dataclass(frozen=True)
class _Context:
    """What the run shows, computed once."""

    divergence: Divergence | None
    divergence_text: str
    divergence_fix: str
    limit_cycle: LimitCycle | None
    cycle_fix: str
    unstable: str
    settling_fix: str


def _spec_nonlinearity(sim: Any) -> dict[str, Any]:
    return dict(dict(sim.settings).get("nonlinearity", {}) or {}) if sim is not None else {}



def _divergence_text(result: Any, div: Divergence) -> tuple[str, str]:
    """The divergence sentence (how, then what the nonlinear element says) and the element's fix."""
    how = describe(result, div)
    element = _spec_nonlinearity(result.simulation)
    explain = getattr(analysis_of(element.get("kind")), "explain_divergence", None)
    sat, fix = (explain(result, div, element, divergence_of) if explain is not None else None) or ("", "")
    text = "The nonlinear loop diverges: " + how + "." + (f" {sat[0].upper()}{sat[1:]}." if sat else "")
    return text, fix


def _limit_cycle(result: Any, div: Divergence) -> tuple[LimitCycle | None, str]:
    """The limit cycle measured at the end of the run (largest over the coordinates), predicted by the
    nonlinear element when it can, and the element's fix."""
    sim = result.simulation
    if sim is None or div.diverged:
        return None, ""
    t = np.asarray(sim.time, float)
    pos = np.asarray(sim.tracked_positions, float)
    ref = np.asarray(sim.reference, float)[:, :, 0]
    window = t >= t[-1] - CYCLE_WINDOW * (t[-1] - t[0])
    scale = max(div.scale, 1e-12)
    best, joint = None, 0
    for j in range(pos.shape[1]):
        if np.ptp(ref[window, j]) > 0:  # the reference itself moves there: a forced response, not a limit cycle
            continue
        osc = measure_oscillation(t, pos[:, j], scale=scale)
        if osc is not None and (best is None or osc.amplitude > best.amplitude):
            best, joint = osc, j
    if best is None:
        return None, ""
    unit_text = sim.coordinate_units[joint]
    name = sim.coordinate_names[joint]
    element = _spec_nonlinearity(sim)
    predict = getattr(analysis_of(element.get("kind")), "predict_cycle", None)
    prediction = predict(result, best.amplitude, best.frequency, element, unit_text) if predict is not None else None
    text = (f"a limit cycle: {name} oscillates with amplitude {quantity(best.amplitude, unit_text)} at "
            f"{quantity(best.frequency, 'rad/s')} (period {quantity(2 * math.pi / best.frequency, 's')}; measured "
            f"over the last {fmt_number(100 * CYCLE_WINDOW, 2)} % of the run, {best.cycles} periods)")
    if prediction is None:
        return LimitCycle(best.amplitude, best.frequency, None, None, text[0].upper() + text[1:] + "."), ""
    text += prediction.text
    sentence = text[0].upper() + text[1:] + "."
    return LimitCycle(best.amplitude, best.frequency, prediction.amplitude, prediction.frequency, sentence), \
        prediction.fix


def _settling_bound(result: Any) -> str:
    element = _spec_nonlinearity(result.simulation)
    bound = getattr(analysis_of(element.get("kind")), "settling_bound", None)
    return bound(result, element) if bound is not None else ""


def _unstable(result: Any) -> str:
    cl = result.design.closed_loop
    if cl is None:
        return ""
    poles = np.asarray(cl.poles, dtype=complex)
    bad = poles[poles.real >= 0]
    if bad.size == 0:
        return ""
    shown = ", ".join(fmt_number(p) for p in sorted(bad, key=lambda z: (-z.real, z.imag))[:4])
    return (f"the linear closed loop is unstable: {bad.size} of its {poles.size} poles have Re ≥ 0 ({shown} 1/s)")


def _solver(check: Any) -> str:
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    status = cert.get("solver_status")
    if status is None or str(status) == "optimal":
        return ""
    solver = cert.get("solver")
    who = f"the solver {solver}" if solver else "the solver"
    return f"{who} did not converge (status {status!s})"


def _context(result: Any) -> _Context:
    sim = result.simulation
    if sim is None:
        return _Context(None, "", "", None, "", _unstable(result), "")
    div = divergence_of(sim)
    dtext = dfix = ""
    if div is not None and div.diverged:
        dtext, dfix = _divergence_text(result, div)
    cycle, cfix = _limit_cycle(result, div)
    return _Context(div, dtext, dfix, cycle, cfix, _unstable(result), _settling_bound(result))



def _specific(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]]:
    """Cause, fix and the fix's spec changes from the owners: the rule of the check (``CheckRule.diagnose``), then
    the design's family (``Family.diagnoses``), the first that has something to say; ``("", "", ())`` when none
    does.  An owner answers ``(cause, fix)`` or ``(cause, fix, changes)``, ``changes`` a tuple of
    :class:`~designkit.synthesis.spec_change.SpecChange` realizing ``fix``."""
    from designkit.families import check_rules, family
    from designkit.verification.suite import owner

    kind = getattr(result.design, "kind", None)
    if kind is None:  # a run without a registered design: no owner to ask
        return ("", "", ())
    rule = owner(check_rules(kind), check.name)
    owners = ((rule.diagnose,) if rule is not None and rule.diagnose is not None else ())
    for explain in (*owners, *family(kind).diagnoses):
        found = explain(result, check)
        if found:
            return explanation(found)
    return ("", "", ())


def _sentence(text: str) -> str:
    text = text.strip().rstrip(";")
    return text[0].upper() + text[1:] + ("" if text.endswith(".") else ".") if text else ""


def _finding(check: Any, ctx: _Context, demand: dict[str, Any],
             specific: tuple[str, str, tuple[SpecChange, ...]] = ("", "", ())) -> Finding:
    label = _LABELS.get(check.name, check.name.replace("_", " "))
    target = unit(check.target or "")
    requirement = f"{label} {target}" if TARGET.match(target) else f"{label}: {target}" if target else label
    achieved = ""
    if isinstance(check.achieved, int | float) and not isinstance(check.achieved, bool):
        achieved = quantity(float(check.achieved), check.unit)
    elif isinstance(check.achieved, str):
        achieved = plain_complex(check.achieved)
    absolute, relative = shortfall(check.target, check.margin, check.unit)
    causes: list[str] = []
    fixes: list[str] = []
    solver = _solver(check)
    if solver:
        causes.append(solver)
        fixes.append("rerun with another solver or a scaled problem (numerics section)")
    if check.name in _TIME_DOMAIN:
        if ctx.divergence is not None and ctx.divergence.diverged:
            causes.append(ctx.divergence_text.rstrip("."))
            if ctx.divergence_fix and _not_a_fix(ctx.divergence_fix):
                causes.append("tried, and not a fix: " + ctx.divergence_fix)
            elif ctx.divergence_fix:
                fixes.append(ctx.divergence_fix)
        elif ctx.limit_cycle is not None:
            causes.append(ctx.limit_cycle.sentence.rstrip("."))
            if ctx.cycle_fix and check.name == "steady_state_error":
                fixes.append(ctx.cycle_fix)
        elif ctx.unstable:
            causes.append(ctx.unstable)
        if check.name == "settling_time" and ctx.settling_fix:
            fixes.append(ctx.settling_fix)
        diverged_saturated = ctx.divergence is not None and ctx.divergence.diverged and demand.get("saturation")
        if demand.get("text") and (check.name == "max_control" or diverged_saturated):
            fixes.append(demand["text"])
        if ctx.unstable and ctx.divergence is not None and ctx.divergence.diverged and ctx.unstable not in causes:
            causes.append(ctx.unstable)
    elif check.name in _STABILITY and ctx.unstable:
        causes.append(ctx.unstable)
    if specific[0]:
        causes.append(specific[0])
    if specific[1]:
        fixes.append(specific[1])
    cause = "; ".join(causes)
    if cause:
        cause = cause[0].upper() + cause[1:]
        cause = cause if cause.endswith(".") else cause + "."
    fix = "; ".join(dict.fromkeys(fixes))
    if fix:
        fix = fix[0].upper() + fix[1:] + ("" if fix.endswith(".") else ".")
    parts = tuple(dict.fromkeys(_sentence(f) for f in fixes if f.strip()))
    declared = ((_sentence(specific[1]), specific[2]),) if specific[1].strip() and specific[2] else ()
    return Finding(check=check.name, status=check.status, requirement=requirement, achieved=achieved,
                   shortfall=absolute, shortfall_percent=relative, cause=cause, fix=fix, fixes=parts,
                   changes=declared)


def _not_a_fix(text: str) -> bool:
    """A remedy its own re-simulation shows does not meet the requirements (it is said, never numbered as a fix)."""
    return "does not help" in text or "stalls short of the command" in text or "could not be tried" in text


def _root_cause(ctx: _Context) -> str:
    """The actuator-limited settling bound, when it says the settling requirement cannot be met by any controller."""
    text = ctx.settling_fix or ""
    if "cannot be met" not in text:
        return ""
    return ("Root cause: " + text[0].lower() + text[1:].rstrip(".") + ". Everything below follows from asking more "
            "than the actuator can give.")


def _demand(result: Any, peak: float | None) -> dict[str, Any]:
    """What the ideal linear loop commands against the actuator limit (saturation) or the max_control requirement."""
    sim = result.simulation
    if peak is None or sim is None:
        return {}
    nl = _spec_nonlinearity(sim)
    req = result.loaded.spec.requirements
    saturated = nl.get("kind") == "saturation"
    if saturated:
        limit = float(np.min(np.atleast_1d(nl["limit"])))
    elif req is not None and req.max_control is not None:
        limit = float(np.min(np.atleast_1d(req.max_control)))
    else:
        return {}
    if not peak > limit:
        return {}
    what = "step" if sim.kind == "step" else "motion"
    return {"saturation": saturated,
            "text": (f"the ideal linear loop itself commands {quantity(peak, 'N*m')} for this {what}, "
                     f"{fmt_number(peak / limit, 3)} times the {quantity(limit, 'N*m')} limit: slower "
                     f"closed-loop poles (or a smaller {what}) are needed to stay within it")}


def diagnose(result: Any, *, resimulate: bool = True) -> Diagnosis:
    """Diagnose a finished run (see :mod:`designkit.analysis.diagnosis`).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        Its ``checks``, ``simulation`` (may be None), ``design`` and ``plant``.
    resimulate : bool
        Re-run every proposed fix through the pipeline (:func:`~designkit.analysis.diagnosis.fixes.check_fixes`,
        at most :data:`~designkit.analysis.diagnosis.resimulate.MAX_FIX_RUNS` runs).

    Returns
    -------
    Diagnosis
        Findings for the failing or undecided required checks, divergence, limit cycle and the
        linear-versus-nonlinear metrics.
    """
    ctx = _context(result)
    pairs, lin = compare(result)
    demand = _demand(result, None if lin is None else lin.peak_u_command)
    failing: Sequence[Any] = [c for c in result.checks if c.required and c.passed is not True]
    findings = tuple(_finding(c, ctx, demand, _specific(result, c)) for c in failing)
    div = ctx.divergence
    root = _root_cause(ctx)
    proposed: tuple[Any, ...] = ()
    if resimulate and getattr(result, "loaded", None) is not None and result.simulation is not None:
        sentences = tuple(dict.fromkeys(s for f in findings for s in f.fixes))
        declared: dict[str, tuple[SpecChange, ...]] = {}
        for f in findings:
            for sentence, changes in f.changes:
                declared.setdefault(sentence, changes)
        proposed = check_fixes(result, sentences, settling_infeasible=bool(root), declared=declared)
    return Diagnosis(findings=findings, diverged=bool(div is not None and div.diverged),
                     divergence=ctx.divergence_text, limit_cycle=ctx.limit_cycle, linear_vs_nonlinear=pairs,
                     root_cause=root, proposed=proposed)
