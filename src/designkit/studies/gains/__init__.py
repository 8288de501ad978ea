"""The gain study: each knob of the family moved by a few factors, everything else equal, through the family's
own run.

For every knob the family declares (or those the spec's ``studies.gains.knobs`` names), the value in use is
multiplied by each factor (the knob's own, default halved and doubled; ``studies.gains.factors``), and the
spec runs again through the family's own run -- the trials of a learning law, the adaptation of an adaptive law,
the held step of a switching law -- with every check the family offers.  Each row says what the variant came to
(every required check passed, which failed, whether it diverged) and the family's metrics on it; the sentences
compare them with the spec's own run.  A variant outside the knob's declared range is not run, and said so.

The study fits its budget (:mod:`designkit.studies.core.budget`): when every knob at every factor would not fit,
it keeps the knobs in the family's order (most telling first) and says which it left out; when not even one knob
fits at its factors it runs the first knob at its first factor only.  It is never skipped.
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import Field, field_validator

from designkit.display.numbers import fmt_number, unit
from designkit.display.section import Question, ReportSection, Table
from designkit.spec.fields import Section
from designkit.spec.ranges import Ranged
from designkit.studies.core.metrics import metrics_of
from designkit.studies.core.study import Entry, Row, Study, StudyContext, StudyResult
from designkit.studies.core.variants import nominal_row, run_variant
from designkit.studies.core.words import change, factor_verb, outcome_words, value_text

__all__ = ["STUDY", "GainsSettings"]


class GainsSettings(Section):
    """``studies.gains``: the knobs to vary (``knobs``, names the family declares; default all of them) and the
    factors (``factors``, 1e-6 to 1e6, other than 1; default each knob's own)."""

    knobs: list[str] | None = Field(default=None, min_length=1, max_length=20)
    factors: list[Ranged(1e-6, 1e6, "")] | None = Field(default=None, min_length=1, max_length=8)

    @field_validator("factors")
    @classmethod
    def _not_one(cls, v: list[float] | None) -> list[float] | None:
        if v is not None:
            for i, f in enumerate(v):
                if f == 1:
                    raise ValueError(f"[{i}]: a factor of 1 is the spec's own run; give factors other than 1")
        return v


def _validate(settings: GainsSettings, family: Any, spec: Any) -> None:
    from designkit.runner.variants import spec_value

    names = [k.key for k in family.knobs]
    for i, name in enumerate(settings.knobs or ()):
        if family.knob(name) is None:
            raise ValueError(f"knobs[{i}]: the {family.kind} family has no knob {name!r}; its knobs are "
                             f"{', '.join(names) or 'none'}")
    for knob in [family.knob(n) for n in settings.knobs] if settings.knobs else family.knobs:
        for i, f in enumerate(settings.factors or ()):
            if knob.gain:
                value, what = f, f"×{f:g}"
            else:
                current = spec_value(spec, knob.path)
                if current is None or isinstance(current, list | tuple):
                    continue  # computed by the family (or per joint): judged when the study runs
                value, what = knob.scaled(float(current), f), f"×{f:g} takes {knob.key} to {knob.scaled(current, f):g}"
            if not knob.inside(value):
                raise ValueError(f"factors[{i}]: {what}, outside the range the family declares for {knob.key} "
                                 f"([{knob.low:g}, {knob.high:g}]{' as factors' if knob.gain else ''})")


def _applies(result: Any, family: Any) -> bool:
    return result.simulation is not None and any(k.applies(result.design) for k in family.knobs)


def _plan(ctx: StudyContext) -> list[tuple[Any, list[float]]]:
    """The knobs and factors asked for (the spec's ``studies.gains``, else every knob at its own factors)."""
    fam, settings = ctx.family, ctx.settings
    knobs = [fam.knob(n) for n in settings.knobs] if settings is not None and settings.knobs else list(fam.knobs)
    knobs = [k for k in knobs if k.applies(ctx.result.design)]
    return [(k, list(settings.factors) if settings is not None and settings.factors else list(k.factors))
            for k in knobs]


def _in_range(knob: Any, current: Any, factor: float) -> bool:
    if knob.gain:
        return knob.inside(factor)
    import numpy as np

    value = np.atleast_1d(knob.scaled(np.asarray(current, dtype=float), factor))
    return all(knob.inside(float(v)) for v in value)


def _sentences(knob: Any, rows: tuple[Row, ...], nominal: Row, metric: Any) -> tuple[str, ...]:
    out = []
    for r in rows:
        if r.factor == 1.0:
            continue
        text = f"{factor_verb(r.factor).capitalize()} {knob.key} (to {value_text(r.value, knob.unit, 3)}): " \
               f"{outcome_words(r.outcome, r.detail)}"
        if r.outcome in ("verified", "failed", "undecided", "diverged") and metric is not None:
            moved = change(nominal.metrics.get(metric.key), r.metrics.get(metric.key), metric.unit)
            text += f"; {metric.label} {moved}"
        out.append(text + ".")
    return tuple(out)


def _sensitivity(rows: tuple[Row, ...], nominal: Row, metric: Any) -> float | None:
    """Largest |ln ratio| of the primary metric over a knob's rows (inf when a variant stops passing)."""
    if metric is None:
        return None
    base = nominal.metrics.get(metric.key)
    worst = 0.0
    for r in rows:
        if r.factor == 1.0:
            continue
        if nominal.passed and not r.passed:
            return math.inf
        v = r.metrics.get(metric.key)
        if base is None or v is None or base <= 0 or v <= 0 or not math.isfinite(base):
            continue
        worst = max(worst, abs(math.log(v / base)) if math.isfinite(v) else math.inf)
    return worst


def _run(ctx: StudyContext) -> StudyResult:
    from designkit.runner.variants import knob_value

    result, fam = ctx.result, ctx.family
    spec = result.loaded.spec
    metrics = metrics_of(result, fam)
    primary = metrics[0] if metrics else None
    budget = ctx.new_budget()
    plan = _plan(ctx)
    # Fit the budget: whole knobs in the family's order, else the first knob's first factor.
    runnable, unset = [], []
    for knob, factors in plan:
        current = knob_value(knob, spec, result.design)
        if current is None:
            unset.append(knob.key)
            continue
        runnable.append((knob, current, [f for f in factors if _in_range(knob, current, f)], factors))
    kept, left_out, planned = [], [], 0
    for knob, current, factors, asked in runnable:
        if factors and planned + len(factors) <= budget.capacity():
            kept.append((knob, current, factors, asked))
            planned += len(factors)
        elif factors:
            left_out.append(knob.key)
        else:
            kept.append((knob, current, factors, asked))  # every factor outside the declared range: said so
    notes = []
    if not planned and any(f for *_, f, _ in runnable):  # not even one knob fits: its first factor, never none
        knob, current, factors, asked = next(x for x in runnable if x[2])
        kept = [(knob, current, factors[:1], asked)]
        notes.append(f"one variant is estimated at {fmt_number(budget.per_run, 2)} s, more than the studies' budget "
                     f"of {fmt_number(ctx.budget, 3)} s allows for every factor: only {knob.key} at its first factor "
                     "was run (raise studies.budget to run more)")
    elif left_out:
        notes.append(f"{', '.join(left_out)} not varied: their variants would exceed the studies' budget of "
                     f"{fmt_number(ctx.budget, 3)} s at about {fmt_number(budget.per_run, 2)} s each (raise "
                     "studies.budget to vary them)")
    reduced = "; ".join(notes)
    entries, questions = [], []
    sensitivities = []
    # every planned variant is independent: one batch (on two cores when asked), rows in the plan's order
    tasks = [(knob, f, (lambda k=knob, c=current, f=f: run_variant(result, k, k.scaled(c, f), f, metrics)))
             for knob, current, factors, _ in kept for f in factors]
    ran = dict(zip([(k.key, f) for k, f, _ in tasks], ctx.run_all([t for *_, t in tasks], budget), strict=True))
    for knob, current, factors, asked in kept:
        nominal = nominal_row(result, current, metrics)
        rows = [nominal, *(ran[(knob.key, f)] for f in factors)]
        outside = [f for f in asked if not _in_range(knob, current, f)]
        if len(rows) == 1 and not outside:
            continue
        rows_t = tuple(sorted(rows, key=lambda r: r.factor))
        entries.append(Entry(knob.key, knob.unit, rows_t))
        sentences = list(_sentences(knob, rows_t, nominal, primary))
        if outside and current is not None:
            sentences.append(f"{', '.join('×' + fmt_number(f, 3) for f in outside)} would take {knob.key} outside "
                             f"the range the family declares ([{fmt_number(knob.low, 3)}, {fmt_number(knob.high, 3)}]"
                             f"{' times the design value' if knob.gain else ' ' + unit(knob.unit)}): not run.")
        s = _sensitivity(rows_t, nominal, primary)
        if s is not None:
            sensitivities.append((s, knob.key))
        header = ("Factor", knob.key + (f" ({unit(knob.unit)})" if knob.unit else ""), "Outcome",
                  *(m.label + (f" ({unit(m.unit)})" if m.unit else "") for m in metrics))
        table_rows = tuple((("× 1 (the spec's run)" if r.factor == 1.0 else f"× {fmt_number(r.factor, 3)}"),
                            value_text(r.value, "", 4), r.outcome if not r.detail else f"{r.outcome}: {r.detail}",
                            *(fmt_number(r.metrics.get(m.key), 4) for m in metrics)) for r in rows_t)
        questions.append(Question(f"{knob.key}, {knob.meaning}: what does it do?", tuple(sentences),
                                  (Table(f"{knob.key} scaled, everything else equal, each variant run through the "
                                         "family's own run and checks", header, table_rows),)))
    summary = []
    ranked = sorted((s for s in sensitivities if s[0] is not None), reverse=True)
    if primary is not None and len(ranked) > 1 and ranked[0][0] > 0:
        top = ranked[0]
        if math.isinf(top[0]):
            breaking = [k for s, k in ranked if math.isinf(s)]
            summary.append(f"Moving {', '.join(breaking)} by the factors studied makes a required check fail that "
                           "passes in the spec's run.")
        finite = [(s, k) for s, k in ranked if math.isfinite(s)]
        if finite and finite[0][0] > 0:
            summary.append(f"Among the knobs whose variants keep every required check as in the spec's run, the "
                           f"{primary.label} is most sensitive to {finite[0][1]}"
                           + (f" and least to {finite[-1][1]}" if len(finite) > 1 else "") + ".")
    locus_sentences, figures = _locus(ctx, [k for k, *_ in kept if k.gain])
    if unset:
        questions.append(Question("Which knobs were not varied?", (
            f"{', '.join(unset)}: not set in the spec and not computed by this design, so there is no value to "
            "scale.",)))
    if locus_sentences:
        questions.append(Question("How do the closed-loop poles move between those factors?", locus_sentences))
    intro = ("Each knob the family declares moved by the factors shown, everything else equal; every variant is run "
             "through the family's own run (its trials, its adaptation, its held step) and judged by the same "
             "checks as the spec's run." + (f" Reduced: {reduced}." if reduced else ""))
    section = ReportSection("study-gains", "Gain study", intro,
                            (Question("Which knob matters most?", tuple(summary)),) + tuple(questions)
                            if summary else tuple(questions))
    return StudyResult("gains", "Gain study", tuple(entries), section, figures, reduced, budget.runs, budget.spent)


def _locus(ctx: StudyContext, knobs: list[Any]) -> tuple[tuple[str, ...], tuple[Any, ...]]:
    """The root locus of the design gains varied (:mod:`~designkit.studies.gains.locus`), in words and drawn."""
    if not knobs:
        return (), ()
    from designkit.studies.gains.locus import POINTS, root_locus
    from designkit.studies.gains.locus_figure import TITLE, root_locus_figure

    rl = root_locus(ctx.result, [k.gain for k in knobs])
    if rl is None:
        return (), ()
    figure = root_locus_figure(ctx.result, rl)
    if figure is None:
        return (), ()
    return (f"The root locus (figure {TITLE}) follows the closed-loop poles of the loop linearized at the design's "
            f"operating point over {POINTS} log-spaced factors from × 0.5 to × 2 of each gain:", *rl.sentences), \
        (figure,)


STUDY = Study(name="gains", title="Gain study", order=20, applies=_applies, run=_run, settings=GainsSettings,
              validate=_validate)
"""The gain study (module docstring)."""
