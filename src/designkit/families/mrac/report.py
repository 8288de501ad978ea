"""The MRAC's report section (the MRAC simulator's questions and experiment 2's, answered from re-simulations) and
its top-level JSON object ``adaptation``.

:func:`json` is cheap: it reads the ``adaptation_error`` check (or runs the one fixed-gain simulation it
needs).  :func:`section` runs the study (:func:`designkit.families.mrac.study.study`, at most
:data:`~designkit.families.mrac.study.MAX_RUNS` simulations, cached with the figures).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, fmt_poles
from designkit.display.section import Question, ReportSection, Table
from designkit.families.mrac.checks import fixed_comparison
from designkit.families.mrac.data import RegressorData
from designkit.families.mrac.model import PARAMETERS, UNITS, ReferenceModel, coefficients_of, gains_of
from designkit.families.mrac.modification import describe
from designkit.families.mrac.runs import adapted, final_link, matching, rms
from designkit.families.mrac.study import Comparison, context, study

__all__ = ["json", "section"]


def _num(x: float | None) -> float | None:
    return float(x) if x is not None and math.isfinite(x) else None


def json(result: Any) -> dict[str, Any]:
    """``{"adaptation": {parameters, units, initial, final, matching, error_rms: {adaptive, fixed}}}``: the RMS
    output error ``ym - x1`` (rad) over the run with adaptation and with the gains frozen at their initial values
    (same scenario); non-finite values are ``null``."""
    d, sim = result.design, result.simulation
    if isinstance(d.data, RegressorData):
        return {"adaptation": regressor_json(result)}
    out: dict[str, Any] = {"parameters": list(PARAMETERS), "units": list(UNITS),
                           "initial": [float(v) for v in d.linearization.initial]}
    if sim is None:
        return {"adaptation": {**out, "final": None, "error_rms": None}}
    final = adapted(sim)[-1]
    check = next((c for c in result.checks if c.name == "adaptation_error"), None)
    if check is not None:
        err = dict(check.certificate["error_rms"])
    else:
        cmp = fixed_comparison(d, context(result))
        err = {"adaptive": _num(rms(cmp["e_adaptive"])), "fixed": _num(rms(cmp["e_fixed"]))}
    plant = result.plant if result.plant is not None else d.plant
    out.update(final=[_num(v) for v in final], matching=list(matching(d, final_link(result.loaded.spec, plant))),
               error_rms={"adaptive": _num(err["adaptive"]), "fixed": _num(err["fixed"])})
    return {"adaptation": out}


def regressor_json(result: Any) -> dict[str, Any]:
    """The feedforward/feedback structure's ``adaptation``: ``{structure, rule, parameters, initial, final,
    matching, error_rms}``; ``matching`` the ideal parameters of the nominal plant, ``matching_final`` those of the
    plant the run ends with (after a ``plant_change``)."""
    from designkit.families.mrac.regressor_checks import adaptation_error, final_ideal

    d, sim = result.design, result.simulation
    x = d.data
    out: dict[str, Any] = {"structure": "feedforward_feedback", "rule": x.rule, "parameters": list(x.parameters),
                           "initial": list(x.initial), "matching": list(x.structure.ideal)}
    if sim is None:
        return {**out, "final": None, "matching_final": None, "error_rms": None}
    plant = result.plant if result.plant is not None else d.plant
    check = next((c for c in result.checks if c.name == "adaptation_error"), None)
    if check is None:
        check = adaptation_error(d, context(result))[0]
    err = check.certificate["error_rms"]
    final_want = final_ideal(d, result.loaded.spec, plant)
    out.update(final=[_num(float(np.asarray(sim.signals[n])[-1])) for n in x.parameters],
               matching_final=list(final_want) if final_want is not None else None,
               error_rms={"adaptive": _num(err["adaptive"]), "fixed": _num(err["fixed"])})
    return out


def _f(x: float | None, digits: int = 3) -> str:
    return "—" if x is None or not math.isfinite(x) else fmt_number(x, digits)


def _pair(p: tuple[float, float]) -> str:
    return f"{_f(p[0], 4)}, {_f(p[1], 4)}"


def _row(c: Comparison) -> tuple[str, ...]:
    return (c.label, _f(c.rms_fixed), _f(c.rms_adaptive), _f(c.last_fixed), _f(c.last_adaptive), _pair(c.final),
            _pair(c.matching), "yes" if c.stable else "no")


HEADER = ("Scenario", "RMS e fixed (rad)", "RMS e adaptive (rad)", "last quarter fixed (rad)",
          "last quarter adaptive (rad)", "final a1, a2", "matching a1, a2", "bounded")


def _why_how(result: Any, s: Any) -> Question:
    d, spec = result.design, result.loaded.spec
    plant = result.plant if result.plant is not None else d.plant
    x = d.data
    link = final_link(spec, plant)
    K1, K2 = gains_of(x.initial, x.nominal_Km, x.nominal_tau)
    c = coefficients_of(K1, K2, *link)
    poles = ReferenceModel(c).poles if min(c) > 0 else tuple(np.roots([1.0, c[1], c[0]]))
    m = s.main
    model_poles = ReferenceModel(x.reference_model.a).poles
    where = (f"on the link at the end of the run (Km = {link[0]:g}, τ = {link[1]:g} s) they place the poles at "
             f"{fmt_poles(poles)} 1/s")
    if np.allclose(sorted(poles, key=lambda p: (p.real, p.imag)), sorted(model_poles, key=lambda p: (p.real, p.imag)),
                   rtol=1e-9):
        where += ", the model's own: the fixed-gain loop is the model and there is nothing to adapt to"
    else:
        where += f" instead of the model's {fmt_poles(model_poles)} 1/s"
    sentences = [
        f"Why: the fixed PD gains K1 = {_f(K1, 4)} N·m/rad, K2 = {_f(K2, 4)} N·m·s/rad are realised for the nominal "
        f"link (Km = {x.nominal_Km:g}, τ = {x.nominal_tau:g} s); {where}, and the fixed-gain loop "
        f"leaves the model by {_f(m.rms_fixed)} rad RMS over the run ({_f(m.last_fixed)} rad over its last quarter).",
        "How: the closed-loop coefficients a1, a2 (realised through K1, K2 on the nominal link) follow the gradient "
        "rule α' = Γ Sᵀ Q e, with S = ∂ym/∂a from the sensitivity model CasADi generates from the reference model "
        "(the notes' approximation ∂e/∂α ≈ −∂ym/∂a)" + (f", modified: {describe(x.modification)}."
                                                         if x.modification else "."),
        f"With what success: {_f(m.rms_adaptive)} rad RMS with adaptation against {_f(m.rms_fixed)} rad without "
        f"({_f(100 * m.rms_adaptive / m.rms_fixed if m.rms_fixed else math.nan)} %), {_f(m.last_adaptive)} rad "
        f"against {_f(m.last_fixed)} rad over the last quarter; a1, a2 end at {_pair(m.final)}, the values that put "
        f"the link on the model being {_pair(m.matching)}.",
    ]
    return Question("Why, how and with what success a model reference adaptive controller?", tuple(sentences),
                    (Table("The spec's scenario", HEADER, (_row(m),)),))


def _outcome(c: Comparison) -> str:
    """What happened to the parameters of one scenario, in words."""
    if not c.stable:
        return "the adaptive run did not stay bounded"
    if c.converged:
        return f"a1, a2 reached the matching values {_pair(c.matching)} (within 5 %)"
    return f"a1, a2 ended at {_pair(c.final)}, not at the matching values {_pair(c.matching)}"


def _edge(c: Comparison) -> str:
    """Where the linearized stability boundary of a scenario lies against the spec's gains."""
    if c.boundary is None:
        return ""
    side = "above" if c.boundary > 1.0 else "below"
    return f"; its linearized stability boundary is at γ × {_f(c.boundary)}, {side} the spec's gains"


