"""Render a :class:`~designkit.report.model.ReportModel` as PDF through Typst.

The Typst source is generated from ``templates/report.typ.j2`` with Jinja2 using delimiters
that cannot occur in Typst (``<< >>``, ``<% %>``, ``<# #>``).  Every ``<< value >>`` is
escaped for Typst *markup* by default (the Typst counterpart of HTML autoescaping); the
template opts out only through the ``str`` filter (a Typst string literal) or the ``raw``
filter (trusted Typst written by this module).  Figures are written as SVG files next to the
``.typ`` source in a temporary directory and included with ``image(...)``.

Typst embeds its default fonts (Libertinus Serif, New Computer Modern, DejaVu Sans Mono);
system fonts are ignored so that the PDF is the same on every machine.  The figures' text is SVG
``<text>`` set in DejaVu Sans (:mod:`designkit.display.svg`): the DejaVu Sans files that ship
with matplotlib are copied into a ``fonts`` folder of the temporary directory and passed to Typst
as its only font path, so the figure text stays text in the PDF (searchable, selectable) and
the font is embedded (only those files: matplotlib's other fonts, e.g. its own DejaVu Sans Mono,
must not shadow Typst's).
"""

from __future__ import annotations

import re
import shutil
import tempfile
import unicodedata
from pathlib import Path

import jinja2

from designkit.display.typeset import Equation, MathFrac, MathToken, line_pieces
from designkit.report.model import ReportModel

