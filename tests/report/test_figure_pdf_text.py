"""Figure text in the PDF: SVG <text> stays text (searchable) and DejaVu Sans is embedded."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from designkit.report.pdf import compile_pdf


def pdf_text(pdf: bytes, tmp_path) -> str:
    """The text of a PDF: ``pdftotext`` when installed, else pypdf; skips (with the reason) without either."""
    if shutil.which("pdftotext"):
        path = tmp_path / "report.pdf"
        path.write_bytes(pdf)
        return subprocess.run(["pdftotext", "-enc", "UTF-8", str(path), "-"], check=True, capture_output=True,
                              text=True, encoding="utf-8").stdout
    try:
        import io

        import pypdf
    except ImportError:
        pytest.skip("neither pdftotext (poppler-utils) nor pypdf is installed: cannot read the PDF's text")
    return "\n".join(page.extract_text() or "" for page in pypdf.PdfReader(io.BytesIO(pdf)).pages)


@pytest.fixture(scope="module")
def servo_pdf(servo_model) -> bytes:
    return compile_pdf(servo_model)


def test_figure_axis_labels_are_text_in_the_pdf(servo_pdf, tmp_path):
    text = pdf_text(servo_pdf, tmp_path)
    for label in ("Re s (1/s)", "Im s (rad/s)", "control (N·m)", "ω (rad/s)"):
        assert label in text, label


def test_dejavu_sans_is_embedded(servo_pdf):
    if shutil.which("pdffonts") is None:  # the bytes: a Type0 font on a DejaVu Sans subset with its font file
        assert re.search(rb"/BaseFont\s*/[A-Z]{6}\+DejaVuSans[/>\s]", servo_pdf)
        assert b"/FontFile2" in servo_pdf
        return
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "report.pdf"
        path.write_bytes(servo_pdf)
        rows = subprocess.run(["pdffonts", str(path)], check=True, capture_output=True, text=True).stdout
    dejavu = [r.split() for r in rows.splitlines() if re.match(r"[A-Z]{6}\+DejaVuSans\s", r)]
    assert dejavu and all(r[-5] == "yes" for r in dejavu)  # the "emb" column