def _plant_question(s: Any) -> Question:
    rows = tuple(_row(c) for c in (s.main, *s.plant))
    scenarios = (s.main, *s.plant)
    better = sum(1 for c in scenarios if c.stable and c.rms_fixed is not None and c.rms_adaptive < c.rms_fixed)
    sentences = [f"Adaptation stayed bounded and lowered the RMS error in {better} of the {len(scenarios)} step "
                 "changes of the link simulated (the spec's and the table's others)."]
    for c in s.plant:
        sentences.append(f"{c.label}: {_f(c.rms_adaptive)} rad RMS with adaptation, {_f(c.rms_fixed)} rad without; "
                         f"{_outcome(c)}; the link's gain ratio k = Km τn/(Kmn τ) becomes {_f(c.k)}{_edge(c)}.")
    sentences.append("The stability boundary of the rule scales as 1/k: a change that raises the link's gain Km or "
                     "lowers its time constant τ makes the same adaptation gains more aggressive.")
    if not s.periodic:
        sentences.append("The reference is not periodic: once it stops moving the link rests on it whatever Km and τ, "
                         "the sensitivities decay to zero and nothing excites the adaptation; a square wave or a PRBS "
                         "keeps it excited.")
    return Question("Behaviour with and without adaptation as a function of the plant time constant and static gain",
                    tuple(sentences), (Table("Step changes of the link during the run (the controller is not told)",
                                             HEADER, rows),))


