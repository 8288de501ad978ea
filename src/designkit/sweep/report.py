"""The sweep report: one model of sentences, tables and figures, written as HTML and as PDF (Typst).

Numbers carry typeset units (N·m, kg·m², rad/s); the verdict says PASS only when every sample met every
requirement and the falsification search broke none, and says FAIL with what failed, in words, otherwise.
"""

from __future__ import annotations

import html
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, unit
from designkit.sweep.figures import WORDS, box_figure, margin_figure, trajectory_figure
from designkit.sweep.margins import REQUIREMENTS

__all__ = ["SweepReport", "build_report", "html_text", "pdf_bytes"]


@dataclass(frozen=True)
class SweepReport:
    """What the report says: title, verdict, sentences, tables ``(header, rows)`` and figures ``(name, svg)``."""

    title: str
    verdict: str
    passed: bool
    sentences: tuple[str, ...]
    tables: tuple[tuple[str, tuple[str, ...], tuple[tuple[str, ...], ...]], ...]
    figures: tuple[tuple[str, str, str], ...]


def _q(value: float | None, u: str) -> str:
    return "undefined" if value is None or not np.isfinite(value) else f"{fmt_number(value)} {unit(u)}".rstrip()


def _named(name: str, value: float, u: str) -> str:
    return f"{name} = {_q(value, u)}"


def _verdict(result: Any) -> tuple[str, tuple[str, ...]]:
    lo, hi = result.confidence
    n, k = result.samples, result.n_passed
    base = (f"{k:,} of {n:,} samples ({100 * k / n:.4g} %) met every requirement; the 95 % Clopper–Pearson "
            f"interval of the pass probability is [{lo:.4g}, {hi:.4g}].")
    said = [base]
    if k < n:
        broken = []
        for r, name in enumerate(result.requirements):
            bad = int(np.count_nonzero(~(np.nan_to_num(result.margin[:, r], nan=-1.0) >= 0)))
            if bad:
                broken.append(f"the {WORDS[name]} in {bad:,}")
        fails = int(np.count_nonzero(result.failed_runs))
        if fails:
            broken.append(f"the integrator stopped early (a diverging loop) in {fails:,}")
        said.append(f"{n - k:,} samples broke a requirement: " + ", ".join(broken) + ".")
    f = result.falsification
    if f is not None:
        where = ", ".join(_named(d.name, float(v), d.unit) for d, v in zip(result.dimensions, f.values,
                                                                              strict=True))
        m = f.margins.get(f.requirement)
        outcome = ("breaks the requirement" if f.broken else "still meets it")
        said.append(f"The falsification search ({f.method}; {f.evaluations} runs) found its worst case at {where}: "
                    f"the {WORDS[f.requirement]} margin there is {_q(m, REQUIREMENTS[f.requirement])}, "
                    + (f"{f.objective:.3g} of the limit" if f.objective > -10 else "at least 10 times the limit "
                       "below it (the search ranks no deeper)") + f", which {outcome}.")
    return ("PASS" if result.verified else "FAIL"), tuple(said)


def build_report(result: Any, prep: Any) -> SweepReport:
    """The report of ``result`` (``prep``: the spec made ready, to re-run the worst samples for their figure)."""
    verdict, said = _verdict(result)
    dist = {"uniform": "uniform on the interval", "normal": f"normal, centred, the half-width "
            f"{prep.space.cut:g} standard deviations, cut at the ends", "corners": "the box's corners in turn"}
    sampled = tuple((d.name, f"[{fmt_number(d.low)}, {fmt_number(d.high)}] {unit(d.unit)}".rstrip(),
                     dist[result.distribution], d.path) for d in result.dimensions)
    if prep.space.noise:
        sampled += (("noise seed", "0 to 2³² − 1", "one per sample", "sweep.noise"),)
    summary = result.requirement_summary()
    req_rows = []
    for name in result.requirements:
        s = summary[name]
        q = s["margin_quantiles"]
        u = REQUIREMENTS[name]
        req_rows.append((WORDS[name], f"≤ {_q(s['limit'], u)}", f"{s['passed']:,} of {result.samples:,}",
                         _q(q["q0"], u), _q(q["q0.01"], u), _q(q["q0.5"], u)))
    worst_rows = []
    for w in result.worst:
        units = {d.name: d.unit for d in result.dimensions}
        where = ", ".join(_named(k, v, units[k]) for k, v in w.values.items())
        bad = min(((k, v) for k, v in w.margins.items()), key=lambda kv: -np.inf if kv[1] is None else
                  kv[1] / result.limits[kv[0]])
        worst_rows.append((str(w.rank), str(w.sample), where or "—", WORDS[bad[0]],
                           _q(bad[1], REQUIREMENTS[bad[0]]), w.spec_file or "—"))
    tables = (
        ("What was sampled", ("quantity", "interval", "distribution", "from"), sampled),
        ("Requirements over the samples", ("requirement", "limit", "met in", "worst margin", "1 % quantile",
                                           "median margin"), tuple(req_rows)),
        ("The worst samples (each a spec that designkit synth re-runs)",
         ("rank", "sample", "values", "worst requirement", "its margin", "spec"), tuple(worst_rows)),
        ("How it ran", ("setting", "value"), tuple((k.replace("_", " "), str(v)) for k, v in result.engine.items())),
    )
    figs = []
    svg = margin_figure(result)
    if svg:
        figs.append(("margins.svg", "Each requirement's margin over the samples (limit minus achieved, in the "
                     "requirement's unit; left of the red line: broken).", svg))
    svg = box_figure(result)
    if svg:
        figs.append(("box.svg", "The samples over the box: met every requirement (blue) or broke one (red).", svg))
    svg = _worst_runs(result, prep)
    if svg:
        figs.append(("worst.svg", "The worst samples' runs (tracked position against the reference).", svg))
    return SweepReport(title=f"Sweep of {result.name}", verdict=verdict, passed=verdict == "PASS", sentences=said,
                       tables=tables, figures=tuple(figs))


