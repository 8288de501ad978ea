"""The sections a comparison report answers: the generic one, from the metrics alone, then the comparison studies'.

:func:`generic_section` says who wins on each metric and each controller's verdict; the comparison studies
(:mod:`designkit.studies`, e.g. the lab experiments over several controllers) are discovered above this layer, run by
the :class:`~designkit.pipeline.ComparisonResult` (its ``studies``), and each returns its own section.
:func:`comparison_sections` is what the report lays out.
"""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table

__all__ = ["comparison_sections", "generic_section"]


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


def comparison_sections(result: Any, studies: bool = True) -> tuple[ReportSection, ...]:
    """The generic section, then the section of every comparison study the result ran (``result.studies``, run on
    first access; none with ``studies`` False)."""
    done = tuple(getattr(result, "studies", ())) if studies else ()
    return (generic_section(result), *(st.section for st in done if st.section is not None))
