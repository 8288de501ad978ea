"""Each controller's verdict in a comparison, written from its checks' statuses only.

A controller is **verified** when every *required* check passes (:func:`designkit.verification.check.all_passed`:
an undecided check is not a pass); its *informational* checks are reported with their status but are not part
of the verdict.  :func:`member_sentence` counts the checks that pass, fail and are undecided, required and
informational apart, and names every check that did not pass, so that the sentence states exactly what the
statuses say and nothing more: a controller with an undecided check is never said to pass all its checks.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

__all__ = ["CheckLine", "check_lines", "check_summary", "member_sentence", "member_verified"]

Status = Literal["PASS", "FAIL", "UNDECIDED"]


@dataclass(frozen=True)
class CheckLine:
    """One check of a controller as the comparison reports it.

    Parameters
    ----------
    name : str
        Its machine name (``common_lyapunov``), used in ``--json`` only.
    label : str
        The check in words, as the report writes it.
    status : str
        ``PASS``, ``FAIL`` or ``UNDECIDED``.
    required : bool
        Whether the verdict depends on it (False: informational).
    """

    name: str
    label: str
    status: Status
    required: bool = True


def _words(check: Any) -> str:
    label = getattr(check, "label", "") or ""
    return label or check.name.replace("_", " ").capitalize()


def check_lines(checks: Iterable[Any]) -> tuple[CheckLine, ...]:
    """The :class:`CheckLine` of each :class:`~designkit.verification.check.Check` of a run, in run order."""
    return tuple(CheckLine(c.name, _words(c), c.status, bool(getattr(c, "required", True))) for c in checks)


def member_verified(checks: Sequence[CheckLine]) -> bool:
    """True when every required check passes (undecided is not a pass; informational checks do not count)."""
    return all(c.status == "PASS" for c in checks if c.required)


def _count(n: int, singular: str, plural: str) -> str:
    return f"{n} {singular if n == 1 else plural}"


def _tally(group: Sequence[CheckLine]) -> str:
    """``5 pass, 1 fails and 1 is undecided`` for a group of checks (only the statuses present)."""
    passed = sum(c.status == "PASS" for c in group)
    failed = sum(c.status == "FAIL" for c in group)
    undecided = sum(c.status == "UNDECIDED" for c in group)
    parts = [p for n, p in ((passed, _count(passed, "passes", "pass")), (failed, _count(failed, "fails", "fail")),
                            (undecided, _count(undecided, "is undecided", "are undecided"))) if n]
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _named(group: Sequence[CheckLine]) -> str:
    """The checks of a group that did not pass, by name: ``: A`` when they share one status, else ``; failed: A,
    B; undecided: C`` (empty when every check of the group passes)."""
    lists = [(word, [c.label for c in group if c.status == status])
             for status, word in (("FAIL", "failed"), ("UNDECIDED", "undecided"))]
    lists = [(word, names) for word, names in lists if names]
    if not lists:
        return ""
    if len(lists) == 1:
        return ": " + ", ".join(lists[0][1])
    return "; " + "; ".join(f"{word}: " + ", ".join(names) for word, names in lists)


def _group(group: Sequence[CheckLine], adjective: str, qualifier: str = "") -> str:
    """One group's clause: its size, how many pass, fail and are undecided, and the name of each that did not
    pass, e.g. ``of its 3 informational checks (not part of the verdict), 2 pass and 1 is undecided: A``."""
    n = len(group)
    kind = f"{adjective} check" + ("s" if n != 1 else "") + qualifier
    if all(c.status == "PASS" for c in group):
        return (f"its only {kind} passes" if n == 1 else f"both its {kind} pass" if n == 2 else
                f"all {n} of its {kind} pass")
    if n == 1:
        return f"its only {kind} " + ("fails" if group[0].status == "FAIL" else "is undecided") + _named(group)
    return f"of its {n} {kind}, {_tally(group)}{_named(group)}"


def check_summary(checks: Sequence[CheckLine]) -> str:
    """What a controller's checks say, without its name: how many required checks pass, fail and are undecided,
    the same for the informational ones (not part of the verdict), and the name of every check that did not pass,
    e.g. ``All 7 of its required checks pass. Of its 3 informational checks (not part of the verdict), 2 pass and
    1 is undecided: Common Lyapunov function over the parameter box.``"""
    if not checks:
        return "No checks were run."
    required = [c for c in checks if c.required]
    informational = [c for c in checks if not c.required]
    if all(c.status == "PASS" for c in checks):
        n = len(checks)
        every = ("its only check passes" if n == 1 else "both its checks pass" if n == 2 else
                 f"all {n} of its checks pass")
        split = f" ({len(required)} required, {len(informational)} informational)" if informational else ""
        return _capital(every + split) + "."
    clauses = [_group(required, "required") if required else "it has no required check"]
    if informational:
        clauses.append(_group(informational, "informational", " (not part of the verdict)"))
    return " ".join(_capital(c) + "." for c in clauses)


def _capital(text: str) -> str:
    return text[0].upper() + text[1:]


def member_sentence(label: str, controller: str, checks: Sequence[CheckLine]) -> str:
    """The comparison's sentence on one controller, generated from its checks' statuses.

    Parameters
    ----------
    label : str
        The controller's label in the comparison.
    controller : str
        Its family in words.
    checks : sequence of CheckLine
        Every check of its own run.

    Returns
    -------
    str
        ``<label> (<controller>) is verified`` only when every required check passes, else ``is not
        verified``; then :func:`check_summary`: how many required checks pass, fail and are undecided, the same
        for the informational ones (not part of the verdict), and the name of every check that did not pass.
    """
    who = f"{label} ({controller})" if "(" not in controller else f"{label}, {controller},"
    if not checks:
        return f"{who} ran no checks, so nothing about it was verified beyond its synthesis."
    verdict = "is verified" if member_verified(checks) else "is not verified"
    summary = check_summary(checks)
    return f"{who} {verdict}: {summary[0].lower()}{summary[1:]}"
