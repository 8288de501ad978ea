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
    for member in result.results:  # the members' own studies are tested in tests/studies; the comparison's run here
        member.__dict__["studies"] = ()
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
                  "RMS departure caused by the change", "Lab experiment 2 (notes, appendix A)",
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


def _axes_and_lines(svg: str) -> list[int]:
    """For each axes of an SVG figure, how many controller lines it draws (tagged ``dk-controller``)."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(svg)
    out = []
    for g in root.iter("{http://www.w3.org/2000/svg}g"):
        if re.fullmatch(r"axes_\d+", g.get("id", "")):
            out.append(sum(1 for el in g.iter() if el.get("id", "").startswith("dk-controller")))
    return out


def test_each_controllers_command_has_its_own_panel(written):
    result, _, _ = written
    from designkit.report.comparison_figures import comparison_figures

    figures = {f.filename: f for f in comparison_figures(result)}
    command = figures["comparison-command.svg"]
    assert _axes_and_lines(command.svg) == [1] * len(result.labels)  # one axis per controller, one line each
    assert "one panel per controller" in command.caption
    assert _axes_and_lines(figures["comparison-output.svg"].svg) == [len(result.labels)]  # outputs overlaid
    assert "comparison-load.svg" not in figures  # no load step in this scenario


def test_a_load_step_gets_a_zoom_and_warnings_reach_page_one(tmp_path):
    """A scenario with a load step: the zoom on it; a member's warnings on page 1 of the HTML and the PDF and in
    the CLI summary, labelled by controller."""
    import dataclasses

    from designkit.cli import _comparison_summary
    from designkit.comparison.table import comparison_table
    from designkit.report.comparison_model import build_comparison_model
    from designkit.report.comparison_writer import compile_comparison_pdf, render_comparison_html
    from designkit.verification.check import Check
    from tests.comparison.test_scenario_metrics import STEP_LOAD

    result = run(parse_spec(STEP_LOAD))
    warning = "Weak stability margin at u: gain margin 3.1 dB, below 6 dB"
    warned = dataclasses.replace(result["fast"], checks=(*result["fast"].checks, Check(
        "margins_note", True, required=False, label="A margin note", warnings=(warning,))))
    results = (result["slow"], warned)
    result = dataclasses.replace(result, results=results,
                                 table=comparison_table(result.labels, results, result.unchanged))
    assert result["fast"].warnings[-1] == warning
    model = build_comparison_model(result, provenance=())
    figures = {f.filename: f for f in model.figures}
    load = figures["comparison-load.svg"]
    assert _axes_and_lines(load.svg) == [2] and "dk-load-step" in load.svg
    assert "Zoom on the load step of 0.5 N·m at 2.5 s" in load.caption
    text = _text(render_comparison_html(model))
    first = text[: text.index("Controllers and their verdicts", text.index("Warnings"))]
    assert f"fast: {warning}" in first and "slow:" not in first
    pdf = tmp_path / "report.pdf"
    pdf.write_bytes(compile_comparison_pdf(model))
    pages = pdf_pages(pdf)
    assert "Warnings" in pages[0] and "fast: Weak stability margin at u: gain margin 3.1 dB" in " ".join(
        pages[0].split())
    summary = _comparison_summary(result)
    assert f"  fast: {warning}" in summary
    assert "fast (PID position servo) is verified: all 9 of its checks pass (5 required, 4 informational)." in summary
