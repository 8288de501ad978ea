"""Lab experiment 1 of the notes (appendix A): a classical PID on a robotic link, answered with numbers from runs.

Applies to the families that are a classical PID (trait ``"pid"``: the servo and the tracker on a link, the
decentralized PID of an arm).  The notes' questions, each answered from the spec's own run or from variants of it
run through the family's own run (:mod:`designkit.runner`) and judged by the family's checks:

* how well a PID performs and how to characterize performance -- the spec's run measured;
* the function of each component, how to tune the gains and how gain variations influence performance -- the gain
  study's rows (:mod:`designkit.studies.gains`), which this study cites;
* the influence of the other controller parameters: sampling period, quantization, measurement noise, maximum
  control level, delay -- variants of the scenario (:mod:`~designkit.studies.lab1.scenario`); the transducer gain is
  said not to be simulated;
* the influence of the manipulator's parameters (masses, lengths, viscosity, inertia) -- the controller designed
  as before, the plant changed; the configuration and the intercouplings are the arm study's
  (:mod:`designkit.studies.arm`) on an arm, and a single link has neither;
* a PID's most advantageous and disadvantageous features -- decided from the variants' outcomes
  (:mod:`~designkit.studies.lab1.features`).
"""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number, unit
from designkit.display.section import Question, ReportSection, Table
from designkit.studies.core.metrics import metrics_of
from designkit.studies.core.study import Entry, Row, Study, StudyContext, StudyResult
from designkit.studies.core.variants import nominal_row, run_row
from designkit.studies.core.words import change, outcome_words
from designkit.studies.lab1.features import feature_sentences
from designkit.studies.lab1.scenario import plant_changes, scenario_changes

__all__ = ["STUDY"]

TITLE = "Lab experiment 1 (notes, appendix A): a classical PID on a robotic link"

_GROUPS = {"sampling": "sampling period", "delay": "delay in the control", "noise": "measurement noise",
           "quantization": "quantization of the command", "limit": "maximum control level",
           "load": "a constant load", "viscosity": "viscosity", "inertia": "inertia", "masses": "link masses",
           "lengths": "link lengths"}


def _applies(result: Any, family: Any) -> bool:
    return result.simulation is not None and "pid" in family.traits


def _table(caption: str, rows: list[tuple[str, Row]], metrics: tuple) -> Table:
    header = ("Variant", "Outcome", *(m.label + (f" ({unit(m.unit)})" if m.unit else "") for m in metrics))
    return Table(caption, header, tuple((label, r.outcome if not r.detail else f"{r.outcome}: {r.detail}",
                                         *(fmt_number(r.metrics.get(m.key), 4) for m in metrics))
                                        for label, r in rows))


def _variant_sentences(rows: list[tuple[str, Row]], nominal: Row, metric: Any) -> tuple[str, ...]:
    out = []
    for label, r in rows:
        text = f"With {label}, {outcome_words(r.outcome, r.detail)}"
        if metric is not None and r.outcome in ("verified", "failed", "undecided"):
            moved = change(nominal.metrics.get(metric.key), r.metrics.get(metric.key), metric.unit)
            text += f"; {metric.label} {moved}"
        out.append(text + ".")
    return tuple(out)


def _performance(result: Any, nominal: Row, metrics: tuple) -> tuple[str, ...]:
    parts = [f"{m.label} {fmt_number(nominal.metrics.get(m.key), 4)}{(' ' + unit(m.unit)) if m.unit else ''}"
             for m in metrics if nominal.metrics.get(m.key) is not None]
    verdict = outcome_words(nominal.outcome, nominal.detail)
    out = [f"On the spec's run: {', '.join(parts)}; judged by every check the family offers, {verdict}."]
    out.append("Performance is characterized by the requirement checks of the report (overshoot, settling, rise, "
               "static and tracking error, peak command) and by the linear loop's margins; the figures show the "
               "response and the command they are measured on.")
    if getattr(result.plant, "kind", "") == "robot":
        out.append("Per joint, the arm section of this report gives the peak, RMS and final error and the peak "
                   "torque.")
    return tuple(out)


def _gains_answer(ctx: StudyContext) -> tuple[str, ...]:
    gains = ctx.study("gains")
    gains_ = ctx.result.design.gains
    roles = "; ".join(f"{k} is the {gains_.meaning(k)} gain" if "gain" not in gains_.meaning(k) else
                      f"{k}: {gains_.meaning(k)}" for k in gains_ if gains_.meaning(k))
    out = ["The gains are computed from the requested closed-loop poles and zero (the design section: the "
           f"characteristic polynomial matched to them), so a PID is tuned by placing those poles. {roles}."]
    if gains is None or not gains.entries:
        out.append("No gain variant was run (see the gain study).")
        return tuple(out)
    for entry in gains.entries:
        for r in entry.rows:
            if r.factor == 1.0:
                continue
            out.append(f"{entry.parameter} ×{fmt_number(r.factor, 3)}: {outcome_words(r.outcome, r.detail)}.")
    out.append("The gain study's table gives every metric of those runs.")
    return tuple(out)