def _worst_runs(result: Any, prep: Any) -> str | None:
    from designkit.sweep.chunk import _inputs

    picks = [(f"sample {w.sample}", result.values[list(result.index).index(w.sample)], w.noise_seed or -1)
             for w in result.worst[:3]]
    if result.falsification is not None:
        picks.append(("falsification's worst", result.falsification.values, result.falsification.noise_seed))
    if not picks:
        return None
    vals = np.stack([p[1] for p in picks])
    seeds = np.array([p[2] for p in picks])
    runs = []
    for a in range(0, len(picks), prep.batch.batch):
        rec = prep.batch.run(**_inputs(prep, vals[a:a + prep.batch.batch], seeds[a:a + prep.batch.batch]))
        for i in range(rec.size):
            runs.append((picks[a + i][0], rec.tracked[i], rec.desired[i]))
    units = "m" if prep.design.motion is not None and "m" in getattr(prep.design.motion.space, "units", ()) else "rad"
    return trajectory_figure(np.asarray(prep.simulator.time), runs, units)


def html_text(rep: SweepReport) -> str:
    """The report as one self-contained HTML page (figures inline as SVG)."""
    e = html.escape
    parts = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>", f"<title>{e(rep.title)}</title>",
             "<style>body{font-family:'DejaVu Sans',Arial,sans-serif;max-width:60em;margin:2em auto;}"
             "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:.25em .6em;"
             "text-align:left}.PASS{color:#1e7d32}.FAIL{color:#c0392b}</style></head><body>",
             f"<h1>{e(rep.title)}</h1>", f"<p class='{rep.verdict}'><strong>{rep.verdict}</strong></p>"]
    parts += [f"<p>{e(s)}</p>" for s in rep.sentences]
    for title, header, rows in rep.tables:
        parts.append(f"<h2>{e(title)}</h2><table><tr>" + "".join(f"<th>{e(h)}</th>" for h in header) + "</tr>")
        parts += ["<tr>" + "".join(f"<td>{e(c)}</td>" for c in row) + "</tr>" for row in rows]
        parts.append("</table>")
    for _, caption, svg in rep.figures:
        parts.append(f"<figure>{svg}<figcaption>{e(caption)}</figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts)


def typst_source(rep: SweepReport) -> str:
    """The report as Typst markup (figures referenced by file name)."""
    from designkit.report.pdf import escape_typst as t

    out = ['#set page(paper: "a4", margin: 2cm)', '#set text(font: "DejaVu Sans", size: 9pt)',
           f"= {t(rep.title)}", "", f"*{rep.verdict}*", ""]
    out += [t(s) + "\n" for s in rep.sentences]
    for title, header, rows in rep.tables:
        cells = ", ".join(f"[*{t(h)}*]" for h in header)
        body = ", ".join(f"[{t(c)}]" for row in rows for c in row)
        out += [f"== {t(title)}", f"#table(columns: {len(header)}, {cells}" + (f", {body}" if body else "") + ")", ""]
    for name, caption, _ in rep.figures:
        out.append(f'#figure(image("{name}", width: 100%), caption: [{t(caption)}])')
    return "\n".join(out)


def pdf_bytes(rep: SweepReport) -> bytes:
    """The report compiled to PDF by Typst (the figures' DejaVu Sans embedded, no system fonts)."""
    import tempfile
    from pathlib import Path

    import typst

    from designkit.report.pdf import figure_font_dir

    with tempfile.TemporaryDirectory(prefix="designkit-sweep-") as tmp:
        root = Path(tmp)
        fonts = figure_font_dir(root)
        for name, _, svg in rep.figures:
            (root / name).write_text(svg, encoding="utf-8")
        main = root / "report.typ"
        main.write_text(typst_source(rep), encoding="utf-8")
        pdf = typst.compile(str(main), root=str(root), font_paths=[str(fonts)], ignore_system_fonts=True)
    if not isinstance(pdf, bytes) or not pdf.startswith(b"%PDF"):
        raise RuntimeError("typst did not return a PDF document")
    return pdf
