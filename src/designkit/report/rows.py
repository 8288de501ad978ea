"""The rows of a report's tables, every cell already formatted (the renderers only lay them out)."""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from typing import Any

from designkit.display.numbers import plain_complex, sentence_units
from designkit.report.certificates import CertificateEntry

__all__ = [
    "CheckRow",
    "ComplianceRow",
    "MetricRow",
    "ParameterRow",
    "PoleRow",
    "Section",
    "WhyFix",
    "WhyRow",
    "check_anchor",
    "check_detail",
]


@dataclass(frozen=True)
class ParameterRow:
    """A named value with its unit and meaning."""

    name: str
    value: str
    unit: str
    meaning: str = ""


@dataclass(frozen=True)
class PoleRow:
    """A requested closed-loop pole next to the achieved one closest to it (``loop``: the joint loop, if any)."""

    loop: str
    requested: str
    achieved: str
    error: str
    damping: str
    natural_frequency: str


@dataclass(frozen=True)
class CheckRow:
    """A check as the report shows it (all values already formatted); ``label`` is its name in words."""

    name: str
    status: str
    target: str
    achieved: str
    margin: str
    unit: str
    detail: str
    certificate: tuple[CertificateEntry, ...]
    label: str = ""
    required: bool = True
    anchor: str = ""


def check_anchor(name: str) -> str:
    """The HTML id and Typst label of a check's details (``check-<name>``, other characters as ``-``)."""
    safe = re.sub(r"[^A-Za-z0-9_-]", "-", name)
    if safe != name:  # distinct names must keep distinct anchors
        safe += "-" + hashlib.sha256(name.encode("utf-8")).hexdigest()[:8]
    return "check-" + safe


@dataclass(frozen=True)
class ComplianceRow:
    """One row of the requirement-compliance table (all cells formatted, units written ``N·m``).

    ``limit`` is the requirement as an inequality (``≤ 5 N·m``) or in words; ``margin`` the signed
    distance to it (positive: met) and ``margin_percent`` that distance relative to the limit
    (``""`` when the limit is not a number).  ``evidence`` is the HTML anchor of the first figure
    that shows this check's evidence (``""``: none) and ``evidence_title`` its title.
    """

    name: str
    label: str
    status: str
    required: bool
    limit: str
    achieved: str
    margin: str
    margin_percent: str
    evidence: str
    evidence_title: str
    detail: str
    anchor: str = ""


@dataclass(frozen=True)
class WhyRow:
    """Why a required check failed or is undecided: the requirement, the achieved value, the
    shortfall (absolute and relative to the limit), the diagnosed cause and the fix."""

    check: str
    label: str
    status: str
    requirement: str
    achieved: str
    shortfall: str
    shortfall_percent: str
    cause: str
    fix: str
    fix_refs: tuple[int, ...] = ()


@dataclass(frozen=True)
class WhyFix:
    """A fix shared by several rows of "why it failed", shown once below the table.

    Parameters
    ----------
    number : int
        1-based; rows refer to it as "fix <number>" (their ``fix_refs``).
    text : str
        The fix, a sentence with its numbers and units.
    checks : tuple of str
        Labels of the rows it applies to, in row order.
    """

    number: int
    text: str
    checks: tuple[str, ...]


@dataclass(frozen=True)
class MetricRow:
    """A metric of the linear model next to the same metric of the nonlinear simulation."""

    metric: str
    unit: str
    linear: str
    nonlinear: str


@dataclass(frozen=True)
class Section:
    """A top-level section of the report, for the table of contents (``anchor`` is the HTML id)."""

    anchor: str
    title: str


def check_detail(check: Any) -> str:
    """A check's own sentence as the report writes it: units one way (``N·m``) and complex numbers as
    :func:`~designkit.display.numbers.fmt_complex` (a check may have written them as Python does)."""
    return plain_complex(sentence_units(check.detail))
