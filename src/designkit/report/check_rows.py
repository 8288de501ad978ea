"""The rows of appendix A: every check with its target, value, margin, detail and rendered certificate."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

from designkit.display.numbers import fmt_number, fmt_signed, plain_complex, unit
from designkit.report.certificates import CertificateEntry, render_certificate
from designkit.report.labels import check_label
from designkit.report.rows import CheckRow, check_anchor, check_detail

__all__ = ["check_row", "check_rows"]


def check_row(check: Any) -> CheckRow:
    """The row of one check (all values formatted, the certificate rendered)."""
    achieved = check.achieved
    return CheckRow(
        name=check.name,
        status=check.status,
        target=unit(check.target) or "—",
        achieved=plain_complex(achieved) if isinstance(achieved, str) else fmt_number(achieved, 4),
        margin=fmt_signed(check.margin, 4),
        unit=unit(check.unit),
        detail=check_detail(check),
        certificate=render_certificate(check.certificate),
        label=check_label(check),
        required=bool(getattr(check, "required", True)),
        anchor=check_anchor(check.name),
    )


def _same(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    try:
        return bool(a == b)
    except (ValueError, TypeError):  # e.g. arrays in a certificate: compare no further
        return False


def check_rows(checks: Sequence[Any]) -> tuple[CheckRow, ...]:
    """Rows of the checks table; a certificate identical to an earlier check's is not repeated."""
    rows: list[CheckRow] = []
    for k, check in enumerate(checks):
        row = check_row(check)
        earlier = next((c for c in checks[:k] if check.certificate and _same(c.certificate, check.certificate)),
                       None)
        if earlier is not None:
            row = dataclasses.replace(row, certificate=(CertificateEntry("certificate", f"same as {earlier.name}"),))
        rows.append(row)
    return tuple(rows)
