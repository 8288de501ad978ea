"""Deterministic SVG output of matplotlib figures: the rc settings, palette, tags and decimation of every figure.

Figures are built with :class:`matplotlib.figure.Figure` directly, never through ``pyplot``, so
no GUI backend is selected and no global figure registry is touched (the SVG canvas renders
them; the interactive backend setting is irrelevant).  Output is reproducible byte for byte:
ids are salted with a fixed ``svg.hashsalt`` and the date metadata is dropped.

Text is written as SVG ``<text>`` elements (``svg.fonttype: none``), not as glyph outlines: it is
searchable and selectable in the HTML report and in the PDF, and rendering is several times
faster.  The font is DejaVu Sans, which ships with matplotlib (:func:`font_dir`), so the text is
laid out with the same metrics on every machine; the SVG names the CSS stack ``'DejaVu Sans',
'Arial', sans-serif`` so a browser without DejaVu Sans falls back sensibly, and the PDF compiler
is given :func:`font_dir` so the PDF embeds DejaVu Sans itself.  The options are applied with
:func:`matplotlib.rc_context`, so matplotlib's global state is left as it was.  matplotlib is
imported lazily, inside the functions.
"""

from __future__ import annotations

import contextvars
import io
import re
from pathlib import Path
from typing import Any

import numpy as np

FONT_FAMILY = "DejaVu Sans"
"""The family every figure's text is set in (shipped with matplotlib, embedded in the PDF)."""
FONT_FILES = ("DejaVuSans.ttf", "DejaVuSans-Bold.ttf", "DejaVuSans-Oblique.ttf", "DejaVuSans-BoldOblique.ttf")
"""The files of :data:`FONT_FAMILY` in :func:`font_dir` (regular, bold, oblique, bold oblique)."""

RC_PARAMS = {
    "svg.hashsalt": "designkit-report",
    "svg.fonttype": "none",
    "font.family": ["sans-serif"],
    "font.sans-serif": [FONT_FAMILY, "Arial"],
    "mathtext.fontset": "dejavusans",
    "font.size": 9.0,
    "axes.titlesize": 10.0,
    "axes.labelsize": 9.0,
    "legend.fontsize": 8.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "lines.linewidth": 1.4,
    "path.simplify": True,
}
"""matplotlib options under which every report figure is drawn."""

BLUE, ORANGE, RED, GREEN, GREY, PURPLE = "#1f5fa8", "#e07b00", "#c0282d", "#2e8b57", "#666666", "#7b3fa0"
TAG_PREFIX = "dk-"
"""Prefix of the SVG ids (matplotlib ``gid``) naming what an artist shows (:func:`tag`)."""
MAX_POINTS = 2000
"""Samples per plotted line; longer signals are min/max decimated."""
MAX_DRAWN = 1e300
"""Largest magnitude drawn: matplotlib's axis and tick arithmetic overflows for extents near the
largest double (about 1.8e308); samples beyond (a diverging run, inf, NaN) are left out of the
line, which then stops where the signal leaves the drawable range."""


def font_dir() -> Path:
    """The folder of the TrueType fonts that ship with matplotlib (holds :data:`FONT_FILES`)."""
    import matplotlib

    return Path(matplotlib.get_data_path()) / "fonts" / "ttf"


def font_files() -> tuple[Path, ...]:
    """The files of :data:`FONT_FAMILY` (those of :data:`FONT_FILES` that exist in :func:`font_dir`)."""
    folder = font_dir()
    return tuple(folder / name for name in FONT_FILES if (folder / name).is_file())


MARGINS = {"left": 0.85, "right": 0.25, "bottom": 0.48, "top": 0.1, "gap": 0.14}
"""Fixed margins (inches) of a ``layout="fixed"`` figure: room for 8-character tick labels and an axis label
on the left, the tick labels and x label below, half of a 5-character tick label centred on the right end of the
x axis (``1000``, ``1e+04``), and between stacked axes (which share x, so their inner tick labels are hidden)."""