def _other_question(s: Any) -> Question:
    rows = tuple(_row(c) for c in (*s.initial, *s.model))
    sentences = [f"{c.label}: {_f(c.rms_adaptive)} rad RMS with adaptation, {_f(c.rms_fixed)} rad with the gains "
                 f"frozen at their initial values; {_outcome(c)}." for c in (*s.initial, *s.model)]
    if s.initial:
        sentences.append("The initial parameters are the adaptation's initial condition: the linearized boundary does "
                         "not depend on them (it is the loop about the matched trajectory), the transient does.")
    return Question("Behaviour as a function of the initial conditions and of the reference model's parameters",
                    tuple(sentences) or ("Not simulated (budget).",),
                    (Table("Other starting parameters and a faster reference model", HEADER, rows),) if rows else ())


def _module_question(result: Any, s: Any) -> Question:
    bd = s.boundary
    rows = [(f"γ × {r.scale:.3g}", _f(r.rms), _pair(r.final), "yes" if r.stable else "no") for r in
            sorted(bd.runs, key=lambda r: r.scale)]
    rows += [(c.label, _f(c.rms_adaptive), _pair(c.final), "yes" if c.stable else "no")
             for c in (*s.gains, *s.weighting)]
    sentences = []
    for c in s.gains:
        sentences.append(f"{c.label}: {_f(c.rms_adaptive)} rad RMS against {_f(s.main.rms_adaptive)} rad at the "
                         f"spec's gains; {_outcome(c)}: the averaged rule removes a parameter error at a rate "
                         "proportional to γ (the convergence check's ρ).")
    for c in s.weighting:
        sentences.append(f"{c.label} (Q): {_f(c.rms_adaptive)} rad RMS; {_outcome(c)}{_edge(c)}.")
    if s.weighting and s.main.boundary is not None:
        sentences.append(f"Q multiplies γ in the rule, so scaling Q as a whole is scaling γ; its shape moves the "
                         f"boundary (γ × {_f(s.main.boundary)} at the spec's Q): the position weight enters the "
                         "destabilizing constant term c0 of the frozen loop's polynomial, the velocity weight its "
                         "damping term c1, which helps or hurts depending on the sensitivities' phase.")
    return Question("What is the influence of the adaptation module's parameters (error weighting Q, gains γ)?",
                    tuple(sentences) or ("Not simulated (budget).",),
                    (Table("Adaptive runs of the spec's scenario with other gains and weightings",
                           ("Run", "RMS e (rad)", "final a1, a2", "bounded"), tuple(rows)),))


