"""The rate study: a switching law run with its command computed at a ladder of sampling rates, and what each rate
leaves of the verdict, the precision and the chattering.

A switching law designed in continuous time switches as fast as its simulation lets it (once an integration step);
a controller computes it once a sampling period and holds it.  For a family declaring the trait ``switching``
(:attr:`designkit.synthesis.family.Family.traits`), the study runs the spec through the family's own run
(:func:`designkit.runner.variants.vary_spec`: its design, its simulation, every check it offers) with the command
sampled at each rate of a ladder (:func:`~designkit.studies.rate.ladder.default_rates`, or the spec's
``studies.rate.rates``), the key and the integration step chosen by :mod:`~designkit.studies.rate.ladder`.  Each
run is a row: its verdict (the outcome of its required checks), its steady error, the switching component of its
command, its reversal rate, its control effort and whether it diverged (:mod:`~designkit.studies.rate.measure`).
The study states the lowest rate at which the verdict still holds (every rate from the highest down to it passing:
:attr:`~designkit.studies.core.study.Entry.recommended`), and says only what the runs showed: no trend is assumed.

The rates are run ends first, then the middle (so a ladder cut by the budget still spans it); each rung's cost is
estimated from its own spec (:func:`rung_cost`: the variant's estimate, its simulations at a step no longer than
the sampling period), and a rung that does not fit the study's budget is left out and named.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from pydantic import Field

from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection
from designkit.spec.fields import PositiveFinite, Section
from designkit.spec.ranges import Ranged
from designkit.studies.core.members import amount
from designkit.studies.core.study import Entry, Row, Study, StudyContext, StudyResult
from designkit.studies.rate.ladder import default_rates, divides, own_rate, rung_changes, sampling_key
from designkit.studies.rate.words import holding, rate_text, row_sentences, summary, table

__all__ = ["MAX_RATES", "STUDY", "TITLE", "RateSettings", "rung_cost"]

TITLE = "Sampling rate of the switching law"
MAX_RATES = 12
"""Most rates a ladder may list."""


class RateSettings(Section):
    """``studies.rate``: the sampling rates to run (``rates``, Hz, 1e-3 to 1e6, distinct; default
    :func:`~designkit.studies.rate.ladder.default_rates`)."""

    rates: list[Ranged(1e-3, 1e6, "Hz", base=PositiveFinite)] | None = Field(default=None, min_length=1,
                                                                             max_length=MAX_RATES)


def _duration(spec: Any) -> tuple[float, str]:
    """The run's duration (s) and where it comes from: ``simulation.duration``, else the default rule estimated from
    the spec (:func:`designkit.schema.budget.steps_of`)."""
    if spec.simulation.duration is not None:
        return float(spec.simulation.duration), "simulation.duration"
    from designkit.schema.budget import steps_of

    return steps_of(spec).duration, "the run's default duration"


def _validate(settings: RateSettings, family: Any, spec: Any) -> None:
    """Each rate given once, its period shorter than the run (a family that does not switch takes the settings and
    is not studied: a comparison gives one ``studies`` section to all its controllers)."""
    if not settings.rates:
        return
    duration, source = _duration(spec)
    for i, r in enumerate(settings.rates):
        if any(abs(r - s) <= 1e-12 * r for s in settings.rates[:i]):
            raise ValueError(f"rates[{i}]: {r:g} Hz is listed twice")
        if 1.0 / r >= duration:
            raise ValueError(f"rates[{i}]: {r:g} Hz samples every {1.0 / r:.4g} s, not shorter than the run "
                             f"({source}: {duration:.4g} s); give a rate above {1.0 / duration:.4g} Hz")


def _applies(result: Any, family: Any) -> bool:
    return (family is not None and "switching" in family.traits and result.simulation is not None
            and getattr(result, "trials", None) is None)


def _coarse_first(n: int) -> list[int]:
    """Indices ``0 .. n-1``: the ends first, then the middles of the gaps, coarsest first."""
    order, seen, gaps = [], set(), [(0, n - 1)]
    for i in (0, n - 1):
        if 0 <= i < n and i not in seen:
            order.append(i)
            seen.add(i)
    while gaps:
        nxt = []
        for a, b in gaps:
            if b - a > 1:
                m = (a + b) // 2
                if m not in seen:
                    order.append(m)
                    seen.add(m)
                nxt += [(a, m), (m, b)]
        gaps = nxt
    return order


def _row(result: Any, rung: Any, factor: float) -> Row:
    """The rung run through the family's own run and measured (never raises for what the run does)."""
    import numpy as np

    from designkit.runner.variants import vary_spec
    from designkit.studies.core.variants import run_row
    from designkit.studies.rate.measure import measure_run

    made: dict[str, Any] = {}

    def make() -> Any:
        run = vary_spec(result, rung.changes)
        with np.errstate(all="ignore"):
            made["metrics"] = measure_run(run) if run.simulation is not None else {}
        return run

    row = run_row(make, factor, rung.rate, ())
    return dataclasses.replace(row, metrics=made.get("metrics", {}))


