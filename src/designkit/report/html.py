"""Render a :class:`~designkit.report.model.ReportModel` as one self-contained HTML file.

Figures are inlined as SVG, CSS is inlined, and there is no script, external font, image or
link: the file can be mailed or archived alone.  Jinja2 autoescaping is on; only the SVG
produced by :mod:`designkit.report.figures` is marked safe, after :func:`inline_svg` has made
it fit for inlining.
"""

from __future__ import annotations

import re

import jinja2
from markupsafe import Markup, escape

from designkit.display.typeset import Equation, MathFrac, MathToken, line_pieces
from designkit.report.model import ReportModel

_TEMPLATE = "report.html.j2"


def inline_svg(svg: str, prefix: str, *, title: str = "") -> str:
    """Make a standalone SVG document fit for inlining in HTML.

    Drops the XML declaration, DOCTYPE, RDF metadata and namespace declarations (the HTML
    parser puts inline ``<svg>`` in the SVG namespace itself), turns ``xlink:href`` into
    ``href`` and prefixes every id and reference with ``prefix`` so that several figures in
    one page cannot collide.
    """
    start = svg.find("<svg")
    if start < 0:
        raise ValueError("not an SVG document")
    out = svg[start:]
    out = re.sub(r"<metadata>.*?</metadata>\s*", "", out, flags=re.S)
    out = re.sub(r'\s+xmlns(?::\w+)?="[^"]*"', "", out)
    out = out.replace("xlink:href=", "href=")
    out = re.sub(r'\bid="([^"]+)"', lambda m: f'id="{prefix}{m.group(1)}"', out)
    out = re.sub(r"url\(#([^)]+)\)", lambda m: f"url(#{prefix}{m.group(1)})", out)
    out = re.sub(r'href="#([^"]+)"', lambda m: f'href="#{prefix}{m.group(1)}"', out)
    label = Markup(' role="img" aria-label="{}"').format(title) if title else ""
    out = out.replace("<svg", f'<svg class="figure-svg"{label}', 1)
    return out.strip()


def breakable(text: object) -> Markup:
    """Escaped text with ``<wbr>`` break opportunities after ``_`` and ``.`` (long identifiers)."""
    return Markup(str(escape(text)).replace("_", "_<wbr>").replace(".", ".<wbr>"))


def _mathml_token(t: MathToken) -> str:
    if t.kind == "sep":
        return f"<mo separator=\"true\">{escape(t.text)}</mo>"
    tag = {"mi": "mi", "mn": "mn", "mo": "mo"}.get(t.kind, "mtext")
    core = f"<{tag}>{escape(t.text)}</{tag}>"
    sub = f"<mrow>{''.join(_mathml_piece(x) for x in t.sub.split(','))}</mrow>" if t.sub else ""
    primes = t.sup.count("′")
    sup = t.sup.replace("′", "")
    sup = f"<mn>{escape(sup)}</mn>" if sup else ""
    if sub and sup:
        out = f"<msubsup>{core}{sub}{sup}</msubsup>"
    elif sub:
        out = f"<msub>{core}{sub}</msub>"
    elif sup:
        out = f"<msup>{core}{sup}</msup>"
    else:
        out = core
    # a prime follows its base at the base's size: the glyph ′ is already a raised mark, and a browser
    # that sets it as a superscript shrinks and lifts it a second time (a speck above the letter)
    return out + '<mo lspace="0" rspace="0">′</mo>' * primes


def _mathml_piece(text: str) -> str:
    return f"<mn>{escape(text)}</mn>" if text.isdigit() else f"<mi>{escape(text)}</mi>"


def _is_op(n, *texts: str) -> bool:
    return isinstance(n, MathToken) and n.kind == "mo" and (not texts or n.text in texts)


def _mathml_nodes(nodes) -> str:
    """MathML of a node row; every ``( ... )`` becomes its own ``<mrow>``, so its parentheses stretch to what
    they enclose, not to the tallest fraction of the line."""
    out: list[list[str]] = [[]]
    for n in nodes:
        if isinstance(n, MathFrac):
            out[-1].append(f"<mfrac><mrow>{_mathml_nodes(n.num)}</mrow><mrow>{_mathml_nodes(n.den)}</mrow></mfrac>")
        elif _is_op(n, "("):
            out.append([_mathml_token(n)])
        elif _is_op(n, ")") and len(out) > 1:
            inner = "".join(out.pop())
            if "<mfrac>" not in inner:  # around a row: the parentheses keep the text's size
                inner = inner.replace("<mo>(</mo>", '<mo stretchy="false">(</mo>', 1)
                inner += '<mo stretchy="false">)</mo>'
            else:
                inner += _mathml_token(n)
            out[-1].append(f"<mrow>{inner}</mrow>")
        else:
            out[-1].append(_mathml_token(n))
    while len(out) > 1:  # an unbalanced "(": its tokens stay in line
        inner = out.pop()
        out[-1].extend(inner)
    return "".join(out[0])


