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
from collections.abc import Sequence
from typing import Any

from designkit.display.design_view import design_html
from designkit.display.html import BANNER as _BANNER
from designkit.display.html import esc as _e
from designkit.display.html import heading as _heading
from designkit.display.html import para as _para
from designkit.display.html import table as _table

__all__ = ["design_html", "result_html"]

_COUNTER = itertools.count(1)


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
