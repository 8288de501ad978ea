"""Lab experiment 3's questions answered in words and tables, from the members' own runs and the runs
:mod:`~designkit.studies.lab3.runs` made.  Every number here is read from one of those runs, or predicted in closed
form by the member's family (``Family.predictions``) and set beside what was measured."""

from __future__ import annotations

import math
from typing import Any

from designkit.display.numbers import fmt_number
from designkit.display.section import Question, Table
from designkit.studies.core.members import Measured, Member, amount, status_words
from designkit.studies.core.metrics import values
from designkit.studies.lab3.measures import Chatter
from designkit.studies.lab3.runs import LoadEffect

__all__ = ["compare_question", "importance_question", "level_question", "perturbation_question", "reliability_question",
           "response_question", "robustness_question", "structure_question", "why_question"]


def _outcome(row: Any) -> str:
    return row.outcome if not row.detail else f"{row.outcome}: {row.detail}"


def _own_row(m: Member) -> Any:
    from designkit.studies.core.study import Row
    from designkit.studies.core.variants import outcome_of

    return Row(1.0, 1.0, {}, *outcome_of(m.run))


def why_question(switching: tuple[Member, ...], chat: dict[str, Chatter], cu: str) -> Question:
    """Each switching member's family's ``how`` answer, then with what success (the table) and its verdict."""
    sentences = []
    for m in switching:
        own = m.family.answer("how", m.run)
        if own:
            sentences.append(f"{m.label}: " + " ".join(own))
        c = chat[m.label]
        over, settle = amount(m.values.get("overshoot"), "%"), amount(m.values.get("settling_time"), "s")
        sentences.append(f"With what success: {m.label} overshoots by {over} and settles in {settle}, at the price of "
                         f"a command that reverses {amount(c.rate)} times per second and varies by "
                         f"{amount(c.variation, cu + '/s')}. {m.verdict}")
    return Question("Why, how and with what success a sliding-mode controller?", tuple(sentences))


def importance_question(runs: dict[str, list[tuple[Any, list[Measured]]]], by_label: dict[str, Member], eu: str,
                        cu: str) -> Question:
    """One parameter at a time (:func:`~designkit.studies.lab3.runs.oat_runs`): what the checks say and what moved."""
    rows, sentences = [], []

    def cells(label: str, what: str, outcome: str, v: Any) -> tuple[str, ...]:
        return (label, what, outcome, amount(v.get("overshoot"), "%"), amount(v.get("settling_time"), "s"),
                amount(v.get("steady_state_error"), eu), amount(v.get("command_peak"), cu),
                amount(v.get("command_variation"), cu + "/s"))

    for label, knobs in runs.items():
        m = by_label[label]
        base = values(m.run, tuple(_measures(m)))
        rows.append(cells(label, "as specified", _outcome(_own_row(m)), base))
        parts = []
        for knob, done in knobs:
            for d in done:
                v = d.metrics
                rows.append(cells(label, f"{knob.key} ×{fmt_number(d.row.factor, 3)}", _outcome(d.row), v))
                text = f"{knob.meaning} ×{fmt_number(d.row.factor, 3)}: the run {d.status}"
                if d.row.outcome in ("verified", "failed", "undecided"):
                    moved = [f"{what} {amount(base.get(key), u)} → {amount(v.get(key), u)}" for what, key, u in
                             (("settling", "settling_time", "s"), ("peak command", "command_peak", cu),
                              ("variation of u", "command_variation", cu + "/s"))]
                    text += f" ({', '.join(moved)})"
                parts.append(text)
        if parts:
            sentences.append(f"{label}: " + "; ".join(parts) + ".")
    table = Table("One setting changed at a time by its family's own factors (the first row of each controller: the "
                  "spec's design)", ("controller", "change", "checks", "overshoot", "settling", "final error",
                                     "peak |u|", "variation of u"), tuple(rows))
    intro = ("Each setting the controller's family declares it may vary (its knobs that are spec settings) was moved "
             "by the knob's own factors, everything else equal, and the controller run again through its own run and "
             "checks; the design gains are varied in each controller's own report.")
    return Question("What is the importance of each controller parameter?", (intro, *sentences), (table,))


def _measures(m: Member) -> tuple:
    from designkit.studies.lab3.measures import measures_of

    return measures_of(m.run, m.family)