def mathml(eq: Equation) -> Markup:
    """An :class:`~designkit.display.typeset.Equation` as presentation MathML (no script, no web font).

    The equation is written as a row of ``<math>`` elements, one per term
    (:func:`~designkit.display.typeset.line_pieces`), inside a wrapping ``<span class="eq">`` labelled with
    the whole formula: MathML in browsers does not break lines, so a formula wider than its column wraps
    between its terms instead of being clipped."""
    if not eq.nodes:
        return Markup("")
    alt = escape(eq.text)
    formulas = []
    for terms in line_pieces(eq.nodes):
        maths = "".join(_term(t, leading=k > 0) for k, t in enumerate(terms))
        formulas.append(f'<span class="eq-formula">{maths}</span>')
    return Markup(f'<span class="eq" role="math" aria-label="{alt}">{"".join(formulas)}</span>')


def _term(nodes, *, leading: bool) -> str:
    """One ``<math>`` of a term; the operator opening a continued term keeps its binary spacing."""
    body = _mathml_nodes(nodes)
    if leading and body.startswith("<mo>"):
        body = '<mo form="infix">' + body[len("<mo>"):]
    return f'<math display="block" alttext="{escape(_plain(nodes))}"><mrow>{body}</mrow></math>'


def _plain(nodes) -> str:
    parts = []
    for n in nodes:
        if isinstance(n, MathFrac):
            parts.append(f"({_plain(n.num)})/({_plain(n.den)})")
        else:
            parts.append(n.text + (f"_{n.sub}" if n.sub else "") + n.sup)
    return " ".join(parts)


CERT_TABLE_WIDTH_PX = 820.0
"""Width (CSS px) a certificate table may take in appendix A at a 1280 px window: the report column
(1040 px less its padding) less the status column and the cell padding."""
_MONO_ADVANCE_PX = 0.602 * 12.8  # DejaVu Sans Mono advance (0.602 em) at the tables' 0.8rem
_CELL_PADDING_PX = 16.0


def fits_as_table(header: tuple[str, ...] | None, rows: tuple[tuple[str, ...], ...] | None) -> bool:
    """Whether a certificate table can be laid out as a table in :data:`CERT_TABLE_WIDTH_PX`: the sum over
    its columns of their narrowest width (the longest word of the column, which a browser cannot break, in
    the monospace cells) with the cell padding.  A table that does not fit is written as one record per
    row (``column: value`` pairs that wrap), so nothing is clipped or needs a scroll bar."""
    columns = list(zip(header or (), *(rows or ()), strict=False))
    width = 0.0
    for cells in columns:
        longest = max((len(word) for cell in cells for word in str(cell).split()), default=0)
        width += longest * _MONO_ADVANCE_PX + _CELL_PADDING_PX
    return width <= CERT_TABLE_WIDTH_PX


def _environment() -> jinja2.Environment:
    from designkit.report.templates_cache import bytecode_cache

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("designkit.report", "templates"),
        bytecode_cache=bytecode_cache(),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )
    env.filters["breakable"] = breakable
    env.filters["mathml"] = mathml
    env.tests["fitting"] = lambda e: fits_as_table(e.header, e.matrix)
    return env


def render_html(model: ReportModel) -> str:
    """The report as one HTML document (UTF-8 text)."""
    anchors = model.figure_anchors or tuple(f"figure-{k}" for k in range(1, len(model.figures) + 1))
    figures = [
        {"title": f.title, "caption": f.caption, "anchor": anchor,
         "svg": Markup(inline_svg(f.svg, f"f{k}-", title=f.title)),
         "narrow": Markup(inline_svg(f.narrow_svg, f"f{k}n-", title=f.title)) if f.narrow_svg else None}
        for k, (f, anchor) in enumerate(zip(model.figures, anchors, strict=True), start=1)
    ]
    return _environment().get_template(_TEMPLATE).render(m=model, figures=figures)
