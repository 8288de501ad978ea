"""Reports of real pipeline runs (synthesis, simulation and verification of the shipped specs)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from html import unescape
from pathlib import Path

import pytest

from designkit.pipeline import run
from designkit.report import build_report_model, write_report
from designkit.schema.loader import load_spec
from tests.report.pdf_text import pdf_pages, pdf_text

SPECS = Path(__file__).resolve().parents[2] / "specs"


@pytest.mark.parametrize("name", ["posspeed-perturbation", "tracking-pid", "posspeed-relay"])
def test_report_of_a_real_run(name, tmp_path):
    path = SPECS / f"{name}.yaml"
    if not path.exists():
        pytest.skip(f"{path.name} not shipped")
    result = run(load_spec(path))
    model = build_report_model(result, studies=False)
    assert model.verified == result.verified
    if result.verified:
        assert model.verdict == "VERIFIED"
    else:
        assert model.verdict.startswith(("FAILED: ", "UNDECIDED: "))
    assert [c.name for c in model.checks] == [c.name for c in result.checks]
    assert {f.filename for f in model.figures} >= {"fig-pole-zero.svg", "fig-linear-response.svg",
                                                   "fig-loop-bode.svg", "fig-simulation.svg"}
    files = write_report(result, tmp_path, studies=False)
    html = files.html.read_text(encoding="utf-8")
    assert "http" not in html and "src=" not in html
    from designkit.report.labels import check_label

    for check in result.checks:
        assert check_label(check) in html
        assert f'<span class="badge {check.status}">{check.status}</span>' in html
    assert files.pdf.read_bytes().startswith(b"%PDF")


# ----------------------------------------------------------------------------- no raw representations

EXAMPLES = ("posspeed-link", "posspeed-relay", "infeasible-requirements", "tracking-pid")
# Python notation that must never reach a reader: empty containers, nested lists, complex numbers with a
# trailing j, "ignored []"-style empty lists, dict reprs, dotted internal keys of certificates
RAW = {
    "empty container": re.compile(r"\{\}|\[\]|\(\)"),
    "nested list": re.compile(r"\[\[\s*-?\d"),
    "Python complex": re.compile(r"\d\s*[+-]\s*\d+(?:\.\d+)?j\b"),
    "dict repr": re.compile(r"\{'\w+':\s"),
    # certificate keys flattened with dots (a spec path such as simulation.anti_windup is the user's own YAML)
    "dotted internal key": re.compile(r"\b[a-z]+(?:_[a-z0-9]+)+\.[a-z0-9_]+\b|\b[a-z_]+\.\d+\.[a-z_]+\b"),
    "None/True/False": re.compile(r"\b(?:None|True|False)\b"),
}


@pytest.fixture(scope="module")
def example_reports(tmp_path_factory):
    """The four example specs run once, their reports written (a few seconds each)."""
    from designkit.report.provenance import STABLE_ENV

    out = tmp_path_factory.mktemp("examples")
    reports = {}
    saved = os.environ.get(STABLE_ENV)
    os.environ[STABLE_ENV] = "stable"  # the command line is pytest's here: not part of what is scanned
    try:
        for name in EXAMPLES:
            result = run(load_spec(SPECS / f"{name}.yaml"))
            files = write_report(result, out, studies=False)
            reports[name] = (result, build_report_model(result, studies=False), files)
    finally:
        if saved is None:
            os.environ.pop(STABLE_ENV, None)
        else:
            os.environ[STABLE_ENV] = saved
    return reports


def _html_text(html: str) -> str:
    html = re.sub(r"<style>.*?</style>|<svg.*?</svg>|<pre class=\"spec\">.*?</pre>", " ", html, flags=re.S)
    html = re.sub(r'alttext="[^"]*"', "", html)
    return unescape(re.sub(r"<[^>]+>", " ", html))


def _pdf_text(path: Path) -> str:
    text = pdf_text(path)
    return text.split("Appendix C: spec")[0] + text.split("Appendix D: provenance")[-1]  # not the echoed YAML


def _raw(text: str) -> list[str]:
    return [f"{what}: {m.group(0)!r} in …{text[max(0, m.start() - 60):m.end() + 20]!r}"
            for what, rx in RAW.items() for m in rx.finditer(text)]


@pytest.mark.parametrize("name", EXAMPLES)
def test_html_has_no_raw_python_representation(example_reports, name):
    _, _, files = example_reports[name]
    text = _html_text(files.html.read_text(encoding="utf-8"))
    assert _raw(text) == []
    assert "N*m" not in text  # one way to write the unit


@pytest.mark.parametrize("name", EXAMPLES)
def test_pdf_has_no_raw_python_representation(example_reports, name):
    _, _, files = example_reports[name]
    text = _pdf_text(files.pdf)
    assert _raw(text) == []
    assert "N*m" not in text


def test_the_raw_patterns_do_catch_python_notation():
    for sample in ("ignored []", "{}", "[[-20, -5, -4]]", "-15.5423 - 15.7453j", "{'kind': 'x'}",
                   "loops.0.gain_margin", "steady_state.window_s", "None"):
        assert _raw(sample), sample


@pytest.mark.parametrize("name", ["infeasible-requirements", "posspeed-relay"])
def test_failing_report_says_why_on_its_first_page(example_reports, name):
    result, model, files = example_reports[name]
    assert not result.verified and model.why
    page1 = pdf_pages(files.pdf)[0]
    flat = " ".join(page1.split())
    assert "Why it failed" in flat and "Requirement compliance" in flat
    for row in model.why:
        assert row.label in flat
        assert " ".join(row.shortfall.split()) in flat
        if row.shortfall_percent:
            assert row.shortfall_percent in flat
        if row.cause:
            assert " ".join(row.cause.split())[:40] in flat


def test_diverging_run_is_called_diverging(example_reports):
    _, model, files = example_reports["infeasible-requirements"]
    if not model.divergence:
        pytest.skip("no diagnosis of divergence available (designkit.analysis.diagnosis)")
    html = files.html.read_text(encoding="utf-8")
    assert html.index("diverges") < html.index('id="compliance"')
    over = next(r for r in model.why if r.check == "overshoot")
    assert over.achieved == "168.6 %" and over.shortfall == "163.6 %" and over.shortfall_percent == "3270 %"


@pytest.mark.parametrize("name", EXAMPLES)
def test_no_near_empty_page(example_reports, name):
    _, _, files = example_reports[name]
    if shutil.which("pdftotext") is None or shutil.which("pdfinfo") is None:
        pytest.skip("pdftotext/pdfinfo (poppler-utils) are not on PATH")
    info = subprocess.run(["pdfinfo", str(files.pdf)], capture_output=True, text=True, check=True).stdout
    pages = int(re.search(r"Pages:\s+(\d+)", info).group(1))
    for page in range(1, pages):  # the last page may be short
        text = subprocess.run(["pdftotext", "-f", str(page), "-l", str(page), "-layout", str(files.pdf), "-"],
                              capture_output=True, text=True, check=True).stdout
        lines = [line for line in text.splitlines() if line.strip()]
        assert len(lines) >= 12, f"page {page} of {pages} is nearly empty: {lines}"