_TEMPLATE = "report.typ.j2"
# Every ASCII punctuation character: Typst markup accepts a backslash before any character, so
# escaping all of them disables headings, lists, emphasis, math, labels, references, raw,
# comments (// and /*), shorthands (~, --, ...), smart quotes and automatic links alike.
_MARKUP_SPECIAL = frozenset("\\#$*_@<>[]`~/=-+\"':.;,!?%&|^(){}")
_STRING_ESCAPES = {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\r": "\\r", "\t": "\\t"}


class TypstCode(str):
    """Text that is already valid Typst and must not be escaped again."""

    __slots__ = ()


def escape_typst(text: object) -> str:
    """Escape ``text`` so that Typst markup shows it literally.

    Every ASCII punctuation character gets a backslash; line breaks become Typst line breaks
    (``\\`` followed by a newline) and other control characters are dropped.

    Examples
    --------
    >>> escape_typst("K_1 = #5 * $x$")
    'K\\\\_1 \\\\= \\\\#5 \\\\* \\\\$x\\\\$'
    """
    s = str(text).replace("\r\n", "\n").replace("\r", "\n")
    out = []
    for ch in s:
        if ch in _MARKUP_SPECIAL:
            out.append("\\" + ch)
        elif ch == "\n":
            out.append("\\\n")
        elif ch == "\t":
            out.append(" ")
        elif ord(ch) < 32 or ord(ch) == 127:
            continue
        else:
            out.append(ch)
    return "".join(out)


def typst_string(text: object) -> TypstCode:
    """A Typst string literal (with quotes) whose value is ``text``."""
    out = []
    for ch in str(text):
        if ch in _STRING_ESCAPES:
            out.append(_STRING_ESCAPES[ch])
        elif ord(ch) < 32 or ord(ch) == 127:
            out.append(f"\\u{{{ord(ch):x}}}")
        else:
            out.append(ch)
    return TypstCode('"' + "".join(out) + '"')


def _finalize(value: object) -> str:
    if isinstance(value, TypstCode):
        return value
    return escape_typst("" if value is None else value)


def _matrix(rows: tuple[tuple[str, ...], ...]) -> TypstCode:
    body = "; ".join(", ".join(typst_string(x) for x in row) for row in rows)
    return TypstCode(f'$mat(delim: "[", align: #right, {body})$')


def _breakable(text: object) -> TypstCode:
    """Escaped markup with zero-width break opportunities after ``_`` and ``.`` (long identifiers)."""
    return TypstCode(escape_typst(text).replace("\\_", "\\_\u200b").replace("\\.", "\\.\u200b"))


_MATH_OPS = {"−": "-", "-": "-", "+": "+", "=": "=", "(": "\\(", ")": "\\)", "∫": "integral", "·": "dot.op"}
_ACCENTS = {"\u0302": "hat", "\u0307": "dot", "\u0308": "dot.double", "\u0303": "tilde"}


def _math_letter(text: str) -> str:
    """A Typst math identifier: one letter as itself (italic), a word as an upright string, accents as functions."""
    decomposed = unicodedata.normalize("NFD", text)
    base = "".join(c for c in decomposed if not unicodedata.combining(c))
    accents = [c for c in decomposed if unicodedata.combining(c)]
    if len(base) == 1 and unicodedata.category(base).startswith("L") and all(a in _ACCENTS for a in accents):
        out = base
        for a in accents:
            out = f"{_ACCENTS[a]}({out})"
        return out
    return typst_string(text)


def _math_token(t: MathToken) -> str:
    if t.kind == "sep":  # the space after it is the one between formulas (typst_math)
        return typst_string(t.text)
    if t.kind == "mi":
        core = _math_letter(t.text)
    elif t.kind == "mn" and t.text.replace(".", "", 1).isdigit():
        core = t.text
    elif t.kind == "mo" and t.text in _MATH_OPS:
        core = _MATH_OPS[t.text]
    else:
        core = typst_string(t.text)
    primes = t.sup.count("′")
    sup = t.sup.replace("′", "")
    out = core + "'" * primes
    if t.sub:
        out += f"_({typst_string(t.sub)})"
    if sup:
        out += f"^({typst_string(sup)})"
    return out


def _math_nodes(nodes) -> str:
    return " ".join(f"frac({_math_nodes(n.num)}, {_math_nodes(n.den)})" if isinstance(n, MathFrac) else _math_token(n)
                    for n in nodes)


_BINARY = {"+": "plus", "−": "minus", "-": "minus"}


def _math_term(nodes, *, continued: bool) -> str:
    """One term as an unbreakable box of display math; a continued term's leading sign is set as a binary
    operator (``class("binary", ...)``: alone at the start of a box Typst would set it as a unary sign)."""
    head = ""
    first = nodes[0]
    if continued and isinstance(first, MathToken) and first.kind == "mo" and first.text in _BINARY:
        head, nodes = f'class("binary", {_BINARY[first.text]}) ', nodes[1:]
    return f"#box($display({head}{_math_nodes(nodes)})$)"


def typst_math(eq: Equation) -> TypstCode:
    """An :class:`~designkit.display.typeset.Equation` as Typst markup of inline display math (every word
    quoted: any text compiles).

    Each term (:func:`~designkit.display.typeset.line_pieces`) is a ``box``, so a line breaks only between
    terms (at the word space before a term's sign, which stands for the sign's left math spacing: Typst
    sets none at the start of a box) or between the formulas of a line (a 1.5 em space), never inside a
    parenthesis, a fraction or a term."""
    if not eq.nodes:
        return TypstCode("")
    formulas = [" ".join(_math_term(t, continued=k > 0) for k, t in enumerate(terms))
                for terms in line_pieces(eq.nodes)]
    return TypstCode(" #h(1.5em) ".join(formulas))


CERT_TABLE_WIDTH_PT = 430.0
"""Width (pt) a certificate table may take in appendix A: the A4 text width (17.6 cm, 499 pt) less the status
column and the cell's inset."""
_ADVANCE_PT = 0.5 * 7.5  # a generous average advance of Libertinus Serif (0.5 em) at the certificates' 7.5 pt
_INSET_PT = 8.0
_MAX_COLUMNS = 8  # more columns leave each about 50 pt: sentences in them would run a word a line


def fits_as_table(header: tuple[str, ...] | None, rows: tuple[tuple[str, ...], ...] | None) -> bool:
    """Whether a certificate table can be set as a table in :data:`CERT_TABLE_WIDTH_PT`: the sum over its
    columns of the longest word (which Typst cannot break) and the cell inset, and at most 8 columns; one that
    cannot is written one row a line as ``column: value`` pairs (the HTML counterpart is
    :func:`designkit.report.html.fits_as_table`)."""
    columns = list(zip(header or (), *(rows or ()), strict=False))
    if len(columns) > _MAX_COLUMNS:
        return False
    width = 0.0
    for cells in columns:
        longest = max((len(word) for cell in cells for word in str(cell).split()), default=0)
        width += longest * _ADVANCE_PT + _INSET_PT
    return width <= CERT_TABLE_WIDTH_PT


def _environment() -> jinja2.Environment:
    from designkit.report.templates_cache import bytecode_cache

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("designkit.report", "templates"),
        bytecode_cache=bytecode_cache(),
        block_start_string="<%",
        block_end_string="%>",
        variable_start_string="<<",
        variable_end_string=">>",
        comment_start_string="<#",
        comment_end_string="#>",
        autoescape=False,
        finalize=_finalize,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )
    env.filters["str"] = typst_string
    env.filters["raw"] = TypstCode
    env.filters["matrix"] = _matrix
    env.filters["breakable"] = _breakable
    env.filters["math"] = typst_math
    env.tests["fitting"] = lambda e: fits_as_table(e.header, e.matrix)
    return env


