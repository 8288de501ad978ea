"""Lab experiment 2 (notes, appendix A): the MRAC and SELFTUNE simulators compared on one link.

The contributed section (:data:`designkit.comparison.answers.CONTRIBUTIONS`) of a comparison that includes an
MRAC and a self-tuning controller.  It answers the experiment's comparative questions with numbers from the
runs: the table's metrics, what each family reports of its own run (its ``--json`` fields: the adapted
parameters, the estimates), the re-simulations of :mod:`designkit.comparison.studies` (an external
perturbation step, the adaptation parameters changed, a larger plant change) and the answer each family's own
report gives to the ad hoc modifications question.
"""

from __future__ import annotations

import math
from typing import Any

from designkit.comparison.studies import perturbation_run, rise_times, variant
from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table
from designkit.families.mrac.laws import KIND as MRAC
from designkit.families.self_tuning.laws import KIND as SELF_TUNING

__all__ = ["ADAPTATION_SETTINGS", "applies", "section"]

ADAPTATION_SETTINGS: dict[str, tuple[str, str, tuple[Any, ...]]] = {
    MRAC: ("gamma", "adaptation gain γ", (0.1, 10.0)),  # factors of the spec's value
    SELF_TUNING: ("forgetting", "forgetting factor λ", (0.95, 0.999)),  # values
}
"""Kind -> (controller field, its name in words, the values tried: factors for ``gamma``, values otherwise)."""


def applies(kinds: tuple[str, ...]) -> bool:
    """The comparison includes an MRAC and a self-tuning controller."""
    return MRAC in kinds and SELF_TUNING in kinds


def _f(x: float | None, unit: str = "", digits: int = 3) -> str:
    if x is None:
        return "—"
    if math.isinf(x):
        return "never" if unit == "s" else "diverged"
    if 1e3 <= abs(x) < 1e9 and float(x) == round(x):
        return f"{int(round(x))} {unit}".strip()  # an adaptation gain of 10000, not 1e+04
    return f"{fmt_number(x, digits)} {unit}".strip()


def _pairs(result: Any) -> list[tuple[str, Any, Any]]:
    """``(label, run, row)`` of each controller."""
    return [(label, r, result.table.row(label)) for label, r in zip(result.labels, result.results, strict=True)]


def _own(run: Any) -> dict[str, Any]:
    from designkit.families import family

    fam = family(run.design.kind)
    try:
        return dict(fam.json(run)) if fam.json is not None else {}
    except Exception:  # noqa: BLE001 - a family's own summary is optional here
        return {}


def _vector(values: Any) -> str:
    return "(" + ", ".join(_f(v, digits=4) for v in values) + ")" if values else "—"


def _why(result: Any) -> Question:
    eu = result.table.error_unit
    sentences = []
    for label, run, row in _pairs(result):
        own = _own(run)
        v = row.values
        how = (f"{label}: departure from its run on the unchanged link {_f(v.get('rms_deviation'), eu)} RMS "
               f"({_f(v.get('max_deviation'), eu)} at most), back within 1 % of the reference's range "
               f"{_f(v.get('reconvergence'), 's')} after the change.")
        if run.design.kind == MRAC and "adaptation" in own:
            a = own["adaptation"]
            err = a.get("error_rms") or {}
            sentences.append(
                f"{label} adapts because the change moves the link off the reference model: the gradient rule "
                f"moves its PD coefficients {', '.join(a['parameters'])} from {_vector(a['initial'])} to "
                f"{_vector(a.get('final'))}, against {_vector(a.get('matching'))} that put the changed link on "
                f"the model; its output error against the reference model is {_f(err.get('adaptive'), eu)} RMS, "
                f"against {_f(err.get('fixed'), eu)} with the coefficients frozen at their initial values. " + how)
        elif run.design.kind == SELF_TUNING and "theta_hat" in own:
            names = ", ".join(own.get(SELF_TUNING, {}).get("parameters", ()))
            sentences.append(
                f"{label} adapts because its estimates of the sampled speed equation ({names}) no longer fit the "
                f"measurements: recursive least squares ends at {_vector(own['theta_hat'])} against the changed "
                f"link's {_vector(own.get('theta_true'))}, and the pole placement redesigned from them at every "
                f"sample restores the requested poles. " + how)
        else:
            sentences.append(how)
    return Question("Why does each controller adapt, and with what success?", tuple(sentences))


def _difference(result: Any) -> Question:
    keys = ("rms_deviation", "max_deviation", "reconvergence", "rms_error_after", "rms_settled_after",
            "rise_time_after", "peak_command", "rms_command")
    winners = [w.sentence for w in result.table.winners() if w.metric.key in keys]
    kinds = {r.design.kind: label for label, r, _ in _pairs(result)}
    ts = next((r.design.extra.get("Ts") for r in result.results if r.design.kind == SELF_TUNING), None)
    words = (f"The difference is one of structure: {kinds[MRAC]} is a direct scheme (it adjusts the controller's "
             f"gains from the output error against a reference model, in continuous time), {kinds[SELF_TUNING]} "
             f"an indirect one (it estimates the link's parameters and recomputes the controller from them, "
             f"sampled every {_f(ts, 's')}). On the same run:")
    return Question("What is the comparative difference?", (words, *winners))


