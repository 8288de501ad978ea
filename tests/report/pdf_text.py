"""Text of a PDF's pages for the report tests: ``pdftotext`` (poppler-utils) when on PATH, else pypdf
(in the test extra, so CI reads the PDFs too); skips with the reason when neither is available."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest


def pdf_pages(path: Path) -> list[str]:
    """The text of every page of the PDF at ``path``, in order."""
    if shutil.which("pdftotext"):
        out = subprocess.run(["pdftotext", "-enc", "UTF-8", str(path), "-"], capture_output=True, check=True,
                             text=True).stdout
        pages = out.split("\f")
        return pages[:-1] if pages and not pages[-1].strip() else pages
    try:
        import pypdf
    except ImportError:
        pytest.skip("neither pdftotext (poppler-utils) nor pypdf is installed: cannot read the PDF's text")
    return [page.extract_text() or "" for page in pypdf.PdfReader(str(path)).pages]


def pdf_text(path: Path) -> str:
    """The text of the whole PDF at ``path``."""
    return "\n".join(pdf_pages(path))
