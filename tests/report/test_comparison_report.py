"""The comparison report: page 1 verdict and table, overlay figures, the sections, linked per-controller reports."""

from __future__ import annotations

import html as html_lib
import re

import pytest

from designkit.pipeline import run
from designkit.report.comparison_writer import write_comparison_report
from designkit.schema.loader import load_spec, parse_spec
from tests.comparison.test_comparison import EXAMPLE, FAILING
from tests.report.pdf_text import pdf_pages


def _text(html: str) -> str:
    body = re.sub(r"<(svg|style)\b.*?</\1>", " ", html, flags=re.S)
    return re.sub(r"\s+", " ", html_lib.unescape(re.sub(r"<[^>]+>", " ", body)))


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    out = tmp_path_factory.mktemp("cmp")
    result = run(load_spec(EXAMPLE))
    files = write_comparison_report(result, out, processes=1)
    return result, files, out


def test_files_and_per_controller_reports(written):
    result, files, out = written
    assert files.html == out / "mrac-vs-selftune" / "report.html"
    for label in result.labels:
        own = out / "mrac-vs-selftune" / label / "report.html"
        assert own.exists() and (own.parent / "report.pdf").read_bytes().startswith(b"%PDF")
        assert f'href="{label}/report.html"' in files.html.read_text()
    assert files.pdf.read_bytes().startswith(b"%PDF")


def test_html_shows_the_table_figures_and_sections_in_words(written):
    result, files, _ = written
    page = files.html.read_text()
    assert page.count("<svg") == 4  # output, departure, error, command
    text = _text(page)
    body = text[: text.rindex("Appendix A: spec")]
    for words in ("The same metrics for every controller", "re-convergence time after the change",
                  "RMS departure caused by the change", "Lab experiment 2: MRAC against SELFTUNE",
                  "How sensitive is each to an external perturbation?", "What is the influence of the adaptation"):
        assert words in body, words
    table = result.table
    for label in result.labels:  # every value of the table, as formatted, on the page
        for m in table.metrics:
            cell = table.cell(m, table.value(label, m.key)).removesuffix(" " + table.unit_of(m))
            assert cell in body, (label, m.key)
    for identifier in ("rms_error_after", "reconvergence", "self_tuning", r"\bNone\b", r"\bnan\b", r"\binf\b"):
        assert not re.search(identifier, body), identifier


def test_pdf_page_one_has_the_verdict_and_table(written):
    _, files, _ = written
    pages = pdf_pages(files.pdf)
    assert "VERIFIED" in pages[0] and "The same metrics for every controller" in pages[0]
    assert "re-convergence time after the change" in pages[0]
    assert "Departure caused by the plant change" in "\n".join(pages)


def test_a_failing_comparison_says_which_controller_and_why(tmp_path):
    result = run(parse_spec(FAILING))
    assert not result.verified
    files = write_comparison_report(result, tmp_path)
    text = _text(files.html.read_text())
    assert "FAILED: too-fast" in text
    failed = result["too-fast"].failed
    assert failed
    for c in failed:
        assert c.label in text
    assert "1 of 2 controllers verified" in text


def test_poppler_reads_the_comparison_pdf_without_a_message(written, tmp_path):
    import shutil
    import subprocess

    if shutil.which("pdfinfo") is None:
        pytest.skip("poppler-utils (pdfinfo) not installed")
    _, files, _ = written
    done = subprocess.run(["pdfinfo", str(files.pdf)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stderr == "", done.stderr
