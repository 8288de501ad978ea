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

from designkit.display.typeset import Equation, MathFrac, MathToken
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
        return f'<mo separator="true">{escape(t.text)}</mo><mspace width="1.5em"></mspace>'
    tag = {"mi": "mi", "mn": "mn", "mo": "mo"}.get(t.kind, "mtext")
    core = f"<{tag}>{escape(t.text)}</{tag}>"
    sub = f"<mrow>{''.join(_mathml_piece(x) for x in t.sub.split(','))}</mrow>" if t.sub else ""
    sup = f"<mo>{escape(t.sup)}</mo>" if t.sup and set(t.sup) <= {"′"} else (
        f"<mn>{escape(t.sup)}</mn>" if t.sup else "")
    if sub and sup:
        return f"<msubsup>{core}{sub}{sup}</msubsup>"
    if sub:
        return f"<msub>{core}{sub}</msub>"
    if sup:
        return f"<msup>{core}{sup}</msup>"
    return core


def _mathml_piece(text: str) -> str:
    return f"<mn>{escape(text)}</mn>" if text.isdigit() else f"<mi>{escape(text)}</mi>"


def _mathml_nodes(nodes) -> str:
    out = []
    for n in nodes:
        if isinstance(n, MathFrac):
            out.append(f"<mfrac><mrow>{_mathml_nodes(n.num)}</mrow><mrow>{_mathml_nodes(n.den)}</mrow></mfrac>")
        else:
            out.append(_mathml_token(n))
    return "".join(out)


def mathml(eq: Equation) -> Markup:
    """An :class:`~designkit.display.typeset.Equation` as presentation MathML (no script, no web font)."""
    if not eq.nodes:
        return Markup("")
    alt = escape(eq.text)
    return Markup(f'<math display="block" alttext="{alt}"><mrow>{_mathml_nodes(eq.nodes)}</mrow></math>')


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
    return env


def render_html(model: ReportModel) -> str:
    """The report as one HTML document (UTF-8 text)."""
    anchors = model.figure_anchors or tuple(f"figure-{k}" for k in range(1, len(model.figures) + 1))
    figures = [
        {"title": f.title, "caption": f.caption, "anchor": anchor,
         "svg": Markup(inline_svg(f.svg, f"f{k}-", title=f.title))}
        for k, (f, anchor) in enumerate(zip(model.figures, anchors, strict=True), start=1)
    ]
    return _environment().get_template(_TEMPLATE).render(m=model, figures=figures)
