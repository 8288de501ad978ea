"""Lab experiment 2's questions answered in words and tables, from the members' own runs and the runs
:mod:`~designkit.studies.lab2.runs` made.  Every number here is read from one of those runs."""

from __future__ import annotations

import math
from typing import Any

from designkit.display.numbers import unit
from designkit.display.section import Question, Table
from designkit.studies.core.members import Measured, Member, amount
from designkit.studies.core.metrics import values
from designkit.studies.core.words import change
from designkit.studies.lab2.runs import Perturbed

__all__ = ["SCHEMES", "adaptation_question", "difference_question", "level_question", "modifications_question",
           "perturbation_question", "response_question", "robustness_question", "strategies_question",
           "why_question"]

SCHEMES = {
    "model_reference": "a direct scheme: it adjusts its controller's gains from the output error against a reference "
                       "model, without estimating the plant",
    "certainty_equivalence": "an indirect scheme: it estimates the plant's parameters and recomputes its controller "
                             "from the estimates",
}
"""What each adaptive trait says of the scheme (:attr:`designkit.synthesis.family.Family.traits`)."""


def _departure(m: Member, values: Any, eu: str) -> str:
    return (f"departure from its run on the unchanged plant {amount(values.get('rms_deviation'), eu)} RMS "
            f"({amount(values.get('max_deviation'), eu)} at most), back within 1 % of the reference's range "
            f"{amount(values.get('reconvergence'), 's')} after the change")


def why_question(adaptive: tuple[Member, ...], eu: str) -> Question:
    """Why each adapts (its family's ``how`` answer), with what success (the table's departure) and its verdict."""
    sentences = []
    for m in adaptive:
        own = m.family.answer("how", m.run)
        if own:
            sentences.append(f"{m.label}: " + " ".join(own))
        sentences.append(f"With what success: {m.label}'s {_departure(m, m.values, eu)}. {m.verdict}")
    return Question("Why does each controller adapt, and with what success?", tuple(sentences))


def difference_question(adaptive: tuple[Member, ...], winners: tuple[Any, ...]) -> Question:
    """The schemes (from the families' traits) and the timing (the law's sampling period), then the table's winners."""
    parts = []
    for m in adaptive:
        scheme = next((words for trait, words in SCHEMES.items() if trait in m.family.traits), "an adaptive scheme")
        ts = m.run.design.law.sampling_period
        timing = f"sampled every {amount(ts, 's')}" if ts else "in continuous time"
        parts.append(f"{m.label} ({m.controller}) is {scheme}, {timing}")
    words = "The difference is one of structure: " + "; ".join(parts) + ". On the shared task:"
    return Question("What is the comparative difference?", (words, *(w.sentence for w in winners)))


def _own_row(m: Member) -> Any:
    from designkit.studies.core.study import Row
    from designkit.studies.core.variants import outcome_of

    return Row(1.0, 1.0, {}, *outcome_of(m.run))


def _cells(done: Measured, eu: str, cu: str) -> tuple[str, ...]:
    v = done.metrics
    return (done.row.outcome if not done.row.detail else f"{done.row.outcome}: {done.row.detail}",
            amount(v.get("rms_deviation"), eu), amount(v.get("reconvergence"), "s"), amount(v.get("peak_command"), cu))


