"""What a comparison study reads of its members, and how it runs one of them again with one thing changed.

A comparison study (``Study.comparison``) receives the :class:`~designkit.pipeline.ComparisonResult`: each member is
one controller's own run of the shared task.  The study reaches a member's family only through the registry
(:func:`designkit.families.family`) and what the family declares -- its ``display`` label, traits, knobs, metrics,
predictions, answers and variants (:class:`~designkit.synthesis.family.Family`); it never names a family.

A member run again (:func:`run_again`) goes through the family's own run (:mod:`designkit.runner.variants`) with
every check the family offers, so what the study says of it is what those checks say
(:func:`designkit.comparison.verdicts.check_summary`), and its numbers are the run's: the family's metrics and, when
asked, the comparison table's (:func:`designkit.comparison.metrics.compute_metrics`, the departure from the run on
the unchanged plant measured against that variant's own re-run without the plant change).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from designkit.comparison.verdicts import CheckLine, check_lines, check_summary, member_sentence, member_verified
from designkit.studies.core.budget import Budget, cpu_seconds
from designkit.studies.core.study import Row
from designkit.studies.core.variants import run_row

__all__ = ["Measured", "Member", "Plan", "amount", "members", "run_again", "status_words", "table_metrics",
           "with_traits"]


@dataclass(frozen=True)
class Member:
    """One controller of a comparison.

    Parameters
    ----------
    label : str
        Its label in the comparison.
    run : PipelineResult
        Its own run of the shared task.
    family : Family
        Its family (:func:`designkit.families.family` of its design's kind).
    values : Mapping
        Its row of the comparison table: metric key -> value (the table's units).
    """

    label: str
    run: Any
    family: Any
    values: Any

    @property
    def controller(self) -> str:
        """The family in words (``Family.display.label``)."""
        return self.family.display.label

    def has(self, *traits: str) -> bool:
        """Whether the family declares every trait of ``traits``."""
        return all(t in self.family.traits for t in traits)

    @property
    def verdict(self) -> str:
        """Its own run's verdict in a sentence, from its checks' statuses
        (:func:`~designkit.comparison.verdicts.member_sentence`)."""
        return member_sentence(self.label, self.controller, check_lines(self.run.checks))


def members(result: Any) -> tuple[Member, ...]:
    """The members of a comparison result, in spec order."""
    from designkit.families import family

    return tuple(Member(label, run, family(run.design.kind), result.table.row(label).values)
                 for label, run in zip(result.labels, result.results, strict=True))


def with_traits(found: tuple[Member, ...], *traits: str, without: tuple[str, ...] = ()) -> tuple[Member, ...]:
    """The members whose families declare every trait of ``traits`` and none of ``without``."""
    return tuple(m for m in found if m.has(*traits) and not any(t in m.family.traits for t in without))


def amount(value: float | None, unit_text: str = "", digits: int = 3) -> str:
    """A measured value with its unit typeset: ``—`` when undefined, ``never`` for an infinite time (s),
    ``unbounded`` for another infinite value, an integer such as an adaptation gain of ``10000`` written whole, a
    large or small one as ``2.29 × 10⁴``."""
    import math

    from designkit.display.numbers import quantity

    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    x = float(value)
    if math.isinf(x):
        return "never" if unit_text == "s" else "unbounded"
    if 1e3 <= abs(x) < 1e9 and x == round(x):
        return quantity(int(round(x)), unit_text, 12)
    text = quantity(x, unit_text, digits)
    if "e" in text.split(" ")[0]:  # 2.29e+04 -> 2.29 × 10⁴
        from designkit.display.numbers import sci

        rest = text.split(" ", 1)[1] if " " in text else ""
        return f"{sci(x, digits)} {rest}".strip()
    return text


def status_words(lines: tuple[CheckLine, ...]) -> str:
    """What a run's checks say, as a clause: ``"verified: all 7 of its required checks pass"``, or ``"not verified:
    of its 7 required checks, 6 pass and 1 fails: Overshoot. ..."`` (:func:`~designkit.comparison.verdicts.
    check_summary`: informational checks that did not pass are named too)."""
    if not lines:
        return "no checks were run"
    summary = check_summary(lines)
    verdict = "verified" if member_verified(lines) else "not verified"
    return f"{verdict}: {summary[0].lower()}{summary[1:]}".rstrip(".")


@dataclass(frozen=True)
class Measured:
    """A member run again with one thing changed.

    Parameters
    ----------
    label : str
        The member's label.
    change : str
        What was changed, in words.
    row : Row
        Its outcome and metrics (:func:`~designkit.studies.core.variants.run_row`).
    checks : tuple of CheckLine
        Every check of the run (empty when the family refused the variant or the run could not be made).
    run : Run or None
        The run itself (None when not made), for what the study compares with the member's own run.
    """

    label: str
    change: str
    row: Row
    checks: tuple[CheckLine, ...] = ()
    run: Any = None

    @property
    def status(self) -> str:
        """What happened, as a predicate: ``"is verified: ..."`` or ``"is not verified: ..."`` (:func:`status_words`),
        ``"diverges: ..."``, ``"is refused by its family: ..."`` or ``"could not be run: ..."`` with the reason."""
        if self.row.outcome in ("verified", "failed", "undecided"):
            return f"is {status_words(self.checks)}"
        words = {"diverged": "diverges", "refused": "is refused by its family"}.get(self.row.outcome,
                                                                                  "could not be run")
        return f"{words}: {self.row.detail}" if self.row.detail else words

    @property
    def metrics(self) -> Any:
        """The row's metrics, by key."""
        return self.row.metrics


@dataclass(frozen=True)
class Plan:
    """A study's budget and what it left out, in words (checked before each run; the budget records the runs and
    ``left`` grows, the plan itself is not rebound)."""

    budget: Budget
    left: list[str] = field(default_factory=list)

    def fits(self, what: str, runs: int) -> bool:
        """Whether ``runs`` more runs fit the budget; if not, ``what`` is recorded as left out."""
        if self.budget.affords(runs):
            return True
        self.left.append(what)
        return False


def run_again(member: Member, change: str, make: Callable[[], Any], value: Any, metrics: tuple, budget: Budget,
              *, table: bool = False, factor: float = 1.0) -> Measured:
    """Run ``make()`` (a :mod:`designkit.runner.variants` run of ``member``'s spec with one thing changed) and measure
    it: its outcome and its checks, the ``metrics`` (:class:`~designkit.synthesis.knobs.Metric`), and with
    ``table`` the comparison table's metrics too (the departure ones against the variant's own re-run on the
    unchanged plant, a second simulation the budget records).  Never raises for what the variant does."""
    made: dict[str, Any] = {}

    def keep() -> Any:
        made["run"] = make()
        return made["run"]

    row = run_row(keep, factor, value, metrics, budget)
    run = made.get("run")
    if table and run is not None and run.simulation is not None and row.outcome != "diverged":
        start = cpu_seconds()
        row = replace(row, metrics={**row.metrics, **table_metrics(run)})
        budget.record(cpu_seconds() - start)
    return Measured(member.label, change, row, check_lines(run.checks) if run is not None else (), run)


def table_metrics(run: Any) -> dict[str, float | None]:
    """The comparison table's metrics of ``run`` (:func:`designkit.comparison.metrics.compute_metrics`), the
    departure ones against the same spec re-run without its plant change."""
    import numpy as np

    from designkit.comparison.metrics import baseline_simulation, compute_metrics

    plant = run.plant if run.plant is not None else run.design.plant
    with np.errstate(all="ignore"):
        base = baseline_simulation(run.loaded.spec, plant) if run.trials is None else None
        return dict(compute_metrics(run.loaded.spec, run.simulation, base))
