"""Jupyter views (``_repr_html_``) and the example notebook docs/example.ipynb, executed."""

from __future__ import annotations

import dataclasses
import html
from html.parser import HTMLParser
from pathlib import Path

import pytest

import designkit as dk
from designkit.report.model import build_report_model
from designkit.report.notebook import design_html, result_html

ROOT = Path(__file__).resolve().parents[1]
SPECS = ROOT / "specs"
NOTEBOOK = ROOT / "docs" / "example.ipynb"
VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}


class _Structure(HTMLParser):
    """Collects text and checks that every element is closed in order (void and self-closing aside)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.text: list[str] = []
        self.tags: list[str] = []
        self.ids: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self.ids += [v for k, v in attrs if k == "id"]
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.tags.append(tag)
        self.ids += [v for k, v in attrs if k == "id"]

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
            return
        self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)


def _parse(fragment: str) -> _Structure:
    p = _Structure()
    p.feed(fragment)
    p.close()
    assert not p.errors, p.errors[:5]
    assert not p.stack, f"unclosed: {p.stack[:5]}"
    return p


@pytest.fixture(scope="module")
def result():
    return dk.run(dk.load_spec(SPECS / "posspeed-link.yaml"))


@pytest.fixture(scope="module")
def model(result):
    return build_report_model(result, studies=False)


def test_result_view_has_verdict_every_check_and_inline_svg(result, model):
    fragment = result._repr_html_()
    parsed = _parse(fragment)
    text = " ".join(parsed.text)
    assert model.verdict == "VERIFIED" and "VERIFIED" in text
    for check in result.checks:
        assert check.name in text, check.name
    assert parsed.tags.count("svg") == len(model.figures) >= 1
    assert len(parsed.ids) == len(set(parsed.ids)), "duplicate ids in one view"
    for gain in ("K1", "K2", "K3", "K4"):
        assert gain in text
    for row in getattr(model, "compliance", ()):
        assert row.achieved in text


def test_two_views_have_disjoint_ids(model):
    a, b = _parse(result_html(model)), _parse(result_html(model))
    assert a.ids and not set(a.ids) & set(b.ids)


def test_result_view_escapes_text(model):
    evil = dataclasses.replace(model, title="<script>alert(1)</script>", verdict="FAILED: <b>x</b>",
                               description="a & b")
    fragment = result_html(evil, prefix="t-")
    assert "<script>" not in fragment and "<b>x</b>" not in fragment
    text = " ".join(_parse(fragment).text)
    assert "<script>alert(1)</script>" in text and "FAILED: <b>x</b>" in text and "a & b" in text


def test_failed_run_shows_why_and_the_failing_checks():
    failed = dk.run(dk.load_spec(SPECS / "infeasible-requirements.yaml"))
    m = build_report_model(failed, studies=False)
    text = " ".join(_parse(result_html(m)).text)
    assert m.verdict_kind == "failed" and m.verdict in text
    for check in failed.failed:
        assert check.name in text
    if getattr(m, "why", ()):
        assert "Why it failed" in text
        for row in m.why:
            assert row.shortfall in text and row.cause in text


def test_design_view_shows_gains_with_units_and_poles(result):
    design = result.design
    fragment = design._repr_html_()
    text = " ".join(_parse(fragment).text)
    for name, value, unit in (("K1", "50", "N·m/rad"), ("K2", "6.75", "N·m·s/rad"), ("K3", "100", "N·m/(rad·s)"),
                              ("K4", "-0.166667", "s")):
        assert name in text and value in text and unit in text
    for pole in ("-4", "-5", "-20"):
        assert pole in text
    assert "xD" in text and "asymptotically stable" in text.lower()
    assert "No check has been run" in text


def test_design_view_escapes_notes(result):
    design = dataclasses.replace(result.design, notes=("<img src=x onerror=alert(1)>",))
    fragment = design_html(design)
    assert "<img" not in fragment
    assert html.escape("<img src=x onerror=alert(1)>", quote=True) in fragment


def test_example_notebook_executes():
    nbformat = pytest.importorskip("nbformat", reason="nbformat is not installed (pip install -e '.[test]')")
    nbclient = pytest.importorskip("nbclient", reason="nbclient is not installed (pip install -e '.[test]')")
    pytest.importorskip("ipykernel", reason="ipykernel is not installed (pip install -e '.[test]')")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOK.parent)}})
    client.execute()  # raises CellExecutionError on the first failing cell
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    rich = " ".join(str(o.get("data", {}).get("text/html", "")) + str(o.get("text", "")) for o in outputs)
    assert "VERIFIED" in rich
    assert "<svg" in rich
    assert "phase margin" in rich.lower()
