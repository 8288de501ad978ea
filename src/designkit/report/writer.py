"""Write a report's HTML and PDF next to each other, atomically.

Both documents are rendered in memory first; only when both succeeded are they written to
temporary files in the destination folder and moved into place with :func:`os.replace`.  A
failure at any point before that leaves an existing report exactly as it was, and no
partially written file is ever visible under the final names.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

from designkit.report.html import render_html
from designkit.report.model import build_report_model
from designkit.report.pdf import compile_pdf

HTML_NAME = "report.html"
PDF_NAME = "report.pdf"


@dataclass(frozen=True)
class ReportFiles:
    """Paths of a written report.

    Parameters
    ----------
    html, pdf : Path
        ``<out_dir>/<spec name>/report.html`` and ``report.pdf``.
    """

    html: Path
    pdf: Path


def _stage(folder: Path, name: str, data: bytes) -> Path:
    """Write ``data`` to a new temporary file in ``folder`` (flushed to disk); return its path.

    The file gets the mode of the report it will replace, or ``0o644`` for a new one
    (``mkstemp`` creates files readable by the owner only).
    """
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            try:
                mode = (folder / name).stat().st_mode & 0o777
            except FileNotFoundError:
                mode = 0o644
            os.fchmod(fh.fileno(), mode)
            os.fsync(fh.fileno())
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return Path(tmp)


def _report_folder(out_dir: Path, name: str) -> Path:
    if not name or name in (".", "..") or "/" in name or "\\" in name or os.sep in name:
        raise ValueError(f"spec name {name!r} cannot be used as a folder name")
    return out_dir / name


def write_report(result, out_dir: str | os.PathLike[str]) -> ReportFiles:
    """Render the report of ``result`` and write ``out_dir/<spec name>/report.{html,pdf}``.

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        The run to report.
    out_dir : path-like
        Report root; created when missing.

    Returns
    -------
    ReportFiles
        Where the two documents were written.
    """
    model = build_report_model(result)
    html = render_html(model).encode("utf-8")
    pdf = compile_pdf(model)
    folder = _report_folder(Path(out_dir), model.name)
    folder.mkdir(parents=True, exist_ok=True)
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
