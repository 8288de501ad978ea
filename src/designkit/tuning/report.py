"""The tuning's files: the tuned spec (``<name>-tuned.yaml``) and its report, as HTML (``<name>-tuning.html``) and as
PDF through Typst (``<name>-tuning.pdf``), the same blocks in both.

The report says, in this order: the verdict; the requirements' worst normalised margins over the box before and
after, and which one is active (limits the design); the tuned values beside the initial ones, with their ranges;
the method (and why it was chosen), iterations, candidates, simulations and time; the convergence history as a
figure; the confirming sweep of the box (pass fraction, samples, worst sample); the trade-off along the final
direction as a figure with its table; the conflict and the minimum-time bound when no tuning met every requirement;
and the tuned spec's checks (its full verify).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["blocks", "convergence_svg", "html_text", "pdf_bytes", "summary_lines", "typst_source", "write_files"]


def _value(v: Any) -> str:
    arr = np.asarray(v)
    if arr.ndim == 0:
        z = arr.item()
        if isinstance(z, complex):
            return f"{z.real:.4g}{z.imag:+.4g}j" if z.imag else f"{z.real:.4g}"
        return f"{float(z):.4g}"
    return "[" + ", ".join(_value(e) for e in arr) + "]"


def _achieved(check: Any) -> str:
    value = check.achieved
    if value is None:
        return ""
    text = f"{value:.4g}" if isinstance(value, float) else str(value)
    return f"{text} {check.unit}".strip()


def convergence_svg(result: Any) -> str:
    """The best score after each candidate, and each candidate's score (SVG)."""
    from designkit.display.svg import new_figure, tag, to_svg

    hist = result.search.history
    fig, (ax,) = new_figure(6.4, 3.0)
    k = np.arange(1, len(hist) + 1)
    shown = np.maximum(hist[:, 0], -1.5) if len(hist) else hist[:, 0]
    (dots,) = ax.plot(k, shown, ".", color="#9aa7b8", markersize=3, label="candidate (below −1.5 drawn at −1.5)")
    (line,) = ax.plot(k, hist[:, 1], "-", color="#1f4e8c", linewidth=1.6, label="best so far")
    zero = ax.axhline(0.0, color="#b3261e", linewidth=0.8, linestyle="--", label="every requirement met")
    tag(fig, "candidates", dots)
    tag(fig, "best", line)
    tag(fig, "met", zero)
    ax.set_xlabel("candidate")
    ax.set_ylabel("worst normalised margin")
    ax.legend(loc="lower right", fontsize=7)
    return to_svg(fig)


def _svg(draw: Any, *args: Any) -> str:
    """``draw(*args)`` under the figures' style: DejaVu Sans, the text kept as SVG text (searchable in the HTML and
    in the PDF, which embeds the font)."""
    import matplotlib

    from designkit.display.svg import RC_PARAMS

    with matplotlib.rc_context(RC_PARAMS):
        return draw(*args)


