"""The verdict of a run: which required checks failed or are undecided, and the counts in words."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["verdict_of", "verdict_summary"]


def verdict_of(checks: Sequence[Any]) -> tuple[str, str]:
    """``(verdict, kind)`` of a list of checks; see :class:`~designkit.report.model.ReportModel`."""
    failed = [c.name for c in checks if c.passed is False and getattr(c, "required", True)]
    undecided = [c.name for c in checks if c.passed is None and getattr(c, "required", True)]
    if failed:
        text = "FAILED: " + ", ".join(failed)
        if undecided:
            text += "; UNDECIDED: " + ", ".join(undecided)
        return text, "failed"
    if undecided:
        return "UNDECIDED: " + ", ".join(undecided), "undecided"
    return "VERIFIED", "verified"


def verdict_summary(checks: Sequence[Any]) -> str:
    """Counts of passed, failed and undecided checks (and the informational ones) in one sentence."""
    n = len(checks)
    if n == 0:
        return "No checks were run: nothing was verified beyond the synthesis itself."
    counts = [sum(c.passed is v for c in checks) for v in (True, False, None)]
    info = sum(not getattr(c, "required", True) for c in checks)
    extra = f" ({info} informational, not part of the verdict)" if info else ""
    return f"{counts[0]} passed, {counts[1]} failed, {counts[2]} undecided, of {n} check{'s' * (n != 1)}{extra}."