def _boundary_question(result: Any, s: Any) -> Question:
    bd, gamma = s.boundary, np.asarray(result.design.data.gamma, dtype=float)
    g = lambda k: ", ".join(_f(k * v, 4) for v in gamma)  # noqa: E731
    sentences = []
    if bd.lo is not None and bd.hi is not None:
        sentences.append(f"Simulated: the run stays bounded at γ × {_f(bd.lo, 3)} (γ = {g(bd.lo)}) and diverges at "
                         f"γ × {_f(bd.hi, 3)} (γ = {g(bd.hi)}), bisected in {len(bd.runs)} runs (bounded: finite, "
                         "|e| within ten times the reference swing and its RMS not growing by more than 10 % from "
                         "one window to the next).")
    else:
        sentences.append(f"Simulated: no boundary bracketed within {len(bd.runs)} runs (largest bounded "
                         f"γ × {_f(bd.lo, 3)}, smallest unbounded γ × {_f(bd.hi, 3)}).")
    if s.floquet is not None:
        sentences.append(f"Linearized about the matched trajectory (plant on the model), the periodic loop's Floquet "
                         f"multipliers leave the unit circle at γ × {_f(s.floquet['scale'], 3)} "
                         f"(γ = {g(s.floquet['scale'])}): above it the parameters no longer converge but oscillate "
                         "(a limit cycle) until the run diverges.")
    if s.frozen is not None:
        ratio = (bd.lo / s.frozen["scale"]) if bd.lo else math.nan
        sentences.append(f"Analytic (frozen signals and Routh, the argument of Åström and Wittenmark, Adaptive "
                         f"Control, 2nd ed., ch. 5, for the MIT rule): γ × {_f(s.frozen['scale'], 3)} "
                         f"(γ = {g(s.frozen['scale'])}), "
                         f"from s³ + a2 s² + (a1 + k c1) s + k c0 at the worst instant t = {_f(s.frozen['at'], 4)} s "
                         f"(k = {_f(s.frozen['k'], 3)}): {_f(ratio, 3)} times below the simulated bounded end, a "
                         "conservative estimate, since the signals it freezes change on the loop's own time scale.")
    sentences.append("Bounded is not verified, and the outcome need not be monotone in γ: the boundary study of this "
                     "report judges each γ by every required check on a grid refined where the outcome changes, and "
                     "recommends a γ only where its neighbourhood passes too.")
    sentences.append("Every estimate scales as 1/(k A² q): γ enters only multiplied by the squared reference "
                     "amplitude A (S and the regressor are proportional to A), by the scale q of Q and by the "
                     "link's gain ratio k = Km τn/(Kmn τ).")
    if s.amplitude is not None:
        factor, runs = s.amplitude
        lo, hi = runs
        held = lo.stable and not hi.stable
        verdict = "holds" if held else "does not hold exactly (the finite parameter error of the change does not scale)"
        sentences.append(f"Check of the amplitude law: with the amplitude × {factor:g}, the bracket divided by "
                         f"{factor ** 2:g} gives γ × {_f(lo.scale, 3)} {'bounded' if lo.stable else 'not bounded'} and "
                         f"γ × {_f(hi.scale, 3)} {'bounded' if hi.stable else 'not bounded'}: the 1/A² law "
                         f"{verdict}.")
    rows = [(f"γ × {r.scale:.3g}", g(r.scale), _f(r.rms), _f(r.growth), "yes" if r.stable else "no")
            for r in sorted(bd.runs, key=lambda r: r.scale)]
    return Question("Where does the gradient rule lose stability as γ or the reference amplitude grows?",
                    tuple(sentences), (Table("Bisection on the adaptation-gain scale",
                                             ("Scale", "γ", "RMS e (rad)", "growth", "bounded"), tuple(rows)),))