def adaptation_question(runs: dict[str, list[tuple[Any, list[Measured]]]], by_label: dict[str, Member], eu: str,
                        cu: str) -> Question:
    """Each adaptation parameter moved (:func:`~designkit.studies.lab2.runs.adaptation_runs`): re-convergence,
    departure, peak command and what the checks say."""
    from designkit.runner.variants import knob_value

    rows, sentences = [], []
    for label, knobs in runs.items():
        m = by_label[label]
        for knob, done in knobs:
            current = knob_value(knob, m.run.loaded.spec, m.run.design)
            shown = amount(float(current) if not hasattr(current, "__len__") else float(current[0]), "", 4)
            rows.append((label, knob.meaning, shown, _outcome(_own_row(m)),
                         amount(m.values.get("rms_deviation"), eu), amount(m.values.get("reconvergence"), "s"),
                         amount(m.values.get("peak_command"), cu)))
            for d in done:
                rows.append((label, knob.meaning, amount(float(d.row.value if not isinstance(d.row.value, tuple)
                                                               else d.row.value[0]), "", 4), *_cells(d, eu, cu)))
            tried = [(shown, m.values, "its own run")] + [
                (amount(float(d.row.value if not isinstance(d.row.value, tuple) else d.row.value[0]), "", 4),
                 d.metrics, d.status) for d in done]
            timed = [t for t in tried if t[1].get("reconvergence") is not None]
            text = f"{label}, {knob.meaning} ({knob.key}): "
            if timed:
                best = min(timed, key=lambda t: t[1]["reconvergence"])
                text += (f"of the values tried, {best[0]} re-converges fastest ({amount(best[1]['reconvergence'], 's')}"
                         f" after the change, departure {amount(best[1].get('rms_deviation'), eu)} RMS). ")
            text += " ".join(f"{knob.key} = {v}: re-converged {amount(x.get('reconvergence'), 's')} after the change, "
                             f"departure {amount(x.get('rms_deviation'), eu)} RMS, peak command "
                             f"{amount(x.get('peak_command'), cu)}; the run {status}." for v, x, status in tried[1:])
            sentences.append(text)
    table = Table("Each controller with one adaptation parameter changed (the first row of each: the spec's value)",
                  ("controller", "parameter", "value", "checks", "RMS departure", "re-convergence", "peak command"),
                  tuple(rows))
    intro = ("Each adaptation parameter the controller's family declares was moved (an adaptation gain divided and "
             "multiplied by 10, a forgetting factor's memory 1 − λ multiplied by 5 and divided by 10) and the "
             "controller run again on the same task through its own run and checks; departure and re-convergence are "
             "measured as in the table, against that variant's own run on the unchanged plant.")
    return Question("What is the influence of the adaptation parameters?", (intro, *sentences),
                    (table,) if rows else ())


def strategies_question(found: tuple[Member, ...]) -> Question:
    """Each member's family's ``strategy`` answer."""
    sentences = []
    for m in found:
        own = m.family.answer("strategy", m.run)
        law = "; ".join(m.family.display.law_lines(m.run.design))
        sentences.append(f"{m.label} ({m.controller}): " + (" ".join(own) if own else law))
    return Question("What are the control strategies?", tuple(sentences))


def _metric_cells(metrics: tuple, values: Any) -> tuple[str, ...]:
    return tuple(amount(values.get(mt.key), "", 4) for mt in metrics)  # the unit is in the column's header


def _outcome(row: Any) -> str:
    return row.outcome if not row.detail else f"{row.outcome}: {row.detail}"


def _required(m: Member, through: list[tuple[Any, Measured]], plain: Measured | None, larger_words: str) -> str:
    """What the runs say is required of ``m``: nothing where its own run passes, else the modifications that pass
    where it does not."""
    own = _own_row(m)
    text = (f"On the shared task {m.label} needs none: its own run is {own.outcome}." if own.outcome == "verified" else
            f"On the shared task {m.label}'s own run is {own.outcome} ({own.detail}).")
    if plain is None or not through:
        return text
    kept = [variant.label for variant, d in through if d.row.outcome == "verified"]
    if plain.row.outcome == "verified":
        return text + f" Through the larger change ({larger_words}) it needs none either: it is verified there as is."
    fate = {"diverged": "diverges", "failed": "is not verified", "undecided": "is undecided",
            "refused": "is refused"}.get(plain.row.outcome, "could not be run")
    return text + (f" Through the larger change ({larger_words}) it {fate} as is, and "
                   + (f"the {', the '.join(kept)} keep{'s' if len(kept) == 1 else ''} every required check there: "
                      f"{'that is' if len(kept) == 1 else 'those are'} the modification{'s' if len(kept) > 1 else ''} "
                      "it requires." if kept else "no modification run here keeps every required check there."))


