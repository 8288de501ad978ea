"""The PDF as a strict reader sees it: poppler opens it without a complaint; formulas stay whole; labels sit
beside their formulas; small tables are never split across pages."""

from __future__ import annotations

import io
import re
import shutil
import subprocess
from importlib.resources import files
from pathlib import Path

import pytest

from designkit.report.pdf import compile_pdf, without_false_suspects
from tests.report.pdf_text import pdf_pages

POPPLER = ("pdfinfo", "pdftoppm", "pdftotext")
needs_poppler = pytest.mark.skipif(any(shutil.which(t) is None for t in POPPLER),
                                   reason="poppler-utils (pdfinfo, pdftoppm, pdftotext) not installed")


@pytest.fixture(scope="module")
def servo_pdf_path(servo_model, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("pdf") / "report.pdf"
    path.write_bytes(compile_pdf(servo_model))
    return path


def _typst(source: str, tmp_path: Path) -> bytes:
    import typst

    main = tmp_path / "doc.typ"
    main.write_text(source, encoding="utf-8")
    return typst.compile(str(main))


@needs_poppler
def test_poppler_reads_the_report_without_a_message(servo_pdf_path, tmp_path):
    for command in (["pdfinfo", str(servo_pdf_path)],
                    ["pdftoppm", "-r", "20", "-png", str(servo_pdf_path), str(tmp_path / "page")],
                    ["pdftotext", str(servo_pdf_path), str(tmp_path / "text.txt")]):
        done = subprocess.run(command, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0 and done.stderr == "", (command[0], done.stderr)
    info = subprocess.run(["pdfinfo", str(servo_pdf_path)], capture_output=True, text=True).stdout
    assert re.search(r"^Tagged:\s+yes$", info, flags=re.M)  # the tags are kept
    assert len(list(tmp_path.glob("page*.png"))) == int(re.search(r"^Pages:\s+(\d+)$", info, flags=re.M).group(1))


def test_the_false_suspects_entry_is_blanked_and_the_pdf_stays_valid(tmp_path):
    import pypdf

    raw = _typst("= Tagged\nA paragraph.", tmp_path)
    assert re.search(rb"/MarkInfo\s*<<\s*/Marked\s+true\s*/Suspects\s+false\s*>>", raw)  # what Typst writes
    fixed = without_false_suspects(raw)
    assert len(fixed) == len(raw) and b"/Suspects" not in fixed
    reader = pypdf.PdfReader(io.BytesIO(fixed), strict=True)  # offsets checked strictly
    mark_info = reader.trailer["/Root"]["/MarkInfo"]
    assert dict(mark_info) == {"/Marked": True}
    assert "Tagged" in reader.pages[0].extract_text()
    assert without_false_suspects(fixed) == fixed  # nothing else is touched
    if shutil.which("pdfinfo"):
        path = tmp_path / "fixed.pdf"
        path.write_bytes(fixed)
        done = subprocess.run(["pdfinfo", str(path)], capture_output=True, text=True)
        assert done.returncode == 0 and done.stderr == ""


def _equation_lines(path: Path) -> list[str]:
    text = subprocess.run(["pdftotext", "-layout", str(path), "-"], capture_output=True, text=True,
                          check=True).stdout
    start = [m.start() for m in re.finditer(r"^ *Equations *$", text, flags=re.M)][-1]  # the section, not the contents
    return text[start:text.index("\nPlant\n", start)].splitlines()[1:]


@needs_poppler
def test_formulas_are_not_split_inside_an_expression(servo_pdf_path):
    lines = _equation_lines(servo_pdf_path)
    for line in lines:
        assert line.count("(") == line.count(")"), line  # no line ends inside a parenthesis
    k4 = [line for line in lines if "𝐾4 =" in line]
    assert len(k4) == 1 and "(𝐾3 𝑧)" in k4[0]  # K4 = −(K3 + K1 z)/(K3 z) on one line
    assert not any("𝐾4 =" in line and "𝐾1 =" in line for line in lines)  # this one line did wrap (a test of it)


@needs_poppler
def test_labels_sit_beside_their_formulas(servo_pdf_path, servo_model):
    lines = _equation_lines(servo_pdf_path)
    for label in ("Control law", "Closed loop", "Loop transfer (Bode plot)"):
        found = [line for line in lines if line.lstrip().startswith(label)]
        assert len(found) == 1 and "=" in found[0], (label, found)  # the formula's "=" on the label's line
    note = next(e.note for e in servo_model.equations if e.label.startswith("Loop transfer"))
    words = note.split()[:4]
    assert any(" ".join(words) in line for line in lines)  # the note below the formula, whole


def _keep_helper() -> str:
    template = files("designkit.report").joinpath("templates", "report.typ.j2").read_text(encoding="utf-8")
    return re.search(r"^#let keep\(.*$", template, flags=re.M).group(0)


@pytest.mark.parametrize("kept", [True, False])
def test_a_small_table_moves_to_the_next_page_whole(tmp_path, kept):
    helper = _keep_helper()
    n = int(re.search(r"rows <= (\d+)", helper).group(1))  # the largest table kept whole
    rows = ", ".join(f"[row {k}.], [{k}]" for k in range(1, n + 1))
    table = f"table(columns: 2, table.header([Name], [Value]), {rows})"
    source = "\n".join([
        "#set page(width: 10cm, height: 8cm, margin: 1cm)",
        helper,
        "#v(3.5cm)",
        "Filler above the table.",
        f"#keep({n}, {table})" if kept else f"#{table}",
    ])
    path = tmp_path / "doc.pdf"
    path.write_bytes(_typst(source, tmp_path))
    pages = pdf_pages(path)
    holding = [k for k, page in enumerate(pages) for r in range(1, n + 1) if f"row {r}." in page]
    if kept:
        assert set(holding) == {1} and "Name" in pages[1] and "Name" not in pages[0]
    else:  # the plain table splits: the situation the helper is for
        assert 0 in holding and 1 in holding