def _perturbation_question(s: Any) -> Question:
    sentences = []
    p, rsp = s.perturbation, s.response
    if p is not None:
        text = f"{p.label}: RMS e {_f(p.rms_adaptive)} rad with adaptation, {_f(p.rms_fixed)} rad without."
        if p.converged:
            text += (f" a1, a2 stay near {_pair(p.matching)} (they end at {_pair(p.final)}): the load's offset "
                     "excites no sensitivity while the reference is still, so adaptation neither helps nor harms.")
        else:
            text += (" The reference model has no perturbation, so the rule reads the offset the load causes as a "
                     f"parameter error: a1, a2 drift to {_pair(p.final)} (the link itself needs {_pair(p.matching)})")
            text += ", a loop that would be unstable if frozen there." if min(p.final) <= 0 else "."
        sentences.append(text)
    if rsp.get("rise_model") is not None:
        sentences.append(f"Response time on the last rising edge (t = {_f(rsp['edge_at'], 4)} s): 10–90 % rise "
                         f"{_f(rsp['rise_model'])} s for the model, {_f(rsp.get('rise_adaptive'))} s for the adaptive "
                         f"loop, {_f(rsp.get('rise_fixed'))} s for the fixed-gain loop.")
    sentences.append(f"Control level: peak |u| {_f(rsp['peak_u_adaptive'])} N·m with adaptation, "
                     f"{_f(rsp['peak_u_fixed'])} N·m with fixed gains"
                     + (f" ({_f(rsp['peak_u_before'])} N·m before the plant change)."
                        if rsp.get("peak_u_before") is not None else "."))
    return Question("What is the sensitivity to external perturbations, the response time, the required control "
                    "level?", tuple(sentences))


def _modifications_question(s: Any) -> Question:
    finals = [r.final for r in s.boundary.runs if r.stable and all(math.isfinite(v) for v in r.final)]
    spread = max((abs(f - m) / abs(m) for r in finals for f, m in zip(r, s.main.matching, strict=True)), default=0.0)
    sentences = ["The boundary's 1/A² dependence is the MIT rule's known weakness: normalising the rule by the "
                 "sensitivities' size (α' = Γ Sᵀ Q e / (ε + ‖S‖²), the normalized MIT rule of Åström and "
                 "Wittenmark, ch. 5) makes it independent of the amplitude."]
    if spread > 0.1:
        a2 = [r[1] for r in finals]
        sentences.append(f"Near the boundary the parameters wander (a2 ends between {_f(min(a2), 3)} and "
                         f"{_f(max(a2), 3)} 1/s in the bounded runs, the matching value being "
                         f"{_f(s.main.matching[1], 3)}): projecting them onto a1, a2 > 0 keeps every frozen loop "
                         "stable; a dead zone on small |e| stops the drift a perturbation or noise causes.")
    else:
        sentences.append("The bounded runs all end within 10 % of the matching values; a dead zone on small |e| would "
                         "still be needed against the drift a perturbation or noise causes.")
    sentences.append("Each of the three is a setting of this family (controller.modification: normalized, dead_zone or "
                     "projection, derived in docs/families/mrac.md).")
    return Question("What ad hoc modifications of the off-the-shelf algorithm might be required?", tuple(sentences))


def section(result: Any) -> ReportSection | None:
    """The MRAC simulator's questions answered from re-simulations (module docstring); None without a run."""
    s = study(result)
    if s is None:
        return None
    questions = (_why_how(result, s), _plant_question(s), _other_question(s), _module_question(result, s),
                 _boundary_question(result, s), _perturbation_question(s), _modifications_question(s))
    intro = (f"Each answer comes from re-simulating the spec's scenario with one thing changed, with adaptation and "
             f"with the gains frozen at their initial values ({s.runs} simulations); e = ym − x1 "
             "is measured against the same reference model in every pair.")
    return ReportSection("lab-mrac", "Lab questions (notes, experiment 2 and the MRAC simulator)", intro, questions)