def _states(design: Any) -> str:
    """The plant states the law reads, from its CasADi functions' dependence on the measured states (``y``)."""
    law = design.law
    names = [s.name for s in design.plant.states]
    used: set[int] = set()
    for f in (law.command, getattr(law, "derivative", None), getattr(law, "update", None)):
        if f is None or f.n_in() == 0 or f.name_in(0) != "y":
            continue
        sp = f.sparsity_jac(0, 0)
        cols = sp.colind()
        used |= {j for j in range(f.size1_in(0)) if cols[j + 1] > cols[j]}
    return ", ".join(names[j] for j in sorted(used) if j < len(names)) or "none of the states"


def structure_question(found: tuple[Member, ...], switching: tuple[Member, ...]) -> Question:
    """Each member's law and family's ``strategy`` answer, what it measures (its law's dependence), its controller
    states and how it is integrated (the law's declarations)."""
    sentences = []
    for m in found:
        d = m.run.design
        law = d.law
        integ = (f"held over steps of at most {amount(law.max_step, 's')} (a switching law)" if law.discontinuous else
                 f"sampled every {amount(law.sampling_period, 's')}" if law.sampling_period else
                 ("continuous, integrated with a step of at most " + amount(law.max_step, "s") if law.max_step else
                  "continuous"))
        own = m.family.answer("strategy", m.run) or ("; ".join(m.family.display.law_lines(d)) + ".",)
        n = len(law.state_names)
        sentences.append(f"{m.label} ({m.controller}): {own[0]} It measures {_states(d)}, has {n} controller "
                         f"state{'s' if n != 1 else ''} and is {integ}.")
        sentences.extend(own[1:])
    return Question("What is the basic structure, and which algorithms does each need?", tuple(sentences))


def compare_question(switching: tuple[Member, ...], others: tuple[Member, ...], chat: dict[str, Chatter],
                     effects: dict[str, LoadEffect | None], winners: tuple[Any, ...], eu: str) -> Question:
    """Each switching state feedback against each linear member, then the table's winners."""

    def ratio(x: float | None, y: float | None) -> str:
        return amount(x / y) if x is not None and y not in (None, 0) and math.isfinite(x / y) else "—"

    sentences = []
    for a in (m for m in switching if m.has("state_feedback")):
        for b in others:
            ea, eb = effects.get(a.label), effects.get(b.label)
            sa, sb = amount(a.values.get("settling_time"), "s"), amount(b.values.get("settling_time"), "s")
            peak = ratio(a.values.get("peak_command"), b.values.get("peak_command"))
            tv = ratio(chat[a.label].variation, chat[b.label].variation)
            la, lb = amount(ea.final if ea else None, eu, 4), amount(eb.final if eb else None, eu, 4)
            sentences.append(f"{a.label} against {b.label} ({b.controller}): settles in {sa} against {sb}, with {peak} "
                             f"times its peak command and {tv} times its command's variation per second; the load "
                             f"leaves {la} against {lb}.")
    keys = ("rms_error_before", "rise_time_before", "overshoot", "settling_time", "max_error_load", "peak_command",
            "rms_command", "rms_error_final")
    return Question("How does the sliding mode compare with the PID and the linear state regulator?",
                    (*sentences, "Metric by metric on the shared task (table above):",
                     *(w.sentence for w in winners if w.metric.key in keys)))


def perturbation_question(effects: dict[str, LoadEffect | None], eu: str) -> Question:
    """The load's effect: each run against its run without the load, beside the family's prediction."""
    rows, sentences = [], []
    for label, e in effects.items():
        if e is None:
            continue
        rows.append((label, amount(e.peak, eu, 4), amount(e.final, eu, 4), amount(e.predicted, eu, 4)))
        predicted = (f"its family predicts a static offset of {amount(e.predicted, eu, 4)}" if e.predicted is not None
                     else "its family predicts no static offset in closed form")
        sentences.append(f"{label}: the {amount(e.value, 'N*m')} load from {amount(e.onset, 's')} moves the controlled "
                         f"position by {amount(e.peak, eu, 4)} at most and leaves {amount(e.final, eu, 4)} at the end "
                         f"of the run; {predicted}. The run without the load {e.measured.status}.")
    table = Table("The load step's effect: |x − x0| against the same design's run without it",
                  ("controller", "largest", "left at the end", "predicted static offset"), tuple(rows))
    return Question("How sensitive is each to an external perturbation?", tuple(sentences), (table,) if rows else ())


