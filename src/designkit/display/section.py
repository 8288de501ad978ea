"""A report section contributed by the module that owns its concept (a family's lab answers, an analysis).

The report lays these out; it does not write them.  A :class:`ReportSection` is a titled list of
:class:`Question` values -- a question of the notes and its answer, as sentences computed from the run
and tables of formatted cells -- optionally with figures of its own.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Question", "ReportSection", "Table"]


@dataclass(frozen=True)
class Table:
    """A table: ``caption``, ``header`` and ``rows`` of formatted cells (text, units typeset)."""

    caption: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class Question:
    """A question and its answer: ``sentences`` and ``tables`` computed from the run."""

    question: str
    sentences: tuple[str, ...]
    tables: tuple[Table, ...] = ()


@dataclass(frozen=True)
class ReportSection:
    """A section of the report.

    Parameters
    ----------
    anchor : str
        HTML id (``"lab-mrac"``), unique in a report.
    title : str
        Heading (``"Lab questions (notes, experiment 2: MRAC)"``).
    intro : str
        How the answers were obtained.
    questions : tuple of Question
    figures : tuple of Figure
        Figures drawn for this section (:class:`designkit.display.figure.Figure`).
    """

    anchor: str
    title: str
    intro: str = ""
    questions: tuple[Question, ...] = ()
    figures: tuple[Any, ...] = ()