def _parameters(result: Any) -> Question:
    eu = result.table.error_unit
    rows, sentences = [], []
    for label, run, row in _pairs(result):
        setting = ADAPTATION_SETTINGS.get(run.design.kind)
        if setting is None:
            continue
        field, words, tried = setting
        current = getattr(run.loaded.spec.controller, field)
        shown_current = current if not isinstance(current, list) else current[0]
        runs = [(shown_current, row.values, True)]
        for x in tried:
            value = ([c * x for c in current] if isinstance(current, list) else current * x) if field == "gamma" else x
            v = variant(label, run, field, value)
            runs.append((value if not isinstance(value, list) else value[0], v.metrics, v.stable))
        for value, m, stable in runs:
            rows.append((label, words, _f(value, digits=4), _f(m.get("rms_deviation"), eu),
                         _f(m.get("reconvergence"), "s"), _f(m.get("peak_command"), result.table.command_unit),
                         "yes" if stable else "no"))
        bounded = [r for r in runs if r[2] and r[1].get("reconvergence") is not None]
        if bounded:
            fastest = min(bounded, key=lambda r: r[1]["reconvergence"])
            others = "; ".join(f"{_f(v, digits=4)}: {_f(m.get('reconvergence'), 's')}, departure "
                               f"{_f(m.get('rms_deviation'), eu)} RMS, peak command "
                               f"{_f(m.get('peak_command'), result.table.command_unit)}"
                               + ("" if ok else ", diverged") for v, m, ok in runs if (v, m, ok) != fastest)
            sentences.append(f"{label}: of the {words} values tried, {_f(fastest[0], digits=4)} re-converges "
                             f"fastest ({_f(fastest[1]['reconvergence'], 's')} after the change, departure "
                             f"{_f(fastest[1].get('rms_deviation'), eu)} RMS); " + others + ".")
    table = Table("Each controller with its adaptation parameter changed (the first row of each: the spec's value)",
                  ("controller", "parameter", "value", "RMS departure", "re-convergence", "peak command", "bounded"),
                  tuple(rows))
    intro = ("Each controller was run again on the same task with its adaptation parameter changed (the MRAC's "
             "adaptation gain divided and multiplied by 10, the estimator's forgetting factor lowered and raised); "
             "re-convergence and departure are measured as in the table.")
    return Question("What is the influence of the adaptation parameters?", (intro, *sentences), (table,))


def _strategies(result: Any) -> Question:
    from designkit.families import family

    sentences = []
    for label, run, _ in _pairs(result):
        d = run.design
        c = run.loaded.spec.controller
        poles = ", ".join(_f(complex(p).real, digits=3) for p in (getattr(c, "poles", None) or d.poles))
        if d.kind == MRAC:
            law = family(d.kind).display.law
            sentences.append(f"{label}: a PD position servo {law[0].split(',')[0]} whose coefficients α1, α2 follow "
                             f"the gradient rule ({law[-1].split(',')[0]}) with γ = "
                             f"{_f(c.gamma if not isinstance(c.gamma, list) else c.gamma[0])}, in continuous time; the "
                             f"reference model has the poles {poles} 1/s.")
        elif d.kind == SELF_TUNING:
            observer = min(p.real for p in d.poles)
            extra = f" (observer pole {_f(observer, digits=3)} 1/s)" if len(d.poles) > 2 else ""
            sentences.append(f"{label}: recursive least squares with forgetting factor {_f(c.forgetting, digits=4)} "
                             f"on the {c.estimator} equation, sampled every {_f(c.sampling_period, 's')}, and a "
                             f"{c.design.replace('_', ' ')} redesign (Diophantine equation) at every sample for the "
                             f"poles {poles} 1/s{extra}.")
    return Question("What are the control strategies?", tuple(sentences))


def _ad_hoc(result: Any) -> Question:
    from designkit.families import family

    sentences = []
    for label, run, _ in _pairs(result):
        found = None
        for make in family(run.design.kind).sections:
            sec = make(run)
            for q in getattr(sec, "questions", ()) if sec is not None else ():
                if "ad hoc" in q.question.lower():
                    found = q
                    break
            if found is not None:
                break
        if found is not None and found.sentences:
            sentences.append(f"{label} (its own report answers): " + " ".join(found.sentences[:2]))
    return Question("What ad hoc modifications does each need?", tuple(sentences) or (
        "Neither family's own report answers this question.",))