def blocks(result: Any) -> list[tuple[Any, ...]]:
    """The report's content, in order, for both renderings: ``("p", text)``, ``("h", text)``, ``("table", header,
    rows, status column or None)``, ``("figure", file name, svg)``."""
    best, initial, s = result.best, result.initial, result.search
    if result.verified:
        verdict = (f"TUNED AND VERIFIED: every requirement holds at the {1 + len(result.points)} plants run, with a "
                   f"worst normalised margin of {best.score:.3g}, and the tuned spec's full verify passes.")
    elif result.met:
        verdict = "TUNED, NOT VERIFIED: the tuned spec's full verify fails " + ", ".join(
            c.name for c in result.verify.failed) + "."
    else:
        verdict = f"NOT MET: no tuning found meets every requirement; the best compromise scores {best.score:.3g}."
    out: list[tuple[Any, ...]] = [("p", verdict), ("h", "Requirements: worst normalised margin over the box")]
    rows = []
    for req in best.margins:
        where = best.worst_point.get(req) or {}
        rows.append((req, f"{initial.margins.get(req, float('nan')):.3g}", f"{best.margins[req]:.3g}",
                     ", ".join(f"{k} = {v:.4g}" for k, v in where.items()) or "nominal",
                     "active" if req == best.active else ""))
    out.append(("table", ("requirement", "initial", "tuned", "worst at", ""), rows, None))
    out.append(("p", "A normalised margin is the check's margin over the requirement's limit (1: the whole limit "
                     "to spare; negative: the requirement fails). The active requirement limits the design."))
    out.append(("h", "Tuned values"))
    out.append(("table", ("knob", "initial", "tuned"), [(k, _value(initial.values[k]), _value(best.values[k]))
                                                       for k in best.values], None))
    out.append(("table", ("coordinate", "unit", "range", "initial", "tuned"), [
        (c.label, c.unit, f"[{c.low:.4g}, {c.high:.4g}]", f"{c.initial:.4g}",
         f"{float(np.exp(np.clip(x, np.log(c.low), np.log(c.high)))):.4g}")
        for c, x in zip(result.space.coordinates, best.x, strict=True)], None))
    if result.at_bounds:
        out.append(("p", "At an end of its range (the range, not a requirement, stops the design there; widen "
                         "tune.ranges to go further): " + ", ".join(result.at_bounds) + "."))
    out += [("p", "Not tuned: " + k) for k in result.space.kept]
    out.append(("h", "Search"))
    sens = (f" ({s.sensitivity_runs} of them runs with the forward sensitivities)" if s.sensitivity_runs else "")
    out.append(("p", f"{s.method}: {s.iterations} iterations, {s.restarts} restarts, {len(s.evaluations)} "
                     f"candidates, {s.simulations} simulations{sens}, {s.seconds:.1f} s ({s.stopped}). Every "
                     f"candidate's requirement checks were measured at the nominal plant and at {len(result.points)} "
                     "other points of the box; every candidate that could become the best also ran through the "
                     "family's own run with every check (its certificates)."))
    if result.choice:
        out.append(("p", f"Why this search: {result.choice}."))
    out.append(("figure", "convergence.svg", _svg(convergence_svg, result)))
    out += _sweep_part(result)
    out += _trade_part(result)
    if result.conflict is not None:
        out.append(("h", "Why no tuning meets every requirement"))
        out.append(("p", result.conflict.sentence))
        out.append(("table", ("requirement", "best alone", "at the compromise"), [
            (r, f"{result.conflict.alone[r]:.3g}", f"{result.conflict.compromise[r]:.3g}")
            for r in result.conflict.alone], None))
    if result.bound is not None:
        out += [("h", "Minimum-time bound of the actuator"), ("p", result.bound.sentence)]
    if not best.certified and best.failed:
        out.append(("p", "The best candidate's certificates that fail: " + ", ".join(best.failed)))
    if result.verify is not None:
        out.append(("h", "The tuned spec's checks (designkit verify)"))
        out.append(("table", ("check", "status", "achieved", "target", "margin"), [
            (c.name, c.status, _achieved(c), c.target,
             "" if c.margin is None else f"{c.margin:.4g}") for c in result.verify.checks], 1))
    return out


def html_text(result: Any) -> str:
    """The report as one HTML page."""
    from designkit.display.html import esc, heading, para, table

    name = result.loaded.spec.name
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{esc(name)}: tuning</title></head>"
             "<body style='font-family:sans-serif;max-width:60em;margin:1em auto'>",
             f"<h2>{esc(name)}: tuning</h2>"]
    for b in blocks(result):
        if b[0] == "p":
            parts.append(para(b[1]))
        elif b[0] == "h":
            parts.append(heading(b[1]))
        elif b[0] == "table":
            parts.append(table(b[1], b[2], status_column=b[3]))
        else:
            parts.append(b[2])
    parts.append("</body></html>")
    return "\n".join(parts)


def typst_source(result: Any) -> str:
    """The report as Typst markup, the same blocks as the HTML page (figures referenced by file name)."""
    from designkit.report.pdf import escape_typst as t
    from designkit.report.pdf import typst_string

    title = f"{result.loaded.spec.name}: tuning"
    out = [f'#set document(title: {typst_string(title)}, author: "designkit", date: none)',
           '#set page(paper: "a4", margin: 2cm)', '#set text(font: "DejaVu Sans", size: 9pt)',
           f"= {t(title)}", ""]
    for b in blocks(result):
        if b[0] == "p":
            out += [t(b[1]), ""]
        elif b[0] == "h":
            out += [f"== {t(b[1])}", ""]
        elif b[0] == "table":
            cells = ", ".join(f"[*{t(h)}*]" for h in b[1])
            body = ", ".join(f"[{t(c)}]" for row in b[2] for c in row)
            out += [f"#table(columns: {len(b[1])}, {cells}" + (f", {body}" if body else "") + ")", ""]
        else:
            out += [f'#image("{b[1]}", width: 100%)', ""]
    return "\n".join(out)