def _run(ctx: StudyContext) -> StudyResult:
    from designkit.runner.variants import vary_plant, vary_spec

    result, fam = ctx.result, ctx.family
    metrics = metrics_of(result, fam)
    primary = metrics[0] if metrics else None
    budget = ctx.new_budget()
    nominal = nominal_row(result, 1.0, metrics)
    scenario, plants = scenario_changes(result), plant_changes(result)
    ran: dict[str, list[tuple[str, Row]]] = {}
    planned = [(c.group, c.label, (lambda c=c: run_row(lambda: vary_spec(result, c.changes), c.size, c.size,
                                                        metrics))) for c in scenario]
    planned += [(p.group, p.label, (lambda p=p: run_row(lambda: vary_plant(result, p.values), p.factor, p.factor,
                                                         metrics))) for p in plants]
    room = budget.capacity()
    kept, left = planned[:room], [label for _, label, _ in planned[room:]]
    for (group, label, _), row in zip(kept, ctx.run_all([t for *_, t in kept], budget), strict=True):
        ran.setdefault(group, []).append((label, row))
    reduced = ""
    if left:
        why = (f"the studies' budget of {fmt_number(ctx.budget, 3)} s fits {room} at about "
               f"{fmt_number(budget.per_run, 2)} s each (raise studies.budget to run them)")
        reduced = f"{len(left)} variants not run ({'; '.join(left)}): {why}"
    scenario_groups = [g for g in ("sampling", "delay", "noise", "quantization", "limit", "load") if g in ran]
    plant_groups = [g for g in ("viscosity", "inertia", "masses", "lengths") if g in ran]
    other = [s for g in scenario_groups for s in _variant_sentences(ran[g], nominal, primary)]
    other.append("A transducer gain other than 1 is not simulated: designkit models no transducer element.")
    physical = [s for g in plant_groups for s in _variant_sentences(ran[g], nominal, primary)]
    robot = getattr(result.plant, "kind", "") == "robot"
    physical.append("The working configuration's influence is the arm section's (the inertia along the path and "
                    "each joint loop's poles at its ends)." if robot else
                    "A single link has no working configuration: its inertia is the one varied above.")
    coupling = (("The arm section of this report measures, along this run, the coupling torques each joint's loop "
                 "must reject against the joint's own inertial torque.",) if robot else
                ("A single link has no intercoupling, centripetal or Coriolis force: the question is the arm's (SIMNOG"
                 " specs).",))
    questions = (
        Question("How well does a PID perform? How to characterize performance?", _performance(result, nominal,
                                                                                                 metrics)),
        Question("What is the function of each of its components? How to tune the gains? How do gain variations "
                 "influence performance?", _gains_answer(ctx)),
        Question("What is the influence of the other controller parameters (sampling period, quantization, "
                 "measurement noise, transducer gains, maximum control level, delay)?", tuple(other),
                 (_table("The spec run again with one setting changed, everything else as designed",
                         [x for g in scenario_groups for x in ran[g]], metrics),) if scenario_groups else ()),
        Question("What is the influence of the manipulator's parameters (masses, inertias, lengths, configuration, "
                 "viscosity)?", tuple(physical),
                 (_table("The true plant changed, the controller designed as before (not told of the change)",
                         [x for g in plant_groups for x in ran[g]], metrics),) if plant_groups else ()),
        Question("How effective is a PID in neutralizing intercouplings, centripetal and Coriolis forces?", coupling),
        Question("What are a PID's most advantageous and disadvantageous features?",
                 feature_sentences(ran, nominal, primary)),
    )
    intro = ("The questions of the notes' simulation experiment 1, answered for this design from the spec's run and "
             "from variants of it, each run through the family's own run and judged by the same checks."
             + (f" Reduced: {reduced}." if reduced else ""))
    entries = tuple(Entry(g, "", tuple(r for _, r in ran[g])) for g in (*scenario_groups, *plant_groups))
    return StudyResult("lab1", TITLE, entries, ReportSection("lab1", TITLE, intro, questions), (), reduced,
                       budget.runs, budget.spent)


STUDY = Study(name="lab1", title=TITLE, order=40, applies=_applies, run=_run)
"""Lab experiment 1 (module docstring)."""
