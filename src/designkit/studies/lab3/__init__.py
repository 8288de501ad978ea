"""Lab experiment 3 (notes, appendix A): sliding-mode control of ROBEL's elastic joint against PID and the linear
state regulator, answered from the runs.

A comparison study: it applies to a comparison (``controllers:``) one of whose members' families declares the traits
``switching`` and ``state_feedback`` (a sliding-mode state regulator) and another ``state_feedback`` without
``switching`` (the linear state regulator) (:attr:`designkit.synthesis.family.Family.traits`).  It reaches the
members' families only through what they declare: their ``how`` and ``strategy`` answers, their knobs that are spec
settings, their ``load_offset`` prediction, their metrics (:mod:`designkit.studies.core.members`).  Every answer is a
number measured on a run it made or on a member's own run:

* **why, how, with what success** -- each switching member's family's answer, the table and the chattering;
* **parameter importance** -- one setting at a time (:mod:`~designkit.studies.lab3.runs`);
* **structure and algorithms** -- each family's answer, the states its law reads, its controller states and how it is
  integrated (the law's declarations);
* **the comparison, the perturbation sensitivity, the response time and the control level** -- the table, the runs
  without the load against the family's predicted offset, the chattering (:mod:`~designkit.studies.lab3.measures`);
* **robustness** -- each designed law at every corner of ``plant.uncertainty``, with its checks there;
* **reliability** -- each switching member with its command sampled at a ladder of rates: its own rate study
  (:mod:`designkit.studies.rate`, run once for the member and laid out in its own report), cited through
  :meth:`~designkit.studies.core.study.StudyContext.study`.
"""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number
from designkit.display.section import ReportSection
from designkit.studies.core.members import Plan, members, with_traits
from designkit.studies.core.study import Entry, Study, StudyContext, StudyResult
from designkit.studies.lab3 import questions as q
from designkit.studies.lab3.measures import chattering
from designkit.studies.lab3.runs import corner_runs, corners, load_effect, oat_runs

__all__ = ["STUDY", "TITLE"]

TITLE = ("Lab experiment 3 (notes, appendix A): sliding-mode control of the elastic joint (ROBEL) against PID and the "
         "linear state regulator")


def _applies(result: Any, family: Any) -> bool:
    found = members(result)
    return (all(m.run.simulation is not None for m in found)
            and bool(with_traits(found, "switching", "state_feedback"))
            and bool(with_traits(found, "state_feedback", without=("switching",))))


def _run(ctx: StudyContext) -> StudyResult:
    result = ctx.result
    found = members(result)
    by_label = {m.label: m for m in found}
    switching = with_traits(found, "switching")
    linear = tuple(m for m in found if "switching" not in m.family.traits)
    eu, cu = result.table.error_unit, result.table.command_unit
    plan = Plan(ctx.new_budget())
    chat = {m.label: chattering(m.run.simulation) for m in found}
    oat = {m.label: oat_runs(m, plan) for m in found}
    effects = {m.label: load_effect(m, plan) for m in found}
    at = corners(result)
    box = {m.label: corner_runs(m, plan, at) for m in found} if at else {}
    unc = getattr(result.loaded.spec.plant, "uncertainty", None)
    box_words = (", ".join(f"{k} in [{fmt_number(lo, 4)}, {fmt_number(hi, 4)}]" for k, (lo, hi) in
                           unc.intervals.items()) if at else "")
    reduced = ""
    if plan.left:
        reduced = (f"{len(plan.left)} runs left out ({'; '.join(plan.left)}): the studies' budget of "
                   f"{fmt_number(ctx.budget, 3)} s fits about {plan.budget.runs} at "
                   f"{fmt_number(plan.budget.per_run, 2)} s each (raise studies.budget to run them)")
    if plan.budget.overrun:
        reduced = "; ".join(filter(None, (reduced, plan.budget.overrun_words())))
    questions = (
        q.why_question(switching, chat, cu),
        q.importance_question(oat, by_label, eu, cu),
        q.structure_question(found, switching),
        q.compare_question(switching, linear, chat, effects, result.table.winners(), eu),
        q.perturbation_question(effects, eu),
        q.response_question(found),
        q.level_question(found, chat, cu),
        q.robustness_question(found, box, box_words, eu, cu),
        q.reliability_question(switching, {m.label: ctx.study("rate", m.run) for m in switching}, eu, cu),
    )
    intro = ("The experiment's questions, answered from the controllers' own runs of the shared task and from runs of "
             "each with one thing changed (one of its settings, the load removed, a corner of the parameter box), "
             "each through its family's own run and judged by its own checks (numbers measured, not quoted)."
             + (f" Reduced: {reduced}." if reduced else ""))
    section = ReportSection("lab-3-comparison", TITLE, intro, questions)
    entries = (*(Entry(f"{label}: {knob.key}", knob.unit, tuple(sorted((d.row for d in done), key=lambda r: r.factor)))
                 for label, knobs in oat.items() for knob, done in knobs),
               *(Entry(f"{label}: without the load", "", (e.measured.row,)) for label, e in effects.items()
                 if e is not None),
               *(Entry(f"{label}: corners of the box", "", tuple(d.row for _, d in done)) for label, done in box.items()
                 if done))
    return StudyResult("lab3", TITLE, entries, section, (), reduced, plan.budget.runs, plan.budget.spent)


STUDY = Study(name="lab3", title=TITLE, order=51, applies=_applies, run=_run, comparison=True)
"""Lab experiment 3 (module docstring)."""