def _perturbation(result: Any) -> Question:
    eu = result.table.error_unit
    spec = result.loaded.spec
    t_end = float(spec.simulation.duration or result.results[0].simulation.time[-1])
    change = spec.simulation.plant_change
    tc = float(change.time) if change is not None else 0.0
    period = float(getattr(spec.simulation.trajectory, "period", 0.0) or 0.0)
    onset = round(tc + (t_end - tc) / 2.0 + period / 4.0, 6)
    peaks = [row.values.get("peak_command") for row in result.table.rows]
    value = float(f"{0.1 * min(p for p in peaks if p is not None and math.isfinite(p)):.1g}")
    runs = [perturbation_run(label, run, value, onset) for label, run, _ in _pairs(result)]
    rows = tuple((p.label, _f(p.rms, eu), _f(p.peak, eu), _f(p.recovery, "s"), _f(p.final, eu)) for p in runs)
    best = min(runs, key=lambda p: p.peak)
    worst = max(runs, key=lambda p: p.peak)
    unit = result.table.command_unit
    words = (f"Each controller was run again with an input-equivalent perturbation step of {_f(value, unit)} (a tenth "
             f"of the smaller peak command) from {_f(onset, 's')} on, after the plant change, and compared with its "
             f"own run without it. {best.label} is the less sensitive: it moves by {_f(best.peak, eu)} at most "
             f"against {_f(worst.peak, eu)} for {worst.label}; over the last period the perturbation leaves "
             + ", ".join(f"{_f(p.final, eu)} ({p.label})" for p in runs) + ".")
    table = Table("Departure |x − x0| from the unperturbed run after the perturbation step",
                  ("controller", "RMS", "largest", "back within 1 % after", "left over the last period"), rows)
    return Question("How sensitive is each to an external perturbation?", (words,), (table,))


def _response(result: Any) -> Question:
    change = result.loaded.spec.simulation.plant_change
    tc = float(change.time) if change is not None else math.inf
    rows, sentences = [], []
    for label, run, row in _pairs(result):
        edges = rise_times(run.simulation)
        before = [r for e, r in edges if e < tc]
        after = [r for e, r in edges if e >= tc]
        b, a = (before[-1] if before else None), (after[-1] if after else None)
        first = after[0] if after else None
        rows.append((label, _f(b, "s"), _f(first, "s"), _f(a, "s"), _f(row.values.get("reconvergence"), "s")))
        sentences.append(f"{label}: 90 % of a reference step is reached in {_f(b, 's')} on the last step before the "
                         f"change, {_f(first, 's')} on the first after it and {_f(a, 's')} on the last of the run.")
    table = Table("Rise time to 90 % of each square-wave step",
                  ("controller", "last before the change", "first after", "last of the run", "re-convergence"),
                  tuple(rows))
    return Question("What is each controller's response time?", tuple(sentences), (table,))


def _level(result: Any) -> Question:
    t = result.table
    cu = t.command_unit
    sentences = tuple(f"{r.label}: peak |u| {_f(r.values.get('peak_command'), cu)} "
                      f"({_f(r.values.get('peak_command_after'), cu)} after the change), RMS "
                      f"{_f(r.values.get('rms_command'), cu)}." for r in t.rows)
    return Question("What control level does each need?", sentences)


def _robustness(result: Any) -> Question:
    from designkit.spec.sections import PlantChange

    eu = result.table.error_unit
    change = result.loaded.spec.simulation.plant_change
    if change is None:
        return Question("How robust is each?", ("The spec has no plant change to enlarge.",))
    values = dict(change.values)
    larger = {**values, "tau": 1.6 * float(result.results[0].loaded.spec.plant.tau)} if hasattr(
        result.loaded.spec.plant, "tau") else values
    new = PlantChange(time=change.time, values=larger)
    words = ", ".join(f"{k} = {_f(v, digits=4)}" for k, v in larger.items())
    sentences = [f"Each controller was run again with a larger change at {_f(float(change.time), 's')}: the link "
                 f"becomes {words} (the time constant too grows, by 60 %, the change of the SELFTUNE example)."]
    rows = []
    for label, run, row in _pairs(result):
        v = variant(label, run, "plant_change", new, section="simulation")
        rows.append((label, "yes" if row.verified else "no", _f(v.metrics.get("rms_deviation"), eu),
                     _f(v.metrics.get("reconvergence"), "s"), "yes" if v.stable else "no"))
        sentences.append(f"{label}: " + (f"stays bounded, departure {_f(v.metrics.get('rms_deviation'), eu)} RMS, "
                                         f"re-converged {_f(v.metrics.get('reconvergence'), 's')} after the change."
                                         if v.stable else "the run diverges: the adaptation does not survive this "
                                         "change with the spec's settings."))
    table = Table("Each controller through the larger change",
                  ("controller", "verified on the spec's change", "RMS departure", "re-convergence", "bounded"),
                  tuple(rows))
    return Question("How robust is each?", tuple(sentences), (table,))


def section(result: Any) -> ReportSection | None:
    """The experiment's comparative questions answered from the runs (None when a run is missing)."""
    if any(r.simulation is None for r in result.results):
        return None
    return ReportSection(
        anchor="lab-2-comparison", title="Lab experiment 2: MRAC against SELFTUNE",
        intro="The comparative questions of the experiment, answered from the controllers' runs of the shared task "
              "and from re-simulations of the same runs with one thing changed (numbers measured, not quoted).",
        questions=(_why(result), _difference(result), _parameters(result), _strategies(result), _ad_hoc(result),
                   _perturbation(result), _response(result), _level(result), _robustness(result)),
    )
