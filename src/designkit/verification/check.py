"""The result of one verification check: pass/fail/undecided plus its evidence."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

Status = Literal["PASS", "FAIL", "UNDECIDED"]


@dataclass(frozen=True)
class Check:
    """Outcome of a single verification check.

    Parameters
    ----------
    name : str
        Machine-readable name, e.g. ``"routh_hurwitz"``, ``"lyapunov"``, ``"overshoot"``.
    passed : bool or None
        ``True`` pass, ``False`` fail, ``None`` undecided (solver failure, inaccurate status, ...).
        Undecided never counts as a pass.
    target : str
        The requirement in words or as an inequality, e.g. ``"<= 10 %"``.
    achieved : float or str or None
        The value obtained (in ``unit``).
    margin : float or None
        Signed distance to the requirement, positive when it holds (in ``unit``).
    unit : str
        Unit of ``achieved`` and ``margin``.
    detail : str
        One line saying what was checked and, on failure, what failed.
    certificate : Mapping
        Evidence: e.g. ``{"P": [[...]], "eig_P": [...], "solver_status": "optimal"}``.
        Values are JSON-serialisable (lists, floats, str).
    data : Mapping
        Bulk data behind the check for the report's figures (time series, frequency responses);
        not part of :meth:`to_dict`.
    label : str
        The check in words, for the report (stamped by the runner from its rule when empty).
    warnings : tuple of str
        Plain sentences a reviewer must see even when the check passes (a weak margin of an
        informational check); the report's first page and ``--json``'s top-level ``warnings`` list them.
    required : bool
        Whether the verdict depends on this check.  An informational check (``False``) is
        reported with its status but does not make a design unverified, e.g. the common
        Lyapunov function of a parameter box, which is sufficient but not necessary for
        robust stability.
    """

    name: str
    passed: bool | None
    target: str = ""
    achieved: float | str | None = None
    margin: float | None = None
    unit: str = ""
    detail: str = ""
    certificate: Mapping[str, Any] = field(default_factory=dict)
    required: bool = True
    data: Mapping[str, Any] = field(default_factory=dict, compare=False, repr=False)
    label: str = ""
    warnings: tuple[str, ...] = ()

    @property
    def status(self) -> Status:
        """``"PASS"``, ``"FAIL"`` or ``"UNDECIDED"``."""
        if self.passed is None:
            return "UNDECIDED"
        return "PASS" if self.passed else "FAIL"

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable form."""
        return {
            "name": self.name,
            "passed": self.passed,
            "status": self.status,
            "target": self.target,
            "achieved": self.achieved,
            "margin": self.margin,
            "unit": self.unit,
            "detail": self.detail,
            "certificate": dict(self.certificate),
            "required": self.required,
            "label": self.label,
            "warnings": list(self.warnings),
        }


def all_passed(checks: tuple[Check, ...] | list[Check]) -> bool:
    """True when every required check passed (an undecided check is not a pass)."""
    return all(c.passed is True for c in checks if c.required)


def not_passed(checks: tuple[Check, ...] | list[Check]) -> tuple[Check, ...]:
    """Required checks that failed or are undecided."""
    return tuple(c for c in checks if c.required and c.passed is not True)
