"""PDF: Typst escaping (round-tripped through the Typst compiler), template, compiled document."""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess

import pytest
import typst

from designkit.report.model import build_report_model
from designkit.report.pdf import TypstCode, compile_pdf, escape_typst, render_typst, typst_string
from designkit.verification.check import Check
from tests.report.conftest import NASTY, make_result

# Typst content -> plain string, so that Typst itself tells what an escaped text displays.
_PLAIN = r"""
#let plain(c) = {
  if type(c) == str { c }
  else if c.has("text") { c.text }
  else if c.has("children") { c.children.map(plain).join("", default: "") }
  else if c.func() == [ ].func() { " " }
  else if c.func() == linebreak { "\n" }
  else if c.func() == smartquote { if c.double { "\"" } else { "'" } }
  else { panic("markup was interpreted: " + repr(c)) }
}
"""

NASTY_STRINGS = [
    NASTY,
    "#set page(width: 1cm) #panic(\"boom\")",
    "$x^2$ and $$ and $",
    "*bold* _emph_ `raw` ```block```",
    "@label <label> [content] {code} \\ \\\\ \\u{41}",
    "= heading-like", "- list-like", "+ enum-like", "1. enum-like", "/ term: list",
    "// line comment", "/* block comment", "https://example.org/a_b",
    "~ -- --- ... -? 'single' \"double\"",
    "K_1 = τ S2/Km,  K2 = -(τ S1 + 1)/Km ∫(x1 - xD) dt",
    "trailing backslash \\",
    "]#[ ) ( #{ } #let x = 1",
]


def _displayed(text: str) -> str:
    """What Typst displays for ``escape_typst(text)`` in markup (compiled for real)."""
    source = _PLAIN + f"#let got = plain([{escape_typst(text)}])\n" \
        + f"#assert.eq(got, {typst_string('sentinel')}, message: \"GOT:\" + got + \":END\")\n"
    try:
        typst.compile(source.encode("utf-8"))
    except typst.TypstError as exc:
        found = re.search(r"GOT:(.*?):END", str(getattr(exc, "message", exc.args[0])), flags=re.S)
        if found is None:
            raise
        return found.group(1)
    raise AssertionError("sentinel matched")


@pytest.mark.parametrize("text", NASTY_STRINGS)
def test_escape_typst_round_trips_through_typst(text):
    expected = " ".join(text.split())  # markup collapses runs of whitespace
    assert _displayed(text) == expected


def test_escape_typst_newlines_become_line_breaks():
    assert _displayed("line 1\nline #2\r\nline 3").replace("\n ", "\n") == "line 1\nline #2\nline 3"


def test_escape_typst_characters():
    for ch in "#$*_@<>[]\\`~/=-+\"':":
        assert escape_typst(ch) == "\\" + ch
    assert escape_typst("abc XYZ 123 τ∫ü") == "abc XYZ 123 τ∫ü"
    assert escape_typst("a\tb\x00c") == "a bc"
    assert escape_typst(3.5) == "3\\.5"


@pytest.mark.parametrize("text", [*NASTY_STRINGS, "multi\nline\ttab \x01 ctrl"])
def test_typst_string_round_trips(text):
    source = f"#assert.eq({typst_string(text)}, {typst_string(text)})\n#let s = {typst_string(text)}\n"
    source += "#assert(s.len() == " + str(len(text.encode("utf-8"))) + ")\n"
    typst.compile(source.encode("utf-8"))
    assert isinstance(typst_string(text), TypstCode)


def test_template_escapes_every_value_by_default():
    checks = (Check(name=NASTY, passed=None, target="$a$ # b", achieved="@x", detail=NASTY,
                    certificate={NASTY: NASTY, "M": [[1.0, 2.0], [3.0, 4.0]]}),)
    model = build_report_model(make_result(checks=checks, simulate=False), studies=False)
    model = dataclasses.replace(model, notes=(NASTY, "= not a heading"), description=NASTY)
    source = render_typst(model)
    assert "#panic" not in source.replace("\\#panic", "")
    assert "<<" not in source and "<%" not in source
    pdf = compile_pdf(model)
    assert pdf.startswith(b"%PDF")


@pytest.fixture(scope="module")
def servo_pdf(servo_model) -> bytes:
    return compile_pdf(servo_model)


def _page_count(pdf: bytes) -> int:
    try:
        import pypdf
    except ImportError:
        return len(re.findall(rb"/Type\s*/Page(?![s\w])", pdf))
    import io

    return len(pypdf.PdfReader(io.BytesIO(pdf)).pages)


def test_pdf_is_a_pdf_with_pages(servo_pdf):
    assert servo_pdf.startswith(b"%PDF-")
    assert servo_pdf.rstrip().endswith(b"%%EOF")
    n = _page_count(servo_pdf)
    assert n >= 3
    count = re.search(rb"/Type\s*/Pages\b.*?/Count\s+(\d+)", servo_pdf, flags=re.S)
    if count is not None:
        assert int(count.group(1)) == n


