"""HTML: self-contained, complete, escaped, verdict banner."""

from __future__ import annotations

import re
from html.parser import HTMLParser

import pytest

from designkit.report.html import inline_svg, render_html
from designkit.report.model import build_report_model
from designkit.verification.check import Check
from tests.report.conftest import NASTY, make_result


class _Collector(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data):
        self.text.append(data)


def _parse(html: str) -> _Collector:
    p = _Collector()
    p.feed(html)
    p.close()
    return p


@pytest.fixture(scope="module")
def servo_html(servo_model) -> str:
    return render_html(servo_model)


def test_html_is_self_contained(servo_html):
    html = servo_html
    assert html.startswith("<!DOCTYPE html>")
    assert "http" not in html  # no external link, font, namespace URL or DTD
    assert "src=" not in html
    assert "<script" not in html.lower() and "<link" not in html.lower() and "@import" not in html
    assert "<iframe" not in html.lower() and "<object" not in html.lower()
    for url in re.findall(r"url\(([^)]*)\)", html):
        assert url.startswith("#"), url
    for tag, attrs in _parse(html).tags:
        href = attrs.get("href")
        # in-page anchors, or images embedded as data (matplotlib's colour bar)
        assert href is None or href.startswith(("#", "data:image/png;base64,")), (tag, href[:40])


def test_every_check_label_and_status_is_shown(servo_result, servo_model, servo_html):
    from designkit.report.labels import check_label

    for check in servo_result.checks:
        pattern = rf'<tr class="check check-{check.status}[^"]*" id="check-{re.escape(check.name)}">.*?</tr>'
        row = re.search(pattern, servo_html, flags=re.S)
        assert row is not None
        assert check_label(check) in row.group(0)
    # once in the compliance (or informational) table and once in the appendix
    assert servo_html.count('<span class="badge PASS">PASS</span>') == 2 * len(servo_result.checks)


def test_compliance_table_comes_before_the_details(servo_model, servo_html):
    compliance = servo_html.index('id="compliance"')
    assert compliance < servo_html.index('id="design"') < servo_html.index('id="certificates"')
    table = re.search(r'<table class="compliance stack">.*?</table>', servo_html, flags=re.S).group(0)
    for row in servo_model.compliance:
        assert f"<td data-label=\"Requirement\">{row.label}</td>" in table
        if row.evidence:
            assert f'<a href="#{row.evidence}">' in table
            assert f'<figure id="{row.evidence}">' in servo_html
    informational = re.search(r'<table class="compliance informational stack">.*?</table>', servo_html, flags=re.S)
    assert informational is not None and '<span class="tag">informational</span>' in informational.group(0)
    assert "loop_margins" not in table  # the informational check is not among the verdict-deciding ones


def test_why_it_failed_comes_first_in_a_failed_report(failed_result):
    html = render_html(build_report_model(failed_result, studies=False))
    why = html.index('id="why"')
    assert why < html.index('id="compliance"') < html.index('id="certificates"')
    section = html[why:html.index('id="compliance"')]
    assert "Overshoot" in section and "≤ 10 %" in section and "Cause:" in section and "Fix:" in section


def test_equations_are_mathml(servo_model, servo_html):
    assert servo_html.count('<span class="eq" role="math"') == sum(bool(e.nodes) for e in servo_model.equations)
    assert servo_html.count('<math display="block"') >= sum(bool(e.nodes) for e in servo_model.equations)
    assert "<msub><mi>K</mi><mrow><mn>1</mn></mrow></msub>" in servo_html
    assert "<mfrac>" in servo_html


def test_table_of_contents_links_every_section(servo_model, servo_html):
    nav = re.search(r'<nav class="toc".*?</nav>', servo_html, flags=re.S).group(0)
    for section in servo_model.contents:
        assert f'<a href="#{section.anchor}">{section.title}</a>' in nav
        assert f'id="{section.anchor}"' in servo_html


@pytest.mark.parametrize(("fixture", "kind", "verdict"), [
    ("servo_result", "verified", "VERIFIED"),
    ("failed_result", "failed", "FAILED: Overshoot"),
    ("undecided_result", "undecided", "UNDECIDED: Overshoot"),
])
def test_verdict_banner_matches_result(request, fixture, kind, verdict):
    result = request.getfixturevalue(fixture)
    html = render_html(build_report_model(result, studies=False))
    banner = re.search(r'<header class="banner (\w+)" role="status">\s*<div class="inner">\s*'
                       r'<div class="verdict">([^<]*)</div>', html)
    assert banner is not None
    assert banner.group(1) == kind and banner.group(2) == verdict
    assert (kind == "verified") == result.verified
    if not result.verified:
        assert re.search(r'<span class="badge (FAIL|UNDECIDED)">', html)


