"""Jupyter views: the ``_repr_html_`` of :class:`~designkit.pipeline.PipelineResult` and of
:class:`~designkit.synthesis.design.Design`.

:func:`result_html` lays out the same :class:`~designkit.report.model.ReportModel` as the HTML
and PDF reports (verdict, why it failed, requirement compliance, every check, gains, poles,
margins and the figures as inline SVG), so the notebook never says something the report does
not.  :func:`design_html` shows a design alone (gains with units, requested and achieved poles,
the closed loop's signals) without running any check.

Every piece of text is escaped with :func:`markupsafe.escape`; only the SVG produced by
:mod:`designkit.report.figures` is inlined as markup.  Styles are inline attributes (Jupyter may
strip ``<style>`` from untrusted outputs), and every id in a view carries a prefix unique to that
view, so several views in one notebook cannot collide.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from markupsafe import escape

__all__ = ["design_html", "result_html"]

_COUNTER = itertools.count(1)

_BANNER = {
    "verified": ("#e6f4ea", "#1e7a34"),
    "failed": ("#fdecea", "#b3261e"),
    "undecided": ("#fff4e5", "#8a5300"),
}
_STATUS = {"PASS": "#1e7a34", "FAIL": "#b3261e", "UNDECIDED": "#8a5300"}
_TABLE = 'style="border-collapse:collapse;margin:0.3em 0 0.8em 0;font-size:0.9em"'
_CELL = "padding:2px 8px;border-bottom:1px solid #ddd;text-align:left;vertical-align:top"


def _e(value: Any) -> str:
    return str(escape("" if value is None else value))


def _status_cell(status: str) -> str:
    colour = _STATUS.get(str(status).upper(), "inherit")
    return f'<td style="{_CELL};font-weight:bold;color:{colour}">{_e(status)}</td>'


def _table(header: Sequence[str], rows: Iterable[Sequence[Any]], *, status_column: int | None = None,
           caption: str = "") -> str:
    """An HTML table; every cell is escaped (a cell given as ``("html", text)`` is inserted as is)."""
    out = [f"<table {_TABLE}>"]
    if caption:
        out.append(f'<caption style="text-align:left;font-weight:bold">{_e(caption)}</caption>')
    out.append("<thead><tr>" + "".join(f'<th style="{_CELL}">{_e(h)}</th>' for h in header) + "</tr></thead>")
    out.append("<tbody>")
    for row in rows:
        cells = []
        for k, cell in enumerate(row):
            if k == status_column:
                cells.append(_status_cell(str(cell)))
            elif isinstance(cell, tuple) and len(cell) == 2 and cell[0] == "html":
                cells.append(f'<td style="{_CELL}">{cell[1]}</td>')
            else:
                cells.append(f'<td style="{_CELL}">{_e(cell)}</td>')
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _heading(text: str) -> str:
    return f'<h4 style="margin:0.8em 0 0.2em 0">{_e(text)}</h4>'


def _para(text: str) -> str:
    return f'<p style="margin:0.2em 0">{_e(text)}</p>' if text else ""


def _fields(row: Any, names: Sequence[str]) -> list[str]:
    return [str(getattr(row, n, "")) for n in names]


def _inline_svg(svg: str, prefix: str, title: str) -> str:
    from designkit.report.html import inline_svg

    try:
        return inline_svg(svg, prefix, title=title)
    except TypeError:  # an older signature without ``title``
        return inline_svg(svg, prefix)


def _label(row: Any) -> str:
    return str(getattr(row, "label", "") or getattr(row, "name", "") or getattr(row, "check", ""))


def _why_section(model: Any) -> str:
    """Diagnosis sentences (divergence, limit cycle) first -- the causes in the table refer to them -- then
    one row per failing or undecided check, the fixes shared by several rows (numbered, the rows refer to
    them), then where the causes come from."""
    why = tuple(getattr(model, "why", ()) or ())
    parts = [_heading("Why it failed")] if why else []
    for name in ("divergence", "limit_cycle"):
        parts.append(_para(str(getattr(model, name, "") or "")))
    if why:
        parts.append(_table(
            ("Check", "Status", "Requirement", "Achieved", "Shortfall", "Shortfall (%)", "Cause", "Fix"),
            ([f"{_label(r)} ({r.check})" if _label(r) != r.check else r.check, *_fields(
                r, ("status", "requirement", "achieved", "shortfall", "shortfall_percent", "cause", "fix"))]
             for r in why), status_column=1))
        fixes = tuple(getattr(model, "why_fixes", ()) or ())
        if fixes:
            parts.append(_table(("Fix", "Applies to", "What to do"),
                                ([f"Fix {f.number}", ", ".join(f.checks), f.text] for f in fixes),
                                caption="Fixes shared by several rows"))
        parts.append(_para(str(getattr(model, "why_note", "") or "")))
    return "".join(parts)


def _compliance_section(model: Any, prefix: str, anchors: set[str]) -> str:
    parts = []
    for field, title in (("compliance", "Requirement compliance"), ("informational", "Informational checks")):
        rows = tuple(getattr(model, field, ()) or ())
        if not rows:
            continue
        body = []
        for r in rows:
            evidence = str(getattr(r, "evidence", "") or "")
            ev_title = str(getattr(r, "evidence_title", "") or evidence)
            ev = ("html", f'<a href="#{_e(prefix + evidence)}">{_e(ev_title)}</a>') if evidence in anchors else ev_title
            body.append([_label(r), *_fields(r, ("limit", "achieved", "margin", "margin_percent")),
                         str(getattr(r, "status", "")), ev])
        parts.append(_heading(title))
        parts.append(_table(("Requirement", "Limit", "Achieved", "Margin", "Margin (%)", "Status", "Evidence"), body,
                            status_column=5))
    return "".join(parts)


def _checks_section(model: Any) -> str:
    rows = []
    for c in model.checks:
        label = str(getattr(c, "label", "") or "")
        name = f"{label} ({c.name})" if label and label != c.name else c.name
        achieved = f"{c.achieved} {c.unit}".strip() if c.achieved not in ("", "—") else c.achieved
        informational = getattr(c, "required", True) is False
        rows.append([name + (" — informational" if informational else ""), c.status, c.target, achieved,
                     c.margin, c.detail])
    return _heading("Checks") + _table(("Check", "Status", "Target", "Achieved", "Margin", "Detail"), rows,
                                       status_column=1)


def _parameter_table(title: str, rows: Sequence[Any]) -> str:
    if not rows:
        return ""
    return _heading(title) + _table(("Name", "Value", "Unit", "Meaning"),
                                    (_fields(r, ("name", "value", "unit", "meaning")) for r in rows))


def _poles_table(rows: Sequence[Any]) -> str:
    if not rows:
        return ""
    loops = any(getattr(r, "loop", "") for r in rows)
    header = (*(("Loop",) if loops else ()), "Requested (1/s)", "Achieved (1/s)", "Error (1/s)", "ζ", "ωn (rad/s)")
    names = (*(("loop",) if loops else ()), "requested", "achieved", "error", "damping", "natural_frequency")
    return _heading("Closed-loop poles") + _table(header, (_fields(r, names) for r in rows))


def _metrics_table(rows: Sequence[Any]) -> str:
    if not rows:
        return ""
    names = ("metric", "unit", "linear", "nonlinear")
    return _heading("Linear model vs nonlinear simulation") + _table(
        ("Metric", "Unit", "Linear", "Nonlinear"), (_fields(r, names) for r in rows))


def _figures_section(model: Any, prefix: str) -> tuple[str, set[str]]:
    figures = tuple(model.figures)
    anchors = tuple(getattr(model, "figure_anchors", ()) or ())
    if len(anchors) != len(figures):
        anchors = tuple(f"fig-{k}" for k in range(1, len(figures) + 1))
    parts = [_heading("Figures")] if figures else []
    for k, (fig, anchor) in enumerate(zip(figures, anchors, strict=True), start=1):
        svg = _inline_svg(fig.svg, f"{prefix}f{k}-", fig.title)
        parts.append(
            f'<figure id="{_e(prefix + anchor)}" style="margin:0.6em 0">'
            f'<div style="max-width:100%;overflow-x:auto">{svg}</div>'
            f'<figcaption style="font-size:0.85em"><b>{_e(fig.title)}.</b> {_e(fig.caption)}</figcaption></figure>'
        )
    return "".join(parts), set(anchors)


def result_html(model: Any, *, prefix: str | None = None) -> str:
    """A pipeline result as an HTML fragment for Jupyter, from its report model.

    Parameters
    ----------
    model : ReportModel
        Built by :func:`designkit.report.model.build_report_model`.
    prefix : str, optional
        Prefix of every id in the fragment (default: ``"dk<n>-"`` with ``n`` counting views in
        this process).

    Returns
    -------
    str
        One ``<div>``: verdict banner, why it failed (when something did), requirement
        compliance, every check, gains, poles, loop margins, linear vs nonlinear metrics, and
        the figures as inline SVG with their captions.
    """
    prefix = f"dk{next(_COUNTER)}-" if prefix is None else prefix
    background, colour = _BANNER.get(model.verdict_kind, ("#eeeeee", "#333333"))
    figures, anchors = _figures_section(model, prefix)
    parts = [
        '<div class="designkit-result" style="font-family:sans-serif;line-height:1.35">',
        f'<h3 style="margin:0.2em 0">{_e(model.title)}</h3>',
        _para(model.description),
        f'<div role="status" style="background:{background};color:{colour};border-left:6px solid {colour};'
        f'padding:6px 10px;margin:0.4em 0"><b style="font-size:1.15em">{_e(model.verdict)}</b><br>'
        f"{_e(model.verdict_summary)}</div>",
        _why_section(model),
        _compliance_section(model, prefix, anchors),
        _checks_section(model),
        _parameter_table("Gains", model.gains),
        _poles_table(model.poles),
        _parameter_table("Zeros", model.zeros),
        _parameter_table("Loop broken at the plant input", model.loop),
        _metrics_table(tuple(getattr(model, "linear_vs_nonlinear", ()) or ())),
        figures,
        f'<p style="font-size:0.8em;color:#555">Spec SHA-256 {_e(model.spec_sha256)}</p>',
        "</div>",
    ]
    return "".join(p for p in parts if p)


# ----------------------------------------------------------------------------- a design alone


def _fmt(value: Any, digits: int = 6) -> str:
    from designkit.report.certificates import fmt_number

    return fmt_number(value, digits)


def _gain_text(value: Any) -> str:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return _fmt(float(arr))
    if arr.ndim == 1:
        return "; ".join(f"joint {j + 1}: {_fmt(v)}" for j, v in enumerate(arr))
    return "; ".join("[" + ", ".join(_fmt(v) for v in row) + "]" for row in arr)


def _pole_rows(poles: Iterable[complex]) -> list[list[str]]:
    rows = []
    for p in sorted((complex(p) for p in poles), key=lambda z: (z.real, z.imag)):
        wn = abs(p)
        rows.append([_fmt(p), _fmt(-p.real / wn, 4) if wn > 0 else "—", _fmt(wn, 4)])
    return rows


def _unit(text: str) -> str:
    return str(text).replace("*", "·")


def design_html(design: Any) -> str:
    """A design as an HTML fragment for Jupyter (no check is run).

    Parameters
    ----------
    design : Design

    Returns
    -------
    str
        One ``<div>``: controller and plant, gains with their units and roles, requested poles
        and zeros (1/s), the achieved closed-loop poles with damping ratio and natural frequency
        (rad/s), the closed loop's inputs, outputs and states, per-joint loops and the notes.
    """
    from designkit.families import FAMILIES

    fam = FAMILIES.get(design.kind)
    label = fam.display.label if fam is not None else design.kind
    parts = ['<div class="designkit-design" style="font-family:sans-serif;line-height:1.35">',
             f'<h3 style="margin:0.2em 0">{_e(label)} ({_e(design.kind)}) on a {_e(design.plant.kind)} plant</h3>',
             _heading("Gains"),
             _table(("Gain", "Value", "Unit", "Meaning"),
                    ([k, _gain_text(v), _unit(design.gains.unit(k)), design.gains.meaning(k)]
                     for k, v in design.gains.items()))]
    if design.poles or design.zeros:
        rows = [["pole", _fmt(p)] for p in design.poles] + [["zero", _fmt(z)] for z in design.zeros]
        parts += [_heading("Requested"), _table(("", "Value (1/s)"), rows)]
    cl = design.closed_loop
    if cl is not None:
        poles = np.linalg.eigvals(np.asarray(cl.A, float))
        abscissa = float(np.max(poles.real)) if poles.size else -math.inf
        stable = "asymptotically stable" if abscissa < 0 else "not asymptotically stable"
        parts += [
            _heading("Nominal closed loop (linearized at the operating point)"),
            _para(f"{len(cl.states)} states ({', '.join(cl.states)}); inputs {', '.join(cl.inputs)}; "
                  f"outputs {', '.join(cl.outputs)}. {stable.capitalize()}: the slowest pole has real part "
                  f"{_fmt(abscissa, 4)} 1/s."),
            _table(("Achieved pole (1/s)", "ζ", "ωn (rad/s)"), _pole_rows(poles)),
        ]
    for name, loop in zip(design.loop_names, design.loops, strict=False):
        if loop.closed_loop is not None:
            parts += [_heading(f"Loop {name}"),
                      _table(("Achieved pole (1/s)", "ζ", "ωn (rad/s)"),
                             _pole_rows(np.linalg.eigvals(np.asarray(loop.closed_loop.A, float))))]
    if design.notes:
        parts.append(_heading("Notes"))
        parts.append("<ul>" + "".join(f"<li>{_e(n)}</li>" for n in design.notes) + "</ul>")
    parts.append(_para("No check has been run on this design: designkit.run(spec) verifies it."))
    parts.append("</div>")
    return "".join(parts)