def response_question(found: tuple[Member, ...]) -> Question:
    """The 90 % rise time and the settling time of the step (the members' own runs)."""
    from designkit.comparison.metrics import rise_times

    rows, sentences = [], []
    for m in found:
        edges = rise_times(m.run.simulation)
        rise = edges[0][1] if edges else None
        settle = m.values.get("settling_time")
        rows.append((m.label, amount(rise, "s"), amount(settle, "s")))
        sentences.append(f"{m.label}: 90 % of the step in {amount(rise, 's')}, settled (2 %) in {amount(settle, 's')}.")
    table = Table("Response time of the step", ("controller", "90 % rise time", "settling time"), tuple(rows))
    return Question("What is each controller's response time?", tuple(sentences), (table,))


def level_question(found: tuple[Member, ...], chat: dict[str, Chatter], cu: str) -> Question:
    """Peak and RMS command (the table's) and the command's chattering (measured here on the members' runs)."""
    return Question("What control level does each need, and how much does it chatter?", tuple(
        f"{m.label}: peak |u| {amount(m.values.get('peak_command'), cu)}, RMS {amount(m.values.get('rms_command'), cu)}"
        f"; the command reverses {chat[m.label].reversals} times ({amount(chat[m.label].rate)} per second) and varies "
        f"by {amount(chat[m.label].variation, cu + '/s')} (total variation {amount(chat[m.label].total_variation, cu)} "
        f"over the {amount(chat[m.label].duration, 's')} run)." for m in found))


def _span(values_: list[float | None], unit_text: str) -> str:
    finite = [v for v in values_ if v is not None and math.isfinite(v)]
    if not finite:
        return "undefined"
    return f"{amount(min(finite), unit_text)} to {amount(max(finite), unit_text)}" + (
        "" if len(finite) == len(values_) else f" ({len(values_) - len(finite)} undefined)")


def robustness_question(found: tuple[Member, ...], runs: dict[str, list[tuple[dict, Measured]]], box_words: str,
                        eu: str, cu: str) -> Question:
    """Each controller, designed for the nominal plant, at the corners of the box: what its checks say there, the
    spans of its step's numbers; and the required checks its stability rests on (their statuses)."""
    if not box_words:
        return Question("How robust is each to parameter changes (and how stable)?",
                        ("The spec gives no parameter box small enough to run at its corners.",))
    rows, sentences = [], [f"Each controller's law, designed for the nominal plant, was run on the true plant at every "
                           f"corner of the box ({box_words}), each corner starting at rest, through the family's own "
                           "run and checks."]
    for label, done in runs.items():
        if not done:
            continue
        kept = sum(d.row.outcome == "verified" for _, d in done)
        bounded = sum(d.row.outcome != "diverged" for _, d in done)
        metric = [d.metrics for _, d in done]
        worst_at, worst = max(done, key=lambda x: -1.0 if x[1].metrics.get("settling_time") is None
                              else x[1].metrics["settling_time"])
        at = ", ".join(f"{k} = {fmt_number(v, 4)}" for k, v in worst_at.items())
        failing = sorted({d.row.detail for _, d in done if d.row.outcome not in ("verified",) and d.row.detail})
        rows.append((label, f"{kept} of {len(done)}", f"{bounded} of {len(done)}",
                     _span([v.get("overshoot") for v in metric], "%"), _span([v.get("settling_time") for v in metric],
                                                                             "s"),
                     _span([v.get("steady_state_error") for v in metric], eu),
                     _span([v.get("command_peak") for v in metric], cu)))
        sentences.append(f"{label}: every required check passes at {kept} of the {len(done)} corners"
                         + (f" (elsewhere: {'; '.join(failing)})" if failing else "")
                         + f", the run is bounded at {bounded}; overshoot "
                           f"{_span([v.get('overshoot') for v in metric], '%')}, settling "
                           f"{_span([v.get('settling_time') for v in metric], 's')} (longest at {at}).")
    for m in found:
        from designkit.comparison.verdicts import check_lines

        lines = [c for c in check_lines(m.run.checks) if c.required]
        sentences.append(f"{m.label}'s own run is {status_words(tuple(check_lines(m.run.checks)))}; its stability "
                         "rests on its required checks: " + "; ".join(f"{c.label} ({c.status})" for c in lines) + ".")
    table = Table("The designed laws at the corners of the parameter box",
                  ("controller", "verified", "bounded", "overshoot", "settling time", "steady-state error", "peak |u|"),
                  tuple(rows))
    return Question("How robust is each to parameter changes (and how stable)?", tuple(sentences), (table,))