def rung_cost(spec: Any, base_dir: Any, period: float) -> float:
    """Seconds a rung is estimated to cost: the variant's estimate (:func:`~designkit.studies.core.budget.
    variant_estimate`), its simulations scaled up by ``dt / period`` when the sampling ``period`` (s) is shorter than
    the step the estimate assumes (``dt``, :func:`designkit.schema.budget.steps_of`): the simulator's step divides the
    period, so it is at most the period."""
    from designkit.schema.budget import estimate, steps_of
    from designkit.studies.core.budget import variant_estimate

    one = variant_estimate(spec, base_dir)
    dt = steps_of(spec).dt
    if period < dt:
        sims = sum(t.seconds for t in estimate(spec, base_dir).terms if t.what == "simulations")
        one += sims * (dt / period - 1.0)
    return one


def _plan(ctx: StudyContext, rungs: list[Any]) -> tuple[list[Any], list[Any], Any]:
    """The rungs the budget fits (ends and middles first), the ones it leaves out, and the budget."""
    from designkit.errors import DesignkitError
    from designkit.runner.run import base_dir
    from designkit.runner.variants import changed_spec
    from designkit.studies.core.budget import VARIANT_FLOOR, Budget

    loaded = ctx.result.loaded
    costs = []
    for rung in rungs:
        try:
            costs.append(rung_cost(changed_spec(loaded, rung.changes).spec, base_dir(loaded), rung.period))
        except DesignkitError:  # the loader refuses the rung: it runs to a refused row, at the floor's cost
            costs.append(VARIANT_FLOOR)
    budget = Budget(ctx.budget, max(costs) if costs else ctx.budget)
    kept, left, planned = [], [], 0.0
    for i in _coarse_first(len(rungs)):
        if planned + costs[i] <= ctx.budget * (1 + 1e-9) or not kept:
            kept.append(rungs[i])
            planned += costs[i]
        else:
            left.append((rungs[i], costs[i]))
    return kept, left, budget


