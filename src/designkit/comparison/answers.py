"""The sections a comparison report answers: one generic, from the metrics alone, and contributed ones.

A contribution is a :class:`ComparisonContribution`: which sets of controller kinds it answers for
(``applies``) and a function of the :class:`~designkit.pipeline.ComparisonResult` returning a
:class:`~designkit.display.section.ReportSection` (or None).  :data:`CONTRIBUTIONS` lists them; a family (or
a lab experiment that involves several) adds its entry there, e.g. :mod:`designkit.comparison.lab2` for the
MRAC and SELFTUNE simulators of lab experiment 2.  :func:`comparison_sections` is what the report lays out.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table

__all__ = ["CONTRIBUTIONS", "ComparisonContribution", "comparison_sections", "generic_section"]


@dataclass(frozen=True)
class ComparisonContribution:
    """A section a comparison report adds when its controllers' kinds fit.

    Parameters
    ----------
    name : str
        Who contributes it (for documentation and tests).
    applies : callable
        ``applies(kinds: tuple[str, ...]) -> bool``, the kinds of the comparison's controllers in spec order.
    build : callable
        ``build(result) -> ReportSection | None`` from the :class:`~designkit.pipeline.ComparisonResult`.
    """

    name: str
    applies: Callable[[tuple[str, ...]], bool]
    build: Callable[[Any], ReportSection | None]


def _lab2() -> ComparisonContribution:
    from designkit.comparison import lab2

    return ComparisonContribution("lab experiment 2: MRAC against SELFTUNE", lab2.applies, lab2.section)


def _lab3() -> ComparisonContribution:
    from designkit.comparison import lab3

    return ComparisonContribution("lab experiment 3: sliding mode on ROBEL's elastic joint", lab3.applies,
                                  lab3.section)


CONTRIBUTIONS: tuple[Callable[[], ComparisonContribution], ...] = (_lab2, _lab3)
"""Factories of the contributed sections, in report order (imported when a report is built)."""


def generic_section(result: Any) -> ReportSection:
    """Who wins on each metric and by how much (or ties), and each controller's verdict written from its checks'
    statuses (:func:`~designkit.comparison.verdicts.member_sentence`), from the table alone."""
    from designkit.comparison.table import TIE_TOLERANCE, tally

    table = result.table
    winners = table.winners()
    meaning = Table("How each metric was computed", ("metric", "computed as"),
                    tuple((m.label, m.meaning) for m in table.metrics))
    tolerance = fmt_number(100 * TIE_TOLERANCE, 2)
    return ReportSection(
        anchor="comparison-answers", title="Which controller does better, on what, by how much",
        intro="Every number is computed the same way from each controller's own run of the shared task; lower "
              f"is better for each metric. Two controllers tie on a metric when their values differ by at most "
              f"{tolerance} % of the larger: a tie is nobody's win.",
        questions=(
            Question("Who wins on each metric?", (tally(result.labels, winners), *(w.sentence for w in winners)),
                     (meaning,)),
            Question("Is each controller verified?", tuple(r.sentence for r in table.rows)),
        ),
    )


def comparison_sections(result: Any) -> tuple[ReportSection, ...]:
    """The generic section, then every contributed one that applies to the comparison's kinds."""
    kinds = tuple(r.design.kind for r in result.results)
    out: list[ReportSection] = [generic_section(result)]
    for factory in CONTRIBUTIONS:
        contribution = factory()
        if contribution.applies(kinds):
            section = contribution.build(result)
            if section is not None:
                out.append(section)
    return tuple(out)


def kinds_include(*wanted: str) -> Callable[[Sequence[str]], bool]:
    """An ``applies`` predicate: the comparison includes a controller of each of ``wanted``."""
    return lambda kinds: all(k in kinds for k in wanted)
