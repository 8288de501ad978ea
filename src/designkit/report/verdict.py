"""The verdict of a run: which required checks failed or are undecided, and the counts in words."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["verdict_of", "verdict_summary"]


def _words(check: Any) -> str:
    label = getattr(check, "label", "") or ""
    if label:
        return label
    base, _, suffix = check.name.partition("[")
    words = base.replace("_", " ").capitalize()
    return f"{words} ({suffix.rstrip(']')})" if suffix else words


def _listing(checks: Sequence[Any]) -> str:
    """The checks in words, per-joint checks of one kind grouped: ``Pole placement (joint1, joint2)``."""
    groups: dict[str, list[str]] = {}
    for c in checks:
        words = _words(c)
        head, sep, tail = words.partition(" (")
        key = head if sep and tail.endswith(")") and tail.startswith(("joint", "u", "loop")) else words
        groups.setdefault(key, [])
        if key != words:
            groups[key].append(tail[:-1])
    return ", ".join(f"{k} ({', '.join(v)})" if v else k for k, v in groups.items())


def verdict_of(checks: Sequence[Any]) -> tuple[str, str]:
    """``(verdict, kind)`` of a list of checks (the checks named in words); see
    :class:`~designkit.report.model.ReportModel`."""
    failed = [c for c in checks if c.passed is False and getattr(c, "required", True)]
    undecided = [c for c in checks if c.passed is None and getattr(c, "required", True)]
    if failed:
        text = "FAILED: " + _listing(failed)
        if undecided:
            text += "; UNDECIDED: " + _listing(undecided)
        return text, "failed"
    if undecided:
        return "UNDECIDED: " + _listing(undecided), "undecided"
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
