"""Layout: responsive tables, print colours, table of contents; figure text size at 420 px from the SVG; and,
in headless Chromium when present, nothing clipped or scrolled at 1280 px and 420 px."""

from __future__ import annotations

import dataclasses
import re

import pytest

from designkit.display.section import Question, ReportSection, Table
from designkit.report.html import render_html
from designkit.report.model import build_report_model
from designkit.verification.check import Check
from tests.report.browser import SKIP_REASON, browser, measure
from tests.report.conftest import make_result, servo_checks


@pytest.fixture(scope="module")
def failed_html(failed_result) -> str:
    return render_html(build_report_model(failed_result, studies=False))


def _css(html: str) -> str:
    return re.search(r"<style>(.*?)</style>", html, flags=re.S).group(1)


def test_narrow_screens_stack_the_tables(failed_html):
    css = _css(failed_html)
    narrow = re.search(r"@media \(max-width: (\d+)px\) \{(.*?)\n\}", css, flags=re.S)
    assert narrow is not None and int(narrow.group(1)) >= 768  # 768 px already gets the stacked layout
    rules = narrow.group(2)
    assert "table.stack thead { display: none; }" in rules.replace("colgroup, table.stack ", "")
    assert "content: attr(data-label)" in rules
    for table in ("why stack", "compliance stack", "checks stack"):
        assert f'<table class="{table}">' in failed_html


def test_every_cell_of_a_stacked_table_has_its_label(failed_html):
    for table in re.findall(r'<table class="[^"]*\bstack\b[^"]*">.*?</table>', failed_html, flags=re.S):
        if "equations" in table.split(">", 1)[0]:
            continue
        for row in re.findall(r"<tr class=\"check[^>]*>(.*?)</tr>", table, flags=re.S):
            cells = re.findall(r"<td([^>]*)>", row)
            assert cells and all("data-label=" in c for c in cells), row[:200]


def test_print_keeps_the_status_colours(failed_html):
    css = _css(failed_html)
    printing = css[css.index("@media print"):]
    assert "print-color-adjust: exact" in printing and ".badge" in printing
    assert "thead { display: table-header-group; }" in printing  # header repeated on each printed page
    assert "break-after: avoid" in printing  # headings kept with their content


def test_table_of_contents(failed_html):
    nav = re.search(r'<nav class="toc"[^>]*>.*?</nav>', failed_html, flags=re.S)
    assert nav is not None
    anchors = re.findall(r'href="#([^"]+)"', nav.group(0))
    assert anchors[:2] == ["why", "compliance"]
    for anchor in anchors:
        assert f'id="{anchor}"' in failed_html


def _px(css: str, pattern: str) -> float:
    found = re.search(pattern, css, flags=re.S)
    assert found is not None, pattern
    return float(found.group(1))


def _figure_widths(html: str) -> tuple[float, float]:
    """The widths (CSS px) a figure is drawn at in a 1280 px and a 420 px window, read from the report's CSS:
    the column (``main`` max-width less its padding, or the window less the narrow padding), capped by the
    figure's max-width."""
    css = _css(html)
    cap = _px(css, r"figure \.figure-svg \{[^}]*max-width: (\d+)px")
    column = (_px(css, r"main \{ max-width: (\d+)px")
              - 2 * _px(css, r"main \{ max-width: \d+px; margin: 0 auto; padding: 0 (\d+)px"))
    narrow = 420 - 2 * _px(css, r"@media \(max-width: 820px\) \{\s*main \{ padding: 0 (\d+)px")
    return min(cap, column), min(cap, narrow)


def _least_text_px(svg: str, drawn_width: float) -> float:
    """Smallest on-screen size (px) of the SVG's text when the SVG is drawn ``drawn_width`` px wide: its
    font size (in viewBox units) times drawn width over viewBox width."""
    view_width = float(re.search(r'viewBox="[-\d.]+ [-\d.]+ ([\d.]+)', svg).group(1))
    sizes = [float(x) for x in re.findall(r"<text[^>]*font-size: ([\d.]+)px", svg)]
    assert sizes, "no text in the figure"
    return min(sizes) * drawn_width / view_width


def test_figure_text_is_at_least_9_px_at_1280_and_420_px(servo_model):
    html = render_html(servo_model)
    wide, narrow = _figure_widths(html)
    assert narrow < 420 < wide
    css = _css(html)
    assert re.search(r"@media \(max-width: (\d+)px\) \{\s*\.fig-wide \{ display: none; \}"
                     r"\s*\.fig-narrow \{ display: block; \}", css)
    breakpoint = _px(css, r"@media \(max-width: (\d+)px\) \{\s*\.fig-wide")
    assert 420 <= breakpoint < 1280
    for fig in servo_model.figures:
        assert fig.narrow_svg is not None, fig.title
        assert _least_text_px(fig.svg, wide) >= 9.0, fig.title
        assert _least_text_px(fig.narrow_svg, narrow) >= 9.0, fig.title
        # the wide drawing alone would be too small on a phone: the narrow variant is what makes it legible
        assert _least_text_px(fig.svg, narrow) < 9.0, fig.title
    assert html.count('<div class="fig-narrow">') == len(servo_model.figures)


