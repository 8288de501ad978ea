"""Deterministic SVG output of matplotlib figures: the report's rc settings, palette and decimation.

Figures are built with :class:`matplotlib.figure.Figure` directly, never through ``pyplot``, so
no GUI backend is selected and no global figure registry is touched (the SVG canvas renders
them; the interactive backend setting is irrelevant).  Output is reproducible byte for byte:
ids are salted with a fixed ``svg.hashsalt``, the date metadata is dropped and text is drawn as
paths (no font is needed to view the SVG).  The options are applied with
:func:`matplotlib.rc_context`, so matplotlib's global state is left as it was.  matplotlib is
imported lazily, inside the functions.
"""

from __future__ import annotations

import io
from typing import Any

import numpy as np

RC_PARAMS = {
    "svg.hashsalt": "designkit-report",
    "svg.fonttype": "path",
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
MAX_POINTS = 2000
"""Samples per plotted line; longer signals are min/max decimated."""
MAX_DRAWN = 1e300
"""Largest magnitude drawn: matplotlib's axis and tick arithmetic overflows for extents near the
largest double (about 1.8e308); samples beyond (a diverging run, inf, NaN) are left out of the
line, which then stops where the signal leaves the drawable range."""


def new_figure(width: float, height: float, rows: int = 1, sharex: bool = True):
    """A constrained-layout figure of ``width`` x ``height`` inches and its ``rows`` axes (one column)."""
    from matplotlib.figure import Figure as MplFigure

    fig = MplFigure(figsize=(width, height), layout="constrained")
    axes = fig.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0]
    return fig, axes


def to_svg(fig) -> str:
    """The SVG text of ``fig``, without date metadata."""
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata={"Date": None})
    return buf.getvalue()


def render(draw, *args: Any) -> str | None:
    """Run ``draw(*args) -> figure or None`` under the report's rc settings and return SVG text."""
    import matplotlib

    with matplotlib.rc_context(RC_PARAMS):
        fig = draw(*args)
        return None if fig is None else to_svg(fig)


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