def test_pdf_embeds_typst_default_fonts_only(servo_pdf):
    """Compiled with system fonts ignored: every font is one Typst ships, embedded."""
    fonts = set(re.findall(rb"/BaseFont\s*/(?:[A-Z]{6}\+)?([\w-]+)", servo_pdf))
    assert fonts
    # Typst's own fonts, plus DejaVu Sans of the figures' SVG text (shipped with matplotlib, see svg.py)
    assert all(f.startswith((b"LibertinusSerif", b"DejaVuSans", b"NewCM")) for f in fonts), fonts
    assert servo_pdf.count(b"/FontFile") >= len({f.split(b"-Identity")[0] for f in fonts})


def test_pdf_is_reproducible(servo_model, servo_pdf):
    assert compile_pdf(servo_model) == servo_pdf


def test_pdf_has_one_image_per_figure(servo_model):
    source = render_typst(servo_model)
    assert source.count("image(") == len(servo_model.figures)
    for fig in servo_model.figures:
        assert f'image("{fig.filename}"' in source


@pytest.mark.skipif(shutil.which("pdftotext") is None, reason="poppler-utils not installed")
def test_pdf_text_shows_verdict_and_checks(servo_result, servo_pdf, tmp_path):
    path = tmp_path / "r.pdf"
    path.write_bytes(servo_pdf)
    text = subprocess.run(["pdftotext", "-layout", str(path), "-"], capture_output=True, text=True,
                          check=True).stdout
    from designkit.report.labels import check_label

    assert "VERIFIED" in text
    raw = subprocess.run(["pdftotext", str(path), "-"], capture_output=True, text=True, check=True).stdout
    flat = " ".join(raw.split())
    for check in servo_result.checks:
        assert check_label(check) in flat
    assert "Spec SHA-256" in text
    assert flat.index("Requirement compliance") < flat.index("Appendix A: check details")


def test_compile_errors_are_reported_with_the_typst_diagnostic(monkeypatch, servo_model):
    monkeypatch.setattr("designkit.report.pdf.render_typst", lambda model: "#let x = (\n")
    with pytest.raises(RuntimeError, match="typst could not compile"):
        compile_pdf(servo_model)


def test_typst_source_layout(servo_model):
    source = render_typst(servo_model)
    assert "#outline(" in source  # table of contents
    assert "sticky: true" in source  # headings kept with what follows them
    # every table opens with a header row that Typst repeats on each page
    assert source.count("table(") <= source.count("table.header(") + source.count("table.cell(") + 40
    for anchor in servo_model.figure_anchors:
        assert f"<{anchor}>" in source
    for row in servo_model.compliance:
        if row.evidence:
            assert f'#link(label("{row.evidence}"))' in source


def test_pdf_metadata_lists_the_versions_of_the_versions_table(servo_model, servo_pdf):
    keywords = re.search(rb"/Keywords\s*\((.*?)\)\s*/", servo_pdf, flags=re.S)
    if keywords is None:  # XMP only
        keywords = re.search(rb"<pdf:Keywords>(.*?)</pdf:Keywords>", servo_pdf, flags=re.S)
    assert keywords is not None
    text = keywords.group(1).decode("latin-1")
    for name, version in servo_model.versions:
        assert f"{name} {version}" in text


@pytest.mark.parametrize("formula", [
    "u = -K1 (x1 - xD) - K2 x2 - K3 ∫(x1 - xD) dt + K3 K4 xD",
    "x1/xD = Km((K1 + K3 K4) s + K3) / (τ s³ + (1 + Km K2) s² + Km K1 s + Km K3)",
    "u = M̂(q) (q̈D + K1 (qD − q) + K2 (q̇D − q̇)) + ĥ(q, q̇)",
    "a* = qD'' + K1 (qD - q) + K2 (qD' - qd);  u = M^(q) a* + h^(q, qd) (model's Newton-Euler at a*)",
    "weird = #x $y$ \\ [a] {b} \"q\" <l> @r ) ( // ⁻¹ ᵀ",
])
def test_typeset_formulas_compile(formula):
    from designkit.display.typeset import equation
    from designkit.report.pdf import typst_math

    source = str(typst_math(equation("f", formula)))
    pdf = typst.compile(source.encode("utf-8"))
    assert pdf.startswith(b"%PDF")
    import io
    import unicodedata

    import pypdf

    text = " ".join(page.extract_text() or "" for page in pypdf.PdfReader(io.BytesIO(pdf)).pages)
    flat = "".join(unicodedata.normalize("NFKC", text).split())  # math italic letters -> plain ones
    # what the formula names survives typesetting (hostile text is quoted, not dropped)
    for token in ("K1", "xD", "weird"):
        if token in formula:
            assert token in flat, (token, text)
