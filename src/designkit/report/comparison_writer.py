"""Write a comparison report: ``<out>/<name>/report.{html,pdf}`` and each controller's own report beside it.

Each controller's report is the single-spec report of its run (:func:`designkit.report.write_report`),
written to ``<out>/<name>/<label>/``; the comparison's HTML and PDF are rendered in memory first and moved
into place as the single-spec writer does (:mod:`designkit.report.writer`).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from markupsafe import Markup

from designkit.errors import OutputError, SpecError
from designkit.report.comparison_model import ComparisonReportModel, build_comparison_model
from designkit.report.writer import HTML_NAME, PDF_NAME, ReportFiles, _check_destination, _shown, _stage, write_report

__all__ = ["render_comparison_html", "render_comparison_typst", "write_comparison_report"]


def render_comparison_html(model: ComparisonReportModel) -> str:
    """The comparison report as one self-contained HTML document."""
    from designkit.report import html

    figures = [{"title": f.title, "caption": f.caption, "anchor": f.anchor,
                "svg": Markup(html.inline_svg(f.svg, f"f{k}-", title=f.title))}
               for k, f in enumerate(model.figures, start=1)]
    return html._environment().get_template("comparison.html.j2").render(m=model, figures=figures)


def render_comparison_typst(model: ComparisonReportModel) -> str:
    """The Typst source of the comparison report; figures are referenced by ``Figure.filename``."""
    from designkit.report import pdf

    return pdf._environment().get_template("comparison.typ.j2").render(m=model)


def compile_comparison_pdf(model: ComparisonReportModel) -> bytes:
    """Compile the comparison report to PDF bytes (the fonts of :func:`designkit.report.pdf.compile_pdf`)."""
    import tempfile

    import typst

    from designkit.report.pdf import figure_font_dir, without_false_suspects

    source = render_comparison_typst(model)
    with tempfile.TemporaryDirectory(prefix="designkit-comparison-") as tmp:
        root = Path(tmp)
        fonts = figure_font_dir(root)
        for fig in model.figures:
            (root / fig.filename).write_text(fig.svg, encoding="utf-8")
        main = root / "report.typ"
        main.write_text(source, encoding="utf-8")
        try:
            out = typst.compile(str(main), root=str(root), font_paths=[str(fonts)], ignore_system_fonts=True)
        except typst.TypstError as exc:  # user text is escaped, so this is a designkit bug
            detail = getattr(exc, "diagnostic", "") or str(exc)
            raise RuntimeError(f"typst could not compile the comparison report: {detail}") from exc
    if not isinstance(out, bytes) or not out.startswith(b"%PDF"):
        raise RuntimeError("typst did not return a PDF document")
    return without_false_suspects(out)  # poppler reads Typst's /Suspects false as a syntax error


def write_comparison_report(result, out_dir: str | os.PathLike[str], *, processes: int = 1,
                            studies: bool = True) -> ReportFiles:
    """Write the comparison report of ``result`` and every controller's own report.

    Parameters
    ----------
    result : designkit.pipeline.ComparisonResult
        The comparison to report.
    out_dir : path-like
        Report root: the comparison goes to ``out_dir/<spec name>/report.{html,pdf}``, controller ``label``'s
        own report to ``out_dir/<spec name>/<label>/report.{html,pdf}``.
    processes : int
        Passed to each controller's report (2 draws its figures on two cores).
    studies : bool
        Lay out the comparison studies and each controller's own studies (:mod:`designkit.studies`, run on first
        access); False leaves them out.

    Returns
    -------
    ReportFiles
        The comparison report's two files.

    Raises
    ------
    SpecError
        ``result`` is not a comparison result.
    OutputError
        ``out_dir`` cannot hold the reports (checked before rendering).
    """
    if not all(hasattr(result, name) for name in ("loaded", "labels", "results", "table")):
        raise SpecError("result", f"expected the ComparisonResult of designkit.run, got {type(result).__name__}")
    folder = _check_destination(out_dir, result.loaded.spec.name)
    model = build_comparison_model(result, studies=studies)
    html = render_comparison_html(model).encode("utf-8")
    pdf = compile_comparison_pdf(model)
    for member in result.results:
        write_report(member, folder, processes=processes, studies=studies)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError("out_dir", f"cannot create the folder {_shown(folder)}: {exc.strerror or exc}; "
                          "nothing was written") from None
    files = ReportFiles(html=folder / HTML_NAME, pdf=folder / PDF_NAME)
    staged: list[Path] = []
    try:
        staged.append(_stage(folder, HTML_NAME, html))
        staged.append(_stage(folder, PDF_NAME, pdf))
        os.replace(staged[0], files.html)
        os.replace(staged[1], files.pdf)
    finally:
        for tmp in staged:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()
    return files


