"""The requirement-compliance table: each check's limit, achieved value, margin and evidence figure.

The helpers that read a requirement (:func:`limit_of`: ``"<= 5 N*m"`` -> ``"≤ 5 N·m"`` and 5) and write
a check's value (:func:`achieved_text`, :func:`unit_suffix`, :func:`percent_of`) serve the "why it
failed" rows too, so both tables say the same numbers the same way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from designkit.display.numbers import TARGET, fmt_number, fmt_signed, is_real, plain_complex, unit
from designkit.report.labels import check_label
from designkit.report.rows import ComplianceRow, check_anchor, check_detail

__all__ = ["achieved_text", "compliance_row", "limit_of", "percent_of", "unit_suffix"]

_SYMBOL = {"<=": "≤", ">=": "≥", "<": "<", ">": ">", "≤": "≤", "≥": "≥"}


def unit_suffix(text: str) -> str:
    """`` unit`` to append to a number (empty for a dimensionless ``1``)."""
    u = unit(text).strip()
    if u in ("", "1", "—"):
        return ""
    if u.startswith("1 (") and u.endswith(")"):
        return " " + u[3:-1]
    return " " + u


def limit_of(check: Any) -> tuple[str, float | None]:
    """The requirement as text (``≤ 5 N·m``) and its numeric limit (None when not a number)."""
    target = unit(str(check.target or "")).strip()
    found = TARGET.match(target)
    if found is None:
        return (target.replace("<=", "≤").replace(">=", "≥") or "—"), None
    op, number, rest = found.groups()
    return f"{_SYMBOL[op]} {fmt_number(float(number))} {rest}".strip(), float(number)


def achieved_text(check: Any) -> str:
    """The check's achieved value with its unit (``"undefined"`` when it has none)."""
    achieved = check.achieved
    if achieved is None:
        return "undefined"
    if isinstance(achieved, str):
        return plain_complex(achieved)
    return fmt_number(achieved, 4) + unit_suffix(check.unit)


def percent_of(value: float | None, limit: float | None) -> str:
    """``value`` in % of ``|limit|`` with 3 significant digits (never in exponent notation), signed."""
    if value is None or limit is None or limit == 0 or not math.isfinite(value):
        return ""
    x = 100 * value / abs(limit)
    if abs(x) >= 1000:  # three significant digits: "+268000 %", not "+267623 %"
        rounded = float(f"{x:.3g}")
        return f"{'+' if rounded > 0 else '-'}{abs(rounded):.0f} %"
    text = f"{x:+.0f}" if abs(x) >= 100 else fmt_signed(float(f"{x:.3g}"), 3)
    return f"{text} %"


def compliance_row(check: Any, figures: Sequence[Any]) -> ComplianceRow:
    """The compliance row of ``check``, its evidence the first of ``figures`` that names it."""
    limit, number = limit_of(check)
    margin = check.margin if is_real(check.margin) else None
    evidence = next((f for f in figures if check.name in tuple(getattr(f, "evidence", ()) or ())), None)
    return ComplianceRow(
        name=check.name, label=check_label(check), status=check.status,
        required=bool(getattr(check, "required", True)), limit=limit, achieved=achieved_text(check),
        margin=(fmt_signed(margin, 4) + unit_suffix(check.unit)) if margin is not None else "—",
        margin_percent=percent_of(margin, number),
        evidence=evidence.anchor if evidence is not None else "",
        evidence_title=evidence.title if evidence is not None else "",
        detail=check_detail(check),
        anchor=check_anchor(check.name),
    )
