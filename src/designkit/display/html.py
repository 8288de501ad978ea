"""Small HTML for Jupyter views: escaped tables, headings and paragraphs with inline styles.

Every piece of text is escaped with :func:`markupsafe.escape`; styles are inline attributes (Jupyter may strip
``<style>`` from untrusted outputs).  Used by the notebook views of a design
(:mod:`designkit.display.design_view`) and of a run (:mod:`designkit.report.notebook`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from markupsafe import escape

__all__ = ["BANNER", "esc", "heading", "para", "status_cell", "table"]

BANNER = {
    "verified": ("#e6f4ea", "#1e7a34"),
    "failed": ("#fdecea", "#b3261e"),
    "undecided": ("#fff4e5", "#8a5300"),
}
_STATUS = {"PASS": "#1e7a34", "FAIL": "#b3261e", "UNDECIDED": "#8a5300"}
_TABLE = 'style="border-collapse:collapse;margin:0.3em 0 0.8em 0;font-size:0.9em"'
_CELL = "padding:2px 8px;border-bottom:1px solid #ddd;text-align:left;vertical-align:top"


def esc(value: Any) -> str:
    return str(escape("" if value is None else value))


def status_cell(status: str) -> str:
    colour = _STATUS.get(str(status).upper(), "inherit")
    return f'<td style="{_CELL};font-weight:bold;color:{colour}">{esc(status)}</td>'


def table(header: Sequence[str], rows: Iterable[Sequence[Any]], *, status_column: int | None = None,
           caption: str = "") -> str:
    """An HTML table; every cell is escaped (a cell given as ``("html", text)`` is inserted as is)."""
    out = [f"<table {_TABLE}>"]
    if caption:
        out.append(f'<caption style="text-align:left;font-weight:bold">{esc(caption)}</caption>')
    out.append("<thead><tr>" + "".join(f'<th style="{_CELL}">{esc(h)}</th>' for h in header) + "</tr></thead>")
    out.append("<tbody>")
    for row in rows:
        cells = []
        for k, cell in enumerate(row):
            if k == status_column:
                cells.append(status_cell(str(cell)))
            elif isinstance(cell, tuple) and len(cell) == 2 and cell[0] == "html":
                cells.append(f'<td style="{_CELL}">{cell[1]}</td>')
            else:
                cells.append(f'<td style="{_CELL}">{esc(cell)}</td>')
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def heading(text: str) -> str:
    return f'<h4 style="margin:0.8em 0 0.2em 0">{esc(text)}</h4>'


def para(text: str) -> str:
    return f'<p style="margin:0.2em 0">{esc(text)}</p>' if text else ""