def _hz(rate: float) -> str:
    return f"{fmt_number(rate / 1000.0, 4)} kHz" if rate >= 1000.0 else f"{fmt_number(rate, 4)} Hz"


def _count(value: float | None) -> str:
    """A count per second, whole from 10 on."""
    if value is None or not math.isfinite(value):
        return "—"
    return f"{value:.0f}" if value >= 10 else fmt_number(value, 3)


def _from_to(rows: list[Any], key: str, unit_text: str) -> str:
    """``"a at R1 to b at R2"`` over ``rows`` (decreasing rate) with a finite value of ``key`` (a count per second
    when ``unit_text`` is ``"1/s"``)."""
    pts = [(float(r.value), r.metrics.get(key)) for r in rows]
    pts = [(f, v) for f, v in pts if v is not None and math.isfinite(v)]
    if not pts:
        return "undefined"

    def text(v: float) -> str:
        return _count(v) if unit_text == "1/s" else amount(v, unit_text)

    first, last = pts[0], pts[-1]
    if len(pts) == 1:
        return f"{text(first[1])} at {_hz(first[0])}"
    return f"{text(first[1])} at {_hz(first[0])} to {text(last[1])} at {_hz(last[0])}"


def reliability_question(switching: tuple[Member, ...], rates: dict[str, Any], eu: str, cu: str) -> Question:
    """Each switching member's rate study (its own, cited, not run again): the lowest sampling rate at which its
    verdict still holds, and its precision, chattering and effort across the rates."""
    intro = ("Reliability is read here as whether the verdict survives the command being computed as an "
             "implementation computes it: once a sampling period, held in between. Each switching controller's own "
             "rate study (in its own report) ran it at a ladder of sampling rates through its family's own run and "
             "checks; its rows are cited here.")
    sentences, lines = [intro], []
    for m in switching:
        study = rates.get(m.label)
        if study is None or not study.entries or not study.entries[0].rows:
            sentences.append(f"{m.label}: no rate was run (the rate study does not apply to its run).")
            continue
        entry = study.entries[0]
        rows = sorted(entry.rows, key=lambda r: -float(r.value))
        hold = entry.recommended
        count = f"{len(rows)} rate{'s' if len(rows) != 1 else ''}"
        if hold is None:
            verdict = (f"its verdict holds at none of the {count} run, from {_hz(rows[0].value)} down to "
                       f"{_hz(rows[-1].value)} (at {_hz(rows[0].value)}: {_outcome(rows[0])})")
        elif hold.value == float(rows[-1].value):
            verdict = (f"its verdict holds at every one of the {count} run, from {_hz(hold.high)} down to "
                       f"{_hz(hold.value)}")
        else:
            below = next(r for r in rows if float(r.value) < hold.value)
            verdict = (f"the lowest rate at which its verdict still holds is {_hz(hold.value)} (every rate from "
                       f"{_hz(hold.high)} down to it passes); at {_hz(below.value)}: {_outcome(below)}")
        diverged = [_hz(r.value) for r in rows if r.outcome == "diverged"]
        sentences.append(
            f"{m.label} ({m.controller}): {verdict}. From the highest rate to the lowest: its steady error (largest "
            f"|x − xD| over the last tenth of the reference's last plateau) {_from_to(rows, 'steady_error', eu)}, the "
            f"RMS of its command's switching component {_from_to(rows, 'chatter_rms', cu)}, its reversals per second "
            f"{_from_to(rows, 'reversal_rate', '1/s')}, its RMS command {_from_to(rows, 'command_rms', cu)}; "
            + (f"it diverges at {', '.join(diverged)}." if diverged else "no run diverges.")
            + (f" Its rate study was reduced: {study.reduced}." if study.reduced else ""))
        for r in rows:
            v = r.metrics
            lines.append((m.label, _hz(r.value), _outcome(r), amount(v.get("steady_error"), eu, 3),
                          amount(v.get("chatter_rms"), cu), _count(v.get("reversal_rate")),
                          amount(v.get("command_rms"), cu)))
    table = Table("Each switching controller at each sampling rate (its rate study's rows)",
                  ("controller", "rate", "checks", "steady error", "switching RMS", "reversals (1/s)", "RMS command"),
                  tuple(lines))
    return Question("How reliable is each switching controller when its command is sampled?", tuple(sentences),
                    (table,) if lines else ())