def pdf_bytes(result: Any) -> bytes:
    """The report compiled to PDF by Typst (the figures' DejaVu Sans embedded, no system fonts, no date: the same
    result gives the same bytes)."""
    import tempfile

    import typst

    from designkit.report.pdf import figure_font_dir, without_false_suspects

    with tempfile.TemporaryDirectory(prefix="designkit-tuning-") as tmp:
        root = Path(tmp)
        fonts = figure_font_dir(root)
        for b in blocks(result):
            if b[0] == "figure":
                (root / b[1]).write_text(b[2], encoding="utf-8")
        main = root / "report.typ"
        main.write_text(typst_source(result), encoding="utf-8")
        pdf = typst.compile(str(main), root=str(root), font_paths=[str(fonts)], ignore_system_fonts=True)
    if not isinstance(pdf, bytes) or not pdf.startswith(b"%PDF"):
        raise RuntimeError("typst did not return a PDF document")
    return without_false_suspects(pdf)


def summary_lines(result: Any) -> list[str]:
    """The confirming sweep and the trade-off as the command line prints them."""
    lines = []
    if result.confirmation is not None:
        lines.append("sweep: " + result.confirmation.sentence)
    t = result.trade
    if t is not None:
        lines.append("trade-off along the final direction (worst normalised margin at steps "
                     + ", ".join(f"{s:g}" for s in t.steps) + "; 0 initial, 1 tuned):")
        for k, m in t.margins.items():
            lines.append(f"  {k}: " + ", ".join("-" if not np.isfinite(v) else f"{v:.3g}" for v in m))
    return lines


def _sweep_part(result: Any) -> list[tuple[Any, ...]]:
    """The confirming sweep: its sentence and, when it ran, the worst sample's margins."""
    c = result.confirmation
    if c is None:
        return []
    parts: list[tuple[Any, ...]] = [("h", "Confirming sweep of the box (designkit sweep)"), ("p", c.sentence + ".")]
    if c.refused is None:
        parts.append(("p", "Samples drawn uniformly over plant.uncertainty by the sweep's own seeded sampling, each "
                           "run through the sweep's batched kernel and scored on every time-domain requirement; "
                           "the box points the search ran are not among them."))
        if c.worst:
            parts.append(("table", ("requirement", "margin at the worst sample"), [
                (k, "undefined" if v is None else f"{v:.4g}") for k, v in c.worst["margins"].items()], None))
    return parts


def _trade_part(result: Any) -> list[tuple[Any, ...]]:
    """The trade-off along the final direction: figure, caption and table."""
    from designkit.tuning.trade import trade_svg

    t = result.trade
    if t is None:
        return []
    names = list(t.margins)
    rows = [(f"{s:+.2f}" + (" (clipped)" if c else ""),
             *("" if not np.isfinite(t.margins[k][i]) else f"{t.margins[k][i]:.3g}" for k in names),
             t.failed[i]) for i, (s, c) in enumerate(zip(t.steps, t.clipped, strict=True))]
    return [("h", "Trade-off along the final direction"), ("figure", "trade-off.svg", _svg(trade_svg, t)),
            ("p", "Each requirement's worst normalised margin over the box's points (the nominal plant and the "
                  f"{len(result.points)} points the search ran), measured by the family's own runs at "
                  f"{len(t.steps)} points on the straight line, in the tuner's log coordinates, from the spec's own "
                  "values (step 0) to the tuned values (step 1), extended a quarter beyond each end; a point "
                  "outside the coordinates' ranges is clipped to them. Margins below −3 are drawn at −3; a point "
                  "the family refuses or whose loop diverges is marked ×. Certificates are not run here."),
            ("table", ("step", *names, "not measured"), rows, None)]


def write_files(result: Any, out: Path) -> Any:
    """Write the tuned spec and the report into ``out`` (created if needed); the result with ``files`` set.

    Raises
    ------
    OutputError
        ``out`` cannot be written.
    """
    from designkit.errors import OutputError

    name = result.loaded.spec.name
    try:
        out.mkdir(parents=True, exist_ok=True)
        spec_file = out / f"{name}-tuned.yaml"
        html_file = out / f"{name}-tuning.html"
        pdf_file = out / f"{name}-tuning.pdf"
        spec_file.write_text(result.tuned.text, encoding="utf-8")
        html_file.write_text(html_text(result), encoding="utf-8")
        pdf_file.write_bytes(pdf_bytes(result))
    except OSError as exc:
        raise OutputError("out", f"cannot write the tuning's files: {exc.strerror or exc}") from None
    return dataclasses.replace(result, files={"spec": spec_file, "html": html_file, "pdf": pdf_file})