def modifications_question(adaptive: tuple[Member, ...], scenario: dict[str, list[tuple[Any, Measured]]],
                           larger: dict[str, list[tuple[Any, Measured]]], plain: dict[str, Measured],
                           larger_words: str) -> Question:
    """Each modification run on the comparison's scenario and through the larger change: what its checks say,
    what it does to the family's metrics (the error against a reference model, the parameters' drift) and to the
    re-convergence, and which the runs show to be required."""
    sentences, tables = [], []
    for m in adaptive:
        runs = scenario.get(m.label, [])
        if not runs:
            continue
        metrics = tuple(m.family.metrics)
        head = ("variant", "checks", *(mt.label + (f" ({unit(mt.unit)})" if mt.unit else "") for mt in metrics),
                "re-convergence (s)")
        own = values(m.run, metrics)
        rows = [("the spec's own", _outcome(_own_row(m)), *_metric_cells(metrics, own),
                 amount(m.values.get("reconvergence"), ""))]
        for variant, d in runs:
            rows.append((variant.label, _outcome(d.row), *_metric_cells(metrics, d.metrics),
                         amount(d.metrics.get("reconvergence"), "")))
            moved = "; ".join(f"{mt.label} {change(own.get(mt.key), d.metrics.get(mt.key), mt.unit)}"
                              for mt in metrics)
            sentences.append(f"{m.label} with the {variant.label} ({variant.meaning}) {d.status}. Against its own "
                             "run: " + (f"{moved}; " if moved else "")
                             + f"re-converged {amount(d.metrics.get('reconvergence'), 's')} after the change (its own "
                               f"run: {amount(m.values.get('reconvergence'), 's')}).")
        tables.append(Table(f"{m.label} with each modification on the shared task", tuple(head), tuple(rows)))
        through = larger.get(m.label, [])
        if through:
            base = plain.get(m.label)
            trows = [("none", _outcome(base.row), *_metric_cells(metrics, base.metrics),
                      amount(base.metrics.get("reconvergence"), ""))] if base is not None else []
            for variant, d in through:
                trows.append((variant.label, _outcome(d.row), *_metric_cells(metrics, d.metrics),
                              amount(d.metrics.get("reconvergence"), "")))
                sentences.append(f"Through the larger change, {m.label} with the {variant.label} {d.status}"
                                 + (f"; it re-converged {amount(d.metrics.get('reconvergence'), 's')} after the change."
                                    if d.row.outcome != "diverged" else "."))
            tables.append(Table(f"{m.label} with each modification through the larger change ({larger_words})",
                                tuple(head), tuple(trows)))
        sentences.append(_required(m, through, plain.get(m.label), larger_words))
    if not sentences:
        sentences.append("No family of these controllers declares a modification that applies to its run.")
    intro = ("Each modification the controller's family declares (its meaning in parentheses) was run on the same "
             "task, and through the larger change of the robustness question, through the family's own run and checks; "
             "the numbers are the family's own metrics on that run.")
    return Question("What ad hoc modifications of the off-the-shelf algorithms might be required?",
                    (intro, *sentences), tuple(tables))


