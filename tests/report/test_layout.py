"""Layout: responsive tables, print colours, table of contents; headless Chromium at 420 px when present."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from designkit.report.html import render_html
from designkit.report.model import build_report_model


@pytest.fixture(scope="module")
def failed_html(failed_result) -> str:
    return render_html(build_report_model(failed_result))


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


def _browser() -> str | None:
    for name in ("chromium", "chromium-browser", "chromium-headless-shell", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.mark.skipif(_browser() is None, reason="no headless Chromium on PATH (chromium, chromium-headless-shell, "
                                                "google-chrome): the 420 px overflow check needs a browser")
def test_no_horizontal_scroll_at_420_px(failed_html, tmp_path):
    probe = failed_html.replace("</body>", "<script>document.title = 'W' + document.documentElement.scrollWidth"
                                           " + 'x' + window.innerWidth;</script></body>")
    page = tmp_path / "r.html"
    page.write_text(probe, encoding="utf-8")
    done = subprocess.run([_browser(), "--headless", "--disable-gpu", "--no-sandbox", "--window-size=420,900",
                           "--dump-dom", page.as_uri()], capture_output=True, text=True, timeout=120)
    found = re.search(r"<title>W(\d+)x(\d+)</title>", done.stdout)
    assert found is not None, done.stderr[-500:]
    assert int(found.group(1)) <= int(found.group(2))