@pytest.fixture(scope="module")
def wide_html() -> str:
    """A report with what overflowed before: a long design formula (K4), the loops certificate, a certificate
    table of 12 columns (as the workspace check writes), a lab table of 11 columns (the gain study)."""
    record = {"joint": 1, "Km": 1.0, "Km unit": "(rad/s)/(N*m)", "inertia range": [0.6689, 2.505],
              "inertia attained": [0.6689, 2.503], "inertia sampled": [0.6689, 2.503], "inertia unit": "kg*m^2",
              "q at min": [0.0, -2.618, 0.21, 6.283], "q at max": [0.0, 0.0, 0.105, 0.0],
              "tau range": [0.6689, 2.505], "conditions": "1 + Km K2 > 0 = 44.09, K3 > 0 = 608.1",
              "relative condition": 0.9411}
    wide_check = Check("workspace_table", True, target="stable", achieved=1.0, margin=1.0, unit="1",
                       detail="a certificate table wider than the page",
                       certificate={"joints": [dict(record, joint=k) for k in range(1, 5)]})
    model = build_report_model(make_result(checks=(*servo_checks(), wide_check)), studies=False)
    header = ("Gain", "Scale", "Loop", "max Re(pole) (1/s)", *(f"peak |e| q{k} (rad)" for k in range(1, 7)), "Note")
    rows = tuple((g, f"× {s}", "stable", "-18.46", *("0.0002211",) * 6, "as designed")
                 for g in ("K1", "K2") for s in (0.5, 1, 2))
    lab = ReportSection("lab-test", "Lab questions", questions=(
        Question("What is the function of each gain?", ("The peak |e| is most sensitive to K1.",),
                 (Table("Each gain scaled on every joint", header, rows),)),))
    return render_html(dataclasses.replace(model, sections=(lab,)))


def test_the_wide_fixture_holds_a_typeset_gain_and_a_twelve_column_certificate(wide_html):
    assert "K_4" in wide_html or "<mn>4</mn>" in wide_html
    assert "cert-table stack records" in wide_html  # 12 columns: written as records
    assert "peak |e| q6 (rad)" in wide_html


@pytest.mark.skipif(browser() is None, reason=SKIP_REASON)
@pytest.mark.parametrize("width", [1280, 420])
def test_nothing_is_clipped_or_scrolls(wide_html, width):
    found = measure(wide_html, width)
    assert found["window_width"] == width
    assert found["document_width"] <= width
    assert found["overflow"] == []
    assert [s for s in found["scroll"] if "pre.spec" not in s] == []
    shown = found["figures"]
    assert len(shown) == wide_html.count("<figure id=")  # one variant of each figure on screen
    assert all(f["narrow"] == (width < 600) for f in shown)
    assert min(f["least_text_px"] for f in shown) >= 9.0


def test_formulas_wrap_between_terms(wide_html):
    law = re.search(r'<span class="eq" role="math" aria-label="K1 = [^"]*">(.*?)</span></span>', wide_html)
    assert law is not None
    formulas = re.findall(r'<span class="eq-formula">', law.group(0))
    assert len(formulas) >= 4  # K1, K2, K3, K4: each may go to its own line
    css = _css(wide_html)
    assert ".eq { display: flex; flex-wrap: wrap;" in css and ".eq-formula { display: flex; flex-wrap: wrap;" in css


def _text_boxes(svg: str):
    """Each unrotated ``<text>`` of an SVG written by matplotlib as (text, x0, x1, viewBox width), the extent
    from DejaVu Sans's own metrics (matplotlib's text-to-path, points = viewBox units)."""
    import html

    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextToPath

    measure_text = TextToPath()
    view_width = float(re.search(r'viewBox="[-\d.]+ [-\d.]+ ([\d.]+)', svg).group(1))
    for m in re.finditer(r'<text style="([^"]*)" x="([-\d.]+)" y="[-\d.]+"(?: transform="([^"]*)")?>([^<]*)</text>',
                         svg):
        style, x, transform, text = m.groups()
        if transform and not re.match(r"rotate\(-?0 ", transform):
            continue  # a rotated axis label: its width runs vertically
        size = float(re.search(r"font-size: ([\d.]+)px", style).group(1))
        anchor = (re.search(r"text-anchor: (\w+)", style) or [None, "start"])[1]
        width, _h, _d = measure_text.get_text_width_height_descent(
            html.unescape(text), FontProperties(family="DejaVu Sans", size=size), ismath=False)
        x0 = float(x) - {"start": 0.0, "middle": width / 2, "end": width}[anchor]
        yield text, x0, x0 + width, view_width


def test_no_figure_text_runs_off_the_drawing(servo_model):
    for fig in servo_model.figures:
        for svg in (fig.svg, fig.narrow_svg):
            boxes = list(_text_boxes(svg))
            assert boxes, fig.title
            for text, x0, x1, view_width in boxes:
                assert x0 >= -0.5 and x1 <= view_width + 0.5, (fig.title, text, x0, x1, view_width)