def perturbation_question(runs: list[Perturbed], value: float, onset: float, eu: str, cu: str) -> Question:
    """The perturbation step's effect on each, against its own run."""
    if not runs:
        return Question("How sensitive is each to an external perturbation?", ("No perturbation run was made.",))
    finite = [p for p in runs if math.isfinite(p.peak)]
    words = (f"Each controller was run again with an input-equivalent perturbation step of {amount(value, cu)} (a "
             f"tenth of the smaller peak command) from {amount(onset, 's')} on, after the plant change, and compared "
             "with its own run without it.")
    if len(finite) > 1:
        best, worst = min(finite, key=lambda p: p.peak), max(finite, key=lambda p: p.peak)
        words += (f" {best.measured.label} is the less sensitive: it moves by {amount(best.peak, eu)} at most against "
                  f"{amount(worst.peak, eu)} for {worst.measured.label}.")
    sentences = [words] + [f"{p.measured.label}: over the last period the perturbation leaves {amount(p.final, eu)}; "
                           f"the perturbed run {p.measured.status}." for p in runs]
    rows = tuple((p.measured.label, amount(p.rms, eu), amount(p.peak, eu), amount(p.recovery, "s"),
                  amount(p.final, eu), p.measured.row.outcome) for p in runs)
    table = Table("Departure |x − x0| from the unperturbed run after the perturbation step",
                  ("controller", "RMS", "largest", "back within 1 % after", "left over the last period", "checks"),
                  rows)
    return Question("How sensitive is each to an external perturbation?", tuple(sentences), (table,))


def response_question(found: tuple[Member, ...], change_time: float) -> Question:
    """The 90 % rise time of the reference's steps before and after the change (the members' own runs)."""
    from designkit.comparison.metrics import rise_times

    rows, sentences = [], []
    for m in found:
        edges = rise_times(m.run.simulation)
        before = [r for e, r in edges if e < change_time]
        after = [r for e, r in edges if e >= change_time]
        b, a = (before[-1] if before else None), (after[-1] if after else None)
        first = after[0] if after else None
        rows.append((m.label, amount(b, "s"), amount(first, "s"), amount(a, "s"), amount(m.values.get("reconvergence"),
                                                                                          "s")))
        sentences.append(f"{m.label}: 90 % of a reference step is reached in {amount(b, 's')} on the last step before "
                         f"the change, {amount(first, 's')} on the first after it and {amount(a, 's')} on the last of "
                         "the run.")
    table = Table("Rise time to 90 % of each reference step",
                  ("controller", "last before the change", "first after", "last of the run", "re-convergence"),
                  tuple(rows))
    return Question("What is each controller's response time?", tuple(sentences), (table,))


def level_question(found: tuple[Member, ...], cu: str) -> Question:
    """Peak and RMS command (the table's)."""
    return Question("What control level does each need?", tuple(
        f"{m.label}: peak |u| {amount(m.values.get('peak_command'), cu)} "
        f"({amount(m.values.get('peak_command_after'), cu)} after the change), RMS "
        f"{amount(m.values.get('rms_command'), cu)}." for m in found))


def robustness_question(runs: list[Measured], larger_words: str, eu: str) -> Question:
    """Each controller through the larger change: what its checks say, its departure and re-convergence."""
    if not runs:
        return Question("How robust is each?", ("No larger change was run (the spec has no plant change to enlarge, "
                                                "or the budget left it out).",))
    sentences = [f"Each controller was run again with a larger change: {larger_words} (the time constant too grows, "
                 "as in the SELFTUNE example)."]
    rows = []
    for d in runs:
        bounded = d.row.outcome != "diverged"
        rows.append((d.label, d.row.outcome if not d.row.detail else f"{d.row.outcome}: {d.row.detail}",
                     amount(d.metrics.get("rms_deviation"), eu), amount(d.metrics.get("reconvergence"), "s"),
                     "yes" if bounded else "no"))
        sentences.append(f"{d.label} {d.status}" + (f"; departure {amount(d.metrics.get('rms_deviation'), eu)} RMS, "
                                                     f"re-converged {amount(d.metrics.get('reconvergence'), 's')} "
                                                     "after the change." if bounded else "."))
    table = Table("Each controller through the larger change",
                  ("controller", "checks", "RMS departure", "re-convergence", "bounded"), tuple(rows))
    return Question("How robust is each?", tuple(sentences), (table,))
