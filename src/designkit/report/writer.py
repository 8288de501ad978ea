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

from designkit import arguments
from designkit.errors import PATH_LIMIT, OutputError, SpecError, shorten
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


MAX_PROCESSES = 256
"""Most processes :func:`write_report` may draw its figures with."""


def _report_folder(out_dir: Path, name: str) -> Path:
    if not name or name in (".", "..") or "/" in name or "\\" in name or os.sep in name:
        raise ValueError(f"spec name {name!r} cannot be used as a folder name")
    return out_dir / name


def _shown(path: Path) -> str:
    return shorten(str(path), PATH_LIMIT)


def _check_destination(out_dir: object, name: str) -> Path:
    """The report folder ``out_dir/name``, checked before anything is rendered; ``OutputError`` when it
    cannot be one (a file in the way, no permission to create it)."""
    out_dir = arguments.path(out_dir, "out_dir", error=OutputError, what="a folder path")
    try:
        folder = _report_folder(out_dir, name)
    except (TypeError, ValueError) as exc:
        raise OutputError("out_dir", str(exc)) from None
    for path in (folder / HTML_NAME, folder / PDF_NAME):
        if path.is_dir():
            raise OutputError("out_dir", f"{_shown(path)} is a folder, a report file cannot replace it")
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent  # the nearest ancestor that exists (a broken symlink counts as missing)
    if existing.exists() and not existing.is_dir():
        raise OutputError("out_dir", f"{_shown(existing)} is an existing file, not a folder; nothing was written")
    if existing.exists() and not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError("out_dir", f"no permission to write in {_shown(existing)}; nothing was written")
    return folder


def write_report(result, out_dir: str | os.PathLike[str], *, processes: int = 1, studies: bool = True) -> ReportFiles:
    """Render the report of ``result`` and write ``out_dir/<spec name>/report.{html,pdf}``.

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        The run to report.
    out_dir : path-like
        Report root; created when missing.
    processes : int
        1 to :data:`MAX_PROCESSES`; 2 draws the figures on two cores (see
        :func:`~designkit.report.model.build_report_model`).
    studies : bool
        Lay out the run's studies (:mod:`designkit.studies`, run on first access); False leaves them out of the
        report (the run's own verdict, checks and figures only).

    Returns
    -------
    ReportFiles
        Where the two documents were written.

    Raises
    ------
    SpecError
        ``result`` is not a :class:`~designkit.pipeline.PipelineResult`.
    OutputError
        ``out_dir`` (or a folder on the way to it) is an existing file, or the report folder cannot
        be created; checked before rendering, nothing is written or overwritten.
    OSError
        Writing failed part-way (e.g. disk full); an existing report is left as it was.
    """
    if not all(hasattr(result, name) for name in ("loaded", "design", "checks", "simulation")):  # a PipelineResult
        raise SpecError("result", f"expected the PipelineResult of designkit.run, got {type(result).__name__}")
    processes = arguments.integer(processes, "processes", low=1, high=MAX_PROCESSES)
    studies = arguments.flag(studies, "studies")
    _check_destination(out_dir, result.loaded.spec.name)  # before the costly rendering
    model = build_report_model(result, processes=processes, studies=studies)
    html = render_html(model).encode("utf-8")
    pdf = compile_pdf(model)
    folder = _check_destination(out_dir, model.name)
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