NARROW_WIDTH = 4.6
"""Width (inches) of a figure's narrow variant, drawn for screens below 600 px (:func:`render`): at the
390-400 px a 420 px window leaves for a figure, 1 pt of the drawing is about 1.2 px, so the 8 pt tick and
legend text is about 9.6 px on screen (the wide drawing, 6.4-6.8 inches, would set it at 6.5 px)."""
_NARROW = contextvars.ContextVar("designkit_narrow_figure", default=False)


class SvgText(str):
    """The SVG text of a figure, carrying the SVG of its narrow variant as :attr:`narrow` (None when the
    drawing has none); :class:`~designkit.display.figure.Figure` picks it up."""

    narrow: str | None = None


def _with_narrow(svg: str, narrow: str | None) -> SvgText:
    out = SvgText(svg)
    out.narrow = narrow if narrow is not None and _viewbox_width(narrow) < _viewbox_width(svg) else None
    return out


def _viewbox_width(svg: str) -> float:
    found = re.search(r'viewBox="\s*[-\d.eE+]+[\s,]+[-\d.eE+]+[\s,]+([-\d.eE+]+)', svg)
    return float(found.group(1)) if found else float("nan")


def new_figure(width: float, height: float, rows: int = 1, sharex: bool = True, layout: str = "fixed"):
    """A ``width`` x ``height`` inch figure and its ``rows`` axes (one column).

    While :func:`render` draws a figure's narrow variant the width is at most :data:`NARROW_WIDTH`
    (the height, the fonts and the margins in inches stay as asked).

    ``layout="fixed"`` places the axes with the fixed :data:`MARGINS` (one text layout pass when the
    figure is saved); ``"constrained"`` lets matplotlib's constrained layout fit colour bars, titles and
    outside legends, at about twice the rendering cost (it measures every text twice more).
    """
    from matplotlib.figure import Figure as MplFigure

    if _NARROW.get():
        width = min(width, NARROW_WIDTH)
    if layout != "fixed":
        fig = MplFigure(figsize=(width, height), layout=layout)
        return fig, fig.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0]
    fig = MplFigure(figsize=(width, height))
    m = MARGINS
    axes_height = (height - m["bottom"] - m["top"] - (rows - 1) * m["gap"]) / rows
    fig.subplots_adjust(left=m["left"] / width, right=1.0 - m["right"] / width, bottom=m["bottom"] / height,
                        top=1.0 - m["top"] / height, hspace=m["gap"] / axes_height)
    return fig, fig.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0]


def tag(fig, key: str, *artists: Any) -> None:
    """Name what ``artists`` show: each gets the SVG id ``dk-<key>`` (``dk-<key>--<n>`` for the n-th
    artist with that key in ``fig``, ids being unique).  Captions are written from these names
    (:func:`drawn_keys`), so a caption names exactly what is drawn; tests read them from the SVG.
    ``key`` is lower-case letters, digits and single hyphens."""
    counts = fig.__dict__.setdefault("_dk_tag_counts", {})
    for artist in artists:
        n = counts.get(key, 0)
        counts[key] = n + 1
        artist.set_gid(f"{TAG_PREFIX}{key}" + (f"--{n}" if n else ""))


def tag_key(gid: str | None) -> str | None:
    """The key of a tagged artist's id (``dk-<key>`` or ``dk-<key>--<n>``), else None.

    Examples
    --------
    >>> tag_key("dk-control-limit--1"), tag_key("dk-reference"), tag_key("line2d_3")
    ('control-limit', 'reference', None)
    """
    if not gid or not gid.startswith(TAG_PREFIX):
        return None
    return gid[len(TAG_PREFIX):].split("--", 1)[0]