def _run(ctx: StudyContext) -> StudyResult:
    from designkit.studies.core.variants import outcome_of
    from designkit.studies.core.words import outcome_words
    from designkit.studies.rate.figure import rate_figure
    from designkit.studies.rate.measure import units_of

    result = ctx.result
    key = sampling_key(result)
    given = ctx.settings is not None and bool(ctx.settings.rates)
    ladder, ladder_words = (ctx.settings.rates, "") if given else default_rates(result, key)
    if not given:  # a default rate whose period is not shorter than the run is no rate of the run
        duration = _duration(result.loaded.spec)[0]
        ladder = tuple(r for r in ladder if 1.0 / r < duration) or ladder
    rates = sorted(ladder, reverse=True)
    own, own_words = own_rate(result)
    rungs = [rung_changes(result, key, r) for r in rates]
    kept, left, budget = _plan(ctx, rungs)
    rows: list[Row] = []
    stopped = []
    for rung in kept:
        if budget.overrun:
            stopped.append(rung)
            continue
        row = _row(result, rung, rung.rate / own)
        budget.record(row.cpu)
        rows.append(row)
    rows.sort(key=lambda r: float(r.value))
    eu, cu = units_of(result)
    reduced_parts = []
    if left:
        reduced_parts.append(f"{', '.join(rate_text(r.rate) for r, _ in left)} not run: the studies' budget of "
                             f"{fmt_number(ctx.budget, 3)} s fits {len(kept)} of the {len(rungs)} rates at their "
                             f"estimated cost (up to {fmt_number(max(c for _, c in left), 2)} s each for those left "
                             "out; raise studies.budget to run them)")
    if stopped:
        reduced_parts.append(f"{', '.join(rate_text(r.rate) for r in stopped)} not run: {budget.overrun_words()}")
    reduced = "; ".join(reduced_parts)
    notes = [r.dt_note for r in kept if r.dt_note]
    dts = [amount(v, "s", 4) for v in sorted({round(r.metrics["dt"], 15) for r in rows if r.metrics.get("dt")})]
    step = (("; ".join(f"at {rate_text(r.rate)}, {r.dt_note}" for r in kept if r.dt_note) + "; elsewhere the spec's "
             "step, which divides the period") if notes else
            "the spec's simulation.dt, which divides every period" if result.loaded.spec.simulation.dt is not None
            else "left to the simulator's default, which takes the largest step not above its rule that divides the "
                 "sampling period")
    how = (f"{len(rows)} run{'s' if len(rows) != 1 else ''} of the spec with its command computed once a sampling "
           f"period and held in between ({key} set to 1/rate), each through the family's own run and judged by "
           f"every check it offers. The integration step simulation.dt: {step} (measured: "
           f"{', '.join(dts) or '—'}). The spec's own run is {own_words} ({rate_text(own)}; the row's factor is the "
           f"rate over that): {outcome_words(*outcome_of(result))}."
           + (f" The rates: {ladder_words}." if ladder_words else ""))
    clocks = []
    for r in rows:
        period, dt = r.metrics.get("sampling_period"), r.metrics.get("dt")
        if period is None or r.outcome in ("refused", "not run"):
            continue
        if abs(period - 1.0 / r.value) > 1e-9 / r.value:
            held = f"held over {amount(period, 's', 4)}" if period > 0 else "not sampled"
            clocks.append(f"at {rate_text(r.value)} the run's command was {held}, not held over the "
                          f"{amount(1.0 / r.value, 's', 4)} asked: {key} does not set the period of this run")
        elif dt and not divides(dt, period):
            clocks.append(f"at {rate_text(r.value)} the run's step {amount(dt, 's', 4)} does not divide the period")
    if clocks:
        how += " Beware: " + "; ".join(clocks) + "."
    questions = (
        Question("At which sampling rates does the switching law keep its verdict, and what does the rate do to its "
                 "precision, chattering and effort?", (how, *summary(rows, eu, cu)), (table(rows, eu, cu),)),
        Question("How often does the command reverse, against how often it is computed?", row_sentences(rows)),
    )
    intro = ("A switching law switches as fast as it is computed: the spec run again with its command sampled at each "
             "rate of a ladder, through the family's own run and checks; every number is measured on those runs."
             + (f" Reduced: {reduced}." if reduced else ""))
    figure = rate_figure(rows, eu, cu)
    section = ReportSection("study-rate", TITLE, intro, questions)
    entry = Entry("sampling rate", "Hz", tuple(rows), holding(rows))
    return StudyResult("rate", TITLE, (entry,), section, (figure,) if figure is not None else (), reduced,
                       budget.runs, budget.spent)


STUDY = Study(name="rate", title=TITLE, order=35, applies=_applies, run=_run, settings=RateSettings,
              validate=_validate)
"""The rate study (module docstring)."""