def test_all_sections_figures_and_certificates_present(servo_model, servo_html):
    for anchor in ("summary", "compliance", "certificates", "design", "figures", "simulation", "spec", "provenance",
                   "glossary"):
        assert f'id="{anchor}"' in servo_html
    assert servo_html.count("<figure id=") == len(servo_model.figures) >= 5
    narrow = sum(f.narrow_svg is not None for f in servo_model.figures)
    assert servo_html.count("<svg") == len(servo_model.figures) + narrow  # a narrow variant for small screens
    assert '<table class="matrix">' in servo_html and "<td>0.1235</td>" in servo_html
    assert '<table class="cert-table stack' in servo_html
    assert servo_model.spec_sha256 in servo_html
    for g in servo_model.gains:
        assert g.unit.replace("(", "").split("/")[0] in servo_html


def test_svg_ids_are_unique_and_references_resolve(servo_html):
    ids = re.findall(r'\bid="([^"]+)"', servo_html)
    assert len(ids) == len(set(ids))
    refs = set(re.findall(r'href="#([^"]+)"', servo_html)) | set(re.findall(r"url\(#([^)]+)\)", servo_html))
    assert refs <= set(ids)


def test_user_text_is_escaped():
    checks = (Check(name="<img src=x onerror=alert(1)>", passed=False, target="< 5 & > 1", achieved="<b>",
                    detail=NASTY, certificate={"note": "<script>x</script>"}),)
    text = make_result(checks=checks, simulate=False).loaded.text.replace(
        "used by the report tests.", "used by <script>alert(1)</script> & tests.")
    html = render_html(build_report_model(make_result(text, checks=checks, simulate=False), studies=False))
    assert "<img" not in html and "<script" not in html
    template_bold = (html.count("<b>Cause:</b>") + html.count("<b>Fix:</b>") + html.count("<b>Contents</b>")
                     + html.count("<figcaption><b>") + html.count('<td data-label="Requirement"><b>'))
    assert html.count("<b>") == template_bold  # only the template's own bold text
    assert "<td data-label=\"Achieved\" class=\"num\">&lt;b&gt;</td>" in html
    assert "&lt;img src=x onerror=alert(1)&gt;" in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt; &amp; tests" in html
    assert "FAILED: &lt;img" in html


def test_inline_svg_prefixes_ids_and_drops_namespaces():
    svg = ('<?xml version="1.0"?>\n<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "http://x/svg11.dtd">\n'
           '<svg xmlns:xlink="http://www.w3.org/1999/xlink" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1 1">'
           '<metadata><rdf:RDF>http://purl.org</rdf:RDF></metadata>'
           '<defs><path id="a"/><clipPath id="c"/></defs><use xlink:href="#a"/><g clip-path="url(#c)"/></svg>')
    out = inline_svg(svg, "f1-", title="T & <x>")
    assert out.startswith('<svg class="figure-svg" role="img" aria-label="T &amp; &lt;x&gt;"')
    assert "http" not in out and "metadata" not in out and "xlink" not in out
    assert 'id="f1-a"' in out and 'href="#f1-a"' in out and "url(#f1-c)" in out
    with pytest.raises(ValueError):
        inline_svg("<html/>", "p")


def test_tracking_report_renders(tracking_result):
    html = render_html(build_report_model(tracking_result, studies=False))
    assert "PID trajectory tracking" in html and "http" not in html


def test_a_formula_is_one_math_element_per_term():
    from designkit.display.typeset import equation
    from designkit.report.html import mathml

    out = str(mathml(equation("law", "u = -K1 (x1 - xD) - K2 x2 + (Km/τ) u, K4 = 2")))
    terms = re.findall(r'<math display="block" alttext="([^"]*)">', out)
    assert [t.split()[0] for t in terms] == ["u", "−", "+", "K_4"]  # broken before each binary sign, after ","
    assert out.count('<span class="eq-formula">') == 2
    assert '<mo form="infix">−</mo>' in out  # a continued term's sign keeps its binary spacing
    assert '<mrow><mo stretchy="false">(</mo><msub><mi>x</mi>' in out  # (x1 - xD): at the text's size
    assert "<mfrac>" in out and out.count('<mo stretchy="false">(</mo>') == 1  # (Km/τ) grows with its fraction
