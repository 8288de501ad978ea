"""Lab experiment 2 (notes, appendix A): the MRAC and SELFTUNE simulators compared on one task, answered from the
runs.

A comparison study: it applies to a comparison (``controllers:``) one of whose members' families declares the traits
``adaptive`` and ``model_reference`` and another ``adaptive`` and ``certainty_equivalence``
(:attr:`designkit.synthesis.family.Family.traits`).  It reaches the members' families only through what they declare:
their ``how`` and ``strategy`` answers, their knobs with an adaptation role, their variants with the role
``modification``, their metrics (:mod:`designkit.studies.core.members`).  The experiment's comparative questions:

* why each adapts and with what success -- its family's answer on its run, the table's departure, its verdict;
* the comparative difference -- the schemes (from the traits), continuous or sampled (the law), the table's winners;
* the influence of the adaptation parameters -- each run again with its adaptation gain or forgetting factor moved
  (:mod:`~designkit.studies.lab2.runs`);
* the control strategies -- each family's answer;
* the ad hoc modifications that might be required -- each modification the families declare, run on the shared task
  and through a larger change;
* the sensitivity to an external perturbation, the response time, the control level, the robustness to a larger
  change -- runs made here and the members' own runs.
"""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number
from designkit.display.section import ReportSection
from designkit.studies.core.members import members, with_traits
from designkit.studies.core.study import Entry, Study, StudyContext, StudyResult
from designkit.studies.lab2 import questions as q
from designkit.studies.lab2.runs import (
    Plan,
    adaptation_runs,
    larger_change,
    modification_runs,
    perturbation,
    perturbed_runs,
    scenario_runs,
)

__all__ = ["STUDY", "TITLE"]

TITLE = "Lab experiment 2 (notes, appendix A): model reference adaptive control against a self-tuning regulator"


def _applies(result: Any, family: Any) -> bool:
    found = members(result)
    return (all(m.run.simulation is not None for m in found) and bool(with_traits(found, "adaptive", "model_reference"))
            and bool(with_traits(found, "adaptive", "certainty_equivalence")))


def _larger_words(values: dict[str, float], at: float) -> str:
    return f"at {fmt_number(at, 4)} s the plant becomes " + ", ".join(f"{k} = {fmt_number(v, 4)}"
                                                                       for k, v in values.items())


def _run(ctx: StudyContext) -> StudyResult:
    result = ctx.result
    found = members(result)
    adaptive = with_traits(found, "adaptive")
    by_label = {m.label: m for m in found}
    eu, cu = result.table.error_unit, result.table.command_unit
    plan = Plan(ctx.new_budget())
    adaptation = {m.label: adaptation_runs(m, plan) for m in adaptive}
    scenario = {m.label: modification_runs(m, plan) for m in adaptive}
    larger = larger_change(result)
    change = result.loaded.spec.simulation.plant_change
    larger_words = _larger_words(larger, float(change.time)) if larger is not None else ""
    through, robust = {}, []
    if larger is not None:
        moved = (("simulation.plant_change", {"time": float(change.time), "values": larger}),)
        robust = [d for m in found if (d := scenario_runs(m, plan, moved, "the larger change")) is not None]
        through = {m.label: modification_runs(m, plan, moved, " through the larger change") for m in adaptive}
    step = perturbation(result)
    perturbed = [p for m in found if step is not None and (p := perturbed_runs(m, plan, *step)) is not None]
    reduced = ""
    if plan.left:
        reduced = (f"{len(plan.left)} runs left out ({'; '.join(plan.left)}): the studies' budget of "
                   f"{fmt_number(ctx.budget, 3)} s fits about {plan.budget.runs} at "
                   f"{fmt_number(plan.budget.per_run, 2)} s each (raise studies.budget to run them)")
    if plan.budget.overrun:
        reduced = "; ".join(filter(None, (reduced, plan.budget.overrun_words())))
    tc = float(change.time) if change is not None else float("inf")
    questions = (
        q.why_question(adaptive, eu),
        q.difference_question(adaptive, result.table.winners()),
        q.adaptation_question(adaptation, by_label, eu, cu),
        q.strategies_question(found),
        q.modifications_question(adaptive, scenario, through, {d.label: d for d in robust}, larger_words),
        q.perturbation_question(perturbed, *(step or (0.0, 0.0)), eu, cu),
        q.response_question(found, tc),
        q.level_question(found, cu),
        q.robustness_question(robust, larger_words, eu),
    )
    intro = ("The experiment's comparative questions, answered from the controllers' own runs of the shared task and "
             "from runs of each controller with one thing changed, each through its family's own run and judged by "
             "its own checks (numbers measured, not quoted)." + (f" Reduced: {reduced}." if reduced else ""))
    section = ReportSection("lab-2-comparison", TITLE, intro, questions)
    entries = (*(Entry(f"{label}: {knob.key}", knob.unit, tuple(sorted((d.row for d in done), key=lambda r: r.factor)))
                 for label, knobs in adaptation.items() for knob, done in knobs),
               *(Entry(f"{label}: {variant.key}", "", (d.row,)) for label, runs in scenario.items()
                 for variant, d in runs),
               *(Entry(f"{d.label}: larger change", "", (d.row,)) for d in robust),
               *(Entry(f"{label}: {variant.key} through the larger change", "", (d.row,))
                 for label, runs in through.items() for variant, d in runs),
               *(Entry(f"{p.measured.label}: perturbation", "", (p.measured.row,)) for p in perturbed))
    return StudyResult("lab2", TITLE, entries, section, (), reduced, plan.budget.runs, plan.budget.spent)


STUDY = Study(name="lab2", title=TITLE, order=50, applies=_applies, run=_run, comparison=True)
"""Lab experiment 2 (module docstring)."""
