"""Where an adaptation, learning or switching gain stops working: a boundary found on a grid, refined where the
outcome changes, never by assuming the outcome is monotone in the gain.

For each knob the family marks ``boundary`` (an MRAC's adaptation gain, a learning gain, a switching amplitude), or
the one the spec's ``studies.boundary.knob`` names, the study runs the spec through the family's own run at every
point of a logarithmic grid over the knob's search range (the family's declared range, or ``studies.boundary.low``
and ``high``), :data:`PER_DECADE` points a decade anchored on the powers of ten -- so two specs of one scenario
that differ only in the knob's value run the same grid and find the same boundary.  Each point passes when every
required check of the family passes.  Wherever two neighbouring points disagree, the geometric midpoint is run,
up to :data:`REFINE` times, so every change of outcome is located to within a factor ``10^(1/(PER_DECADE
2^REFINE))``, however many there are.

A value is **recommended** only where it and its neighbourhood passed: both ends of ``[value/nu, value*nu]``, ``nu``
half a grid step (:func:`neighbourhood`), and every run inside were run and passed.  The candidates are, in each
stretch of passing runs wide enough, its runs ranked by the family's primary metric (or the stretch's centre);
their neighbourhoods are run, best first, until one passes (at most :data:`MAX_CANDIDATES`); none is recommended
when none does, and the report says so.  The knob's value in the spec is judged by the spec's own run.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import model_validator

from designkit.display.numbers import fmt_number, unit
from designkit.display.section import Question, ReportSection, Table
from designkit.spec.fields import PositiveFinite, Section
from designkit.studies.core.budget import Budget
from designkit.studies.core.metrics import metrics_of
from designkit.studies.core.study import Entry, Recommended, Row, Study, StudyContext, StudyResult
from designkit.studies.core.variants import run_variant
from designkit.studies.core.words import value_text

__all__ = ["PER_DECADE", "REFINE", "STUDY", "BoundarySettings", "boundary_points", "candidates", "neighbourhood",
           "recommend", "search", "search_grid"]

PER_DECADE = 2
"""Grid points per decade of the search range."""
REFINE = 3
"""Times a change of outcome between neighbours is bisected (geometrically)."""
MAX_CANDIDATES = 3
"""Most values whose neighbourhood is run before the study gives up recommending one."""
MAX_DECADES = 8
"""Widest default search range (decades); a wider declared range is centred on the value in use."""


class BoundarySettings(Section):
    """``studies.boundary``: the knob (``knob``, default every boundary knob of the family) and the search range
    (``low``, ``high``, the knob's unit, inside the range the family declares)."""

    knob: str | None = None
    low: PositiveFinite | None = None
    high: PositiveFinite | None = None

    @model_validator(mode="after")
    def _ordered(self) -> BoundarySettings:
        if self.low is not None and self.high is not None and not self.low < self.high:
            raise ValueError(f"high: must be above low ({self.low:g}), got {self.high:g}")
        return self


def _boundary_knobs(family: Any, design: Any = None) -> list[Any]:
    return [k for k in family.knobs if k.boundary and (design is None or k.applies(design))]


def _validate(settings: BoundarySettings, family: Any, spec: Any) -> None:
    knobs = _boundary_knobs(family)
    if settings.knob is not None:
        knob = family.knob(settings.knob)
        if knob is None or not knob.boundary:
            names = ", ".join(k.key for k in knobs) or "none"
            raise ValueError(f"knob: the {family.kind} family has no boundary knob {settings.knob!r}; its boundary "
                             f"knobs are {names}")
        knobs = [knob]
    if not knobs:
        raise ValueError(f"knob: the {family.kind} family declares no knob with a stability or convergence boundary")
    for knob in knobs:
        for name in ("low", "high"):
            value = getattr(settings, name)
            if value is not None and not knob.inside(value):
                raise ValueError(f"{name}: {value:g} is outside the range the family declares for {knob.key} "
                                 f"([{knob.low:g}, {knob.high:g}] {unit(knob.unit)})".rstrip())


def _applies(result: Any, family: Any) -> bool:
    return result.simulation is not None and bool(_boundary_knobs(family, result.design))


def search_grid(low: float, high: float, per_decade: int = PER_DECADE) -> np.ndarray:
    """The grid points ``10^(k/per_decade)`` inside ``[low, high]`` (both ends included when not on the grid)."""
    k_lo, k_hi = math.ceil(math.log10(low) * per_decade - 1e-9), math.floor(math.log10(high) * per_decade + 1e-9)
    pts = [10.0 ** (k / per_decade) for k in range(k_lo, k_hi + 1)]
    if not pts or pts[0] > low * (1 + 1e-9):
        pts.insert(0, low)
    if pts[-1] < high * (1 - 1e-9):
        pts.append(high)
    return np.asarray(pts, dtype=float)


def boundary_points(rows: list[Row]) -> list[tuple[float, float]]:
    """Adjacent ``(value, value)`` pairs, in increasing value, whose outcomes differ (pass against not pass)."""
    ordered = sorted(rows, key=lambda r: r.value)
    return [(a.value, b.value) for a, b in zip(ordered, ordered[1:], strict=False) if a.passed != b.passed]


def neighbourhood(per_decade: int = PER_DECADE) -> float:
    """The factor ``nu`` of a recommendation's neighbourhood ``[value/nu, value*nu]``: half a grid step."""
    return 10.0 ** (1.0 / (2 * per_decade))


def _runs_of(rows: list[Row], value: float) -> Row | None:
    return next((r for r in rows if abs(r.value - value) <= 1e-9 * value), None)


def candidates(rows: list[Row], nu: float, metric: Any) -> list[float]:
    """Values worth recommending, best first: in each stretch of consecutive passing runs wide enough to hold a
    neighbourhood (``high/low >= nu^2``), its passing runs at least ``nu`` inside it ranked by the primary metric,
    else the stretch's geometric centre."""
    ordered = sorted(rows, key=lambda r: r.value)
    stretches, current = [], []
    for r in ordered:
        if r.passed:
            current.append(r)
        elif current:
            stretches.append(current)
            current = []
    if current:
        stretches.append(current)
    scored = []
    for st in stretches:
        lo, hi = st[0].value, st[-1].value
        if hi / lo < nu * nu * (1 - 1e-9):
            continue
        inside = [r for r in st if lo * nu * (1 - 1e-9) <= r.value <= hi / nu * (1 + 1e-9)]
        if not inside:
            scored.append((1, 0.0, math.sqrt(lo * hi)))
            continue
        for r in inside:
            m = r.metrics.get(metric.key) if metric is not None else None
            sign = 1.0 if metric is None or metric.better == "lower" else -1.0
            scored.append((0 if m is not None else 1, sign * m if m is not None else 0.0, r.value))
    return [v for *_, v in sorted(scored)]


def recommend(rows: list[Row], nu: float) -> Recommended | None:
    """The first value of ``rows`` (in the order given by :func:`candidates`) whose neighbourhood was run at both
    ends and passed at every run inside it; None when none has."""
    for r in rows:
        if not r.passed:
            continue
        lo, hi = r.value / nu, r.value * nu
        ends = _runs_of(rows, lo), _runs_of(rows, hi)
        near = [x for x in rows if lo * (1 - 1e-9) <= x.value <= hi * (1 + 1e-9)]
        if all(e is not None for e in ends) and all(x.passed for x in near):
            return Recommended(float(r.value), float(lo), float(hi), tuple(sorted(float(x.value) for x in near)))
    return None


def _search(knob: Any, current: float | None, settings: BoundarySettings | None, design: Any
            ) -> tuple[float, float, str]:
    lo, hi = knob.low, knob.high
    why = "the range the family declares"
    if knob.search is not None:
        s_lo, s_hi = knob.search(design)
        lo, hi, why = max(lo, s_lo), min(hi, s_hi), "the range the family searches for this design"
    if settings is not None and settings.low is not None:
        lo, why = settings.low, "the spec's studies.boundary"
    if settings is not None and settings.high is not None:
        hi, why = settings.high, "the spec's studies.boundary"
    if math.log10(hi / lo) > MAX_DECADES:
        centre = math.log10(current) if current else 0.5 * (math.log10(lo) + math.log10(hi))
        centre = math.floor(centre + 0.5)
        lo = max(lo, 10.0 ** (centre - MAX_DECADES // 2))
        hi = min(hi, 10.0 ** (centre + MAX_DECADES // 2))
        why += f", {MAX_DECADES} decades about the value in use"
    return lo, hi, why


MIN_RUNS = 3
"""Fewest runs a search makes (the range's ends and middle), whatever the budget: never skipped, and a budget that
fits fewer says what a search needs."""


@dataclass(frozen=True)
class _Axis:
    """Where the search runs: ``coordinate`` values on a logarithmic grid, each mapped to the knob's value."""

    low: float
    high: float
    why: str
    to_value: Any
    name: str
    unit: str


def _axis(ctx: StudyContext, knob: Any, current: Any) -> _Axis:
    """The search's coordinate: the knob's value; ``1 - lambda`` for a forgetting factor; a common factor of a
    per-parameter value."""
    design, settings = ctx.result.design, ctx.settings
    if current is not None and np.ndim(current) > 0:
        arr = np.asarray(current, dtype=float)
        return _Axis(10.0 ** (-MAX_DECADES / 2), 10.0 ** (MAX_DECADES / 2), "factors of the value in use",
                     lambda g: arr * g, f"{knob.key} factor", "")
    if knob.role == "forgetting":
        lo, hi, why = _search(knob, current, settings, design)
        return _Axis(max(1.0 - hi, 1e-6), 1.0 - lo, why + ", searched on 1 − " + knob.key, lambda g: 1.0 - g,
                     f"1 − {knob.key}", "")
    lo, hi, why = _search(knob, current, settings, design)
    return _Axis(lo, hi, why, lambda g: g, knob.key, knob.unit)


def _entry(ctx: StudyContext, knob: Any, budget: Budget, metrics: tuple) -> tuple[Entry, tuple[str, ...],
                                                                                  tuple[Table, ...], str]:
    from designkit.runner.variants import knob_value

    result = ctx.result
    current = knob_value(knob, result.loaded.spec, result.design)
    axis = _axis(ctx, knob, current)
    room = budget.capacity()
    if room < MIN_RUNS:  # never skipped: the range's ends and middle, said so
        budget = dataclasses.replace(budget, seconds=MIN_RUNS * budget.estimate)
        cut = (f"{knob.key}: three points only (the range's ends and middle): a search of one point a decade needs "
               f"{len(search_grid(axis.low, axis.high, 1))} runs of about {fmt_number(budget.per_run, 2)} s, more "
               f"than the studies' budget of {fmt_number(ctx.budget, 3)} s (raise studies.budget to locate the "
               "boundary)")
    else:
        cut = ""
    base = float(current) if current is not None and np.ndim(current) == 0 else None

    def run(g: float) -> Row:
        value = axis.to_value(g)
        factor = float(value / base) if base else float(g)
        row = run_variant(result, knob, value, factor, metrics)
        return dataclasses.replace(row, value=float(g))

    def run_many(values: Any) -> list[Row]:
        return ctx.run_all([(lambda g=g: run(g)) for g in values], budget)

    primary = metrics[0] if metrics else None
    rows, pick, nu, reduced = search(axis.low, axis.high, run_many, budget, primary)
    if cut:
        reduced = cut
    sentences = _sentences(knob, axis, rows, pick, nu, primary, result, base)
    setting = None
    if pick is not None and knob.path and base is not None:
        setting = (knob.path, float(axis.to_value(pick.value)))
    table = Table(f"{axis.name}: every run of the search, in increasing value",
                  (axis.name + (f" ({unit(axis.unit)})" if axis.unit else ""), "Outcome",
                   *(m.label + (f" ({unit(m.unit)})" if m.unit else "") for m in metrics)),
                  tuple((fmt_number(r.value, 4), r.outcome if not r.detail else f"{r.outcome}: {r.detail}",
                         *(fmt_number(r.metrics.get(m.key), 4) for m in metrics)) for r in rows))
    return Entry(axis.name, axis.unit, tuple(rows), pick, setting), sentences, (table,), reduced


def _coarse_first(n: int) -> list[int]:
    """Indices ``0 .. n-1`` ends first, then the midpoints of the gaps, coarsest first."""
    if n <= 2:
        return list(range(n))
    order, seen, gaps = [0, n - 1], {0, n - 1}, [(0, n - 1)]
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


def search(low: float, high: float, run_many: Any, budget: Budget, primary: Any = None
           ) -> tuple[list[Row], Recommended | None, float, str]:
    """The search of the module docstring over ``[low, high]`` with ``run_many(values) -> rows`` (independent
    runs, in the order given; a batch may run on two cores).

    Returns
    -------
    rows : list of Row
        Every run, in increasing value.
    recommended : Recommended or None
    nu : float
        The neighbourhood's factor.
    reduced : str
        What the budget left out (``""``: nothing).
    """
    per_decade = PER_DECADE
    grid = search_grid(low, high, per_decade)
    reduced = ""
    room = budget.capacity()
    if len(grid) > room:
        per_decade = 1
        grid = search_grid(low, high, per_decade)
        reduced = f"one point a decade instead of {PER_DECADE} (the budget fits {room} runs)"
        if len(grid) > room:
            grid = grid[np.linspace(0, len(grid) - 1, max(room, 2)).round().astype(int)]
            reduced = f"{max(room, 2)} points over the range (the budget fits no more)"
    order = _coarse_first(len(grid))  # the grid's ends and middle first: a grid cut short still spans the range
    rows = list(run_many([grid[i] for i in order[:2]]))
    if len(order) > 2 and not budget.overrun:
        rows += run_many([grid[i] for i in order[2:]])
    elif len(order) > 2:
        reduced = (reduced + "; " if reduced else "") + f"the grid stopped after 2 of {len(grid)} points: " \
            + budget.overrun_words()
    for _ in range(REFINE):
        pairs = boundary_points(rows)
        if not pairs or not budget.affords(len(pairs)):
            if pairs:
                reduced = (reduced + "; " if reduced else "") + "the last refinement was left out (budget)"
            break
        rows += run_many([math.sqrt(a * b) for a, b in pairs])
    # A recommendation: the best candidates, each run with both ends of its neighbourhood until one passes.
    nu = neighbourhood(per_decade)
    pick = None
    for g in candidates(rows, nu, primary)[:MAX_CANDIDATES]:
        missing = [v for v in (g, g / nu, g * nu) if _runs_of(rows, v) is None]
        if not budget.affords(len(missing)):
            reduced = (reduced + "; " if reduced else "") + "the recommendation's neighbourhood was not run (budget)"
            break
        rows += run_many(missing)
        first = [r for r in rows if abs(r.value - g) <= 1e-9 * g]
        pick = recommend(first + [r for r in rows if r not in first], nu)
        if pick is not None and abs(pick.value - g) <= 1e-9 * g:
            break
        pick = None
    rows.sort(key=lambda r: r.value)
    return rows, pick, nu, reduced


def _sentences(knob: Any, axis: _Axis, rows: list[Row], pick: Recommended | None, nu: float, primary: Any,
               result: Any, base: float | None) -> tuple[str, ...]:
    changes = boundary_points(rows)
    out = [f"{len(rows)} runs of the spec with {axis.name} from {value_text(axis.low, axis.unit, 3)} to "
           f"{value_text(axis.high, axis.unit, 3)} ({axis.why}); each run is judged by every required check of the "
           "family."]
    if not changes:
        out.append("Every point has the same outcome: " + ("all pass." if rows[0].passed else "none passes."))
    else:
        words = []
        for a, b in changes:
            below = next(r for r in rows if r.value == a)
            words.append(f"between {fmt_number(a, 3)} and {fmt_number(b, 3)} ("
                         + ("passes below, fails above" if below.passed else "fails below, passes above") + ")")
        out.append(f"The outcome changes {len(changes)} time{'s' if len(changes) > 1 else ''}: " + "; ".join(words)
                   + ".")
        if len(changes) > 1:
            out.append(f"The outcome is not monotone in {axis.name}: a single threshold would misstate it.")
    if pick is not None:
        out.append(f"Recommended: {axis.name} = {value_text(pick.value, axis.unit, 3)}, which passes, as does every "
                   f"run from {fmt_number(pick.low, 3)} to {fmt_number(pick.high, 3)} ({len(pick.checked)} runs, both "
                   "ends included)" + (f"; ranked by the {primary.label}" if primary else "") + ".")
    else:
        out.append("No value is recommended: no value was found whose neighbourhood (half a grid step each way, a "
                   f"factor of {fmt_number(nu, 3)}) passes at both ends and at every run inside.")
    if base is not None:
        spec_pass = all(c.passed is True for c in result.checks if c.required)
        out.append(f"The spec's own {knob.key} = {value_text(base, knob.unit, 4)} "
                   + ("passes" if spec_pass else "does not pass") + " in the spec's run.")
    return tuple(out)


def _run(ctx: StudyContext) -> StudyResult:

    result, fam = ctx.result, ctx.family
    metrics = metrics_of(result, fam)
    settings = ctx.settings
    knobs = [fam.knob(settings.knob)] if settings is not None and settings.knob else _boundary_knobs(fam, result.design)
    entries, questions, reduced = [], [], []
    budget = ctx.new_budget()
    for knob in knobs:
        entry, sentences, tables, cut = _entry(ctx, knob, budget, metrics)
        entries.append(entry)
        if cut:
            reduced.append(f"{knob.key}: {cut}")
        questions.append(Question(f"For which {knob.key} ({knob.meaning}) does every required check pass?",
                                  sentences, tables))
    text = "; ".join(reduced)
    intro = ("The spec run again over a logarithmic grid of each gain, refined wherever the outcome changes between "
             "neighbours (never assuming it is monotone); each run is the family's own, judged by the family's "
             "checks." + (f" Reduced: {text}." if text else ""))
    section = ReportSection("study-boundary", "Stability and convergence boundary", intro, tuple(questions))
    return StudyResult("boundary", "Stability and convergence boundary", tuple(entries), section, (), text,
                       budget.runs, budget.spent)


STUDY = Study(name="boundary", title="Stability and convergence boundary", order=30, applies=_applies, run=_run,
              settings=BoundarySettings, validate=_validate)
"""The boundary study (module docstring)."""