def drawn_keys(fig) -> tuple[str, ...]:
    """The keys (:func:`tag`) of the visible artists of ``fig``, each once, in drawing order."""
    keys = (tag_key(a.get_gid()) for a in fig.findobj(lambda a: a.get_gid() is not None and a.get_visible()))
    return tuple(dict.fromkeys(k for k in keys if k is not None))


def svg_keys(svg: str) -> tuple[str, ...]:
    """The keys (:func:`tag`) found in an SVG document's ids, each once, in document order."""
    import re

    found = (tag_key(m) for m in re.findall(r'\bid="([^"]+)"', svg))
    return tuple(dict.fromkeys(k for k in found if k is not None))


def to_svg(fig) -> str:
    """The SVG text of ``fig``, without date metadata."""
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata={"Date": None})
    return buf.getvalue()


def _narrow_variant(draw, args: tuple[Any, ...]) -> str | None:
    """The SVG of ``draw(*args)`` drawn again with :data:`NARROW_WIDTH` (None when it draws nothing)."""
    token = _NARROW.set(True)
    try:
        out = draw(*args)
    finally:
        _NARROW.reset(token)
    if out is None:
        return None
    return to_svg(out[0] if isinstance(out, tuple) else out)


def render(draw, *args: Any) -> SvgText | None:
    """Run ``draw(*args) -> figure or None`` under the report's rc settings and return SVG text (with the
    narrow variant, :class:`SvgText`, drawn by the same function at :data:`NARROW_WIDTH`)."""
    import matplotlib

    with matplotlib.rc_context(RC_PARAMS):
        fig = draw(*args)
        if fig is None:
            return None
        return _with_narrow(to_svg(fig), _narrow_variant(draw, args))


def render_tagged(draw, *args: Any) -> tuple[SvgText | None, tuple[str, ...], dict[str, Any]]:
    """Like :func:`render` for ``draw(*args) -> figure or (figure, info) or None``: the SVG text, the keys
    of what was drawn (:func:`drawn_keys`, read after the layout) and ``info`` (what the drawing measured
    for the caption, e.g. an axis scale; empty when ``draw`` returns a figure alone)."""
    import matplotlib

    with matplotlib.rc_context(RC_PARAMS):
        out = draw(*args)
        if out is None:
            return None, (), {}
        fig, info = out if isinstance(out, tuple) else (out, {})
        svg = _with_narrow(to_svg(fig), _narrow_variant(draw, args))
        return svg, drawn_keys(fig), dict(info)


def column(values: np.ndarray, index: int = 0) -> np.ndarray:
    """Column ``index`` of a 2-D signal; a 1-D signal is returned as is."""
    arr = np.asarray(values, dtype=float)
    return arr[:, index] if arr.ndim == 2 else arr


def minmax_decimate(t: np.ndarray, y: np.ndarray, max_points: int = MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Reduce a signal to at most ``max_points`` samples keeping each bucket's min and max.

    Chattering signals (relays, quantisers) keep their envelope, unlike plain subsampling.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    n = t.size
    if n <= max_points:
        return t, y
    buckets = max_points // 2
    edges = np.linspace(0, n, buckets + 1).astype(int)
    idx = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        if hi <= lo:
            continue
        seg = y[lo:hi]
        i_min, i_max = lo + int(np.argmin(seg)), lo + int(np.argmax(seg))
        idx.extend(sorted({i_min, i_max}))
    sel = np.asarray(idx, dtype=int)
    return t[sel], y[sel]


def drawable(y: np.ndarray) -> np.ndarray:
    """``y`` as float with every sample that is not finite or beyond :data:`MAX_DRAWN` in magnitude set to NaN
    (not drawn)."""
    y = np.asarray(y, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.where(np.abs(y) <= MAX_DRAWN, y, np.nan)


def plot_decimated(ax, t, y, **kwargs):
    """``ax.plot`` of the signal after :func:`minmax_decimate`, samples beyond :data:`MAX_DRAWN` left out."""
    td, yd = minmax_decimate(t, y)
    return ax.plot(td, drawable(yd), **kwargs)