def render_typst(model: ReportModel) -> str:
    """The Typst source of the report; figures are referenced by ``Figure.filename``."""
    return _environment().get_template(_TEMPLATE).render(m=model)


def figure_font_dir(root: Path) -> Path:
    """Copy the figures' font files (:func:`designkit.display.svg.font_files`) into ``root / "fonts"``
    and return that folder (the font path given to Typst)."""
    from designkit.display.svg import font_files

    folder = root / "fonts"
    folder.mkdir(exist_ok=True)
    for path in font_files():
        shutil.copyfile(path, folder / path.name)
    return folder


def compile_pdf(model: ReportModel) -> bytes:
    """Compile the report to PDF bytes (Typst default fonts and the figures' DejaVu Sans, no system fonts)."""
    import typst

    source = render_typst(model)
    with tempfile.TemporaryDirectory(prefix="designkit-report-") as tmp:
        root = Path(tmp)
        fonts = figure_font_dir(root)
        for fig in model.figures:
            (root / fig.filename).write_text(fig.svg, encoding="utf-8")
        main = root / "report.typ"
        main.write_text(source, encoding="utf-8")
        try:
            pdf = typst.compile(str(main), root=str(root), font_paths=[str(fonts)],
                                ignore_system_fonts=True)
        except typst.TypstError as exc:  # user text is escaped, so this is a designkit bug
            detail = getattr(exc, "diagnostic", "") or str(exc)
            raise RuntimeError(f"typst could not compile the report source: {detail}") from exc
    if not isinstance(pdf, bytes) or not pdf.startswith(b"%PDF"):
        raise RuntimeError("typst did not return a PDF document")
    return without_false_suspects(pdf)


_FALSE_SUSPECTS = re.compile(rb"(/MarkInfo\s*<<\s*/Marked\s+true\s*)(/Suspects\s+false)(?=\s*>>)")


def without_false_suspects(pdf: bytes) -> bytes:
    """``pdf`` with the catalog's ``/MarkInfo`` entry ``/Suspects false`` blanked out (same length, so every
    cross-reference offset stays valid).

    Typst writes ``/MarkInfo << /Marked true /Suspects false >>`` in the document catalog of a tagged PDF.
    That is valid PDF (ISO 32000-1, table 321: ``Suspects`` is a boolean, default false), but poppler up to
    at least 22.12 reports any ``Suspects`` that is not ``true`` as "Syntax Error: Suspects object is wrong
    type (boolean)" on stderr for every ``pdfinfo``, ``pdftoppm`` or ``pdftotext`` run.  Dropping the key
    keeps its meaning (the default is false) and silences the reader; the tags and everything else are
    untouched.  A PDF without that entry is returned as is.

    Examples
    --------
    >>> without_false_suspects(b"<</MarkInfo<</Marked true/Suspects false>>>>")
    b'<</MarkInfo<</Marked true               >>>>'
    """
    return _FALSE_SUSPECTS.sub(lambda m: m.group(1) + b" " * len(m.group(2)), pdf, count=1)
