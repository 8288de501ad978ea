"""A figure as the report holds it, and the drawing conventions every figure follows.

:class:`Figure` is a titled, captioned SVG document that names the checks it is evidence for.
The helpers here are the ones every figure uses, whoever draws it: the line styles (references
dash-dot, limits dashed, events dotted), the joint colours, :func:`on_scale` and
:func:`off_scale_entry` (a level far from the signals is named in the legend instead of squashing
them), and the tick helpers :func:`plain_ticks` and :func:`few_log_ticks`.  matplotlib is imported
lazily, inside the functions.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.svg import BLUE, GREEN, GREY, MAX_DRAWN, ORANGE, PURPLE, RED, drawable

__all__ = [
    "joint_units",
    "EVENT_STYLE",
    "Figure",
    "JOINT_COLORS",
    "LIMIT_STYLE",
    "OFF_SCALE",
    "REFERENCE_STYLE",
    "few_log_ticks",
    "off_scale_entry",
    "on_scale",
    "plain_ticks",
]

REFERENCE_STYLE = {"ls": "-.", "lw": 1.0}
"""Line style of references (commanded positions, trajectories): dash-dot."""
LIMIT_STYLE = {"ls": "--", "lw": 1.0}
"""Line style of limits (requirement levels, actuator output levels, stability limits): dashed."""
EVENT_STYLE = {"ls": ":", "lw": 1.0}
"""Line style of event markers (a perturbation's onset, a crossover frequency): dotted, vertical."""
JOINT_COLORS = (BLUE, GREEN, PURPLE, ORANGE, RED, GREY)
"""Colour of joint (or input, or channel) ``k``: ``JOINT_COLORS[k % len(JOINT_COLORS)]``."""

OFF_SCALE = 3.0
"""A level is drawn when it lies within this many times the extent of the drawn signals beyond them
(for a control limit: at most this many times the peak |u|); otherwise it is only named in the legend,
marked "off scale"."""


@dataclass(frozen=True)
class Figure:
    """One report figure.

    Parameters
    ----------
    title : str
        Short title shown above the figure.
    caption : str
        What the figure shows and how to read it, written from what is drawn (the keys of the tagged
        artists, :func:`designkit.display.svg.tag`): nothing absent from the drawing is named.
    svg : str
        A standalone SVG document (text as ``<text>`` in DejaVu Sans).
    filename : str
        File name used when the figure is written next to the Typst source (``*.svg``).  Unique among
        a report's figures: it also names the figure's HTML anchor, :attr:`anchor`.
    evidence : tuple of str
        Names of the checks whose evidence the figure shows (e.g. the simulation figure for
        ``overshoot``, ``settling_time``, ...; the Bode and sensitivity figures for ``loop_margins``),
        only checks present in the run.  A report links each requirement to the first figure whose
        ``evidence`` names its check.
    narrow_svg : str or None
        The same drawing at :data:`~designkit.display.svg.NARROW_WIDTH` inches, which the HTML report
        shows on screens below 600 px so that its text stays about 9.6 px high; by default the variant
        that :func:`~designkit.display.svg.render` drew along with ``svg`` (None for an SVG from elsewhere).
    """

    title: str
    caption: str
    svg: str
    filename: str
    evidence: tuple[str, ...] = ()
    narrow_svg: str | None = None

    def __post_init__(self) -> None:
        if self.narrow_svg is None and getattr(self.svg, "narrow", None):
            object.__setattr__(self, "narrow_svg", self.svg.narrow)
        if isinstance(self.svg, str) and type(self.svg) is not str:
            object.__setattr__(self, "svg", str(self.svg))

    @property
    def anchor(self) -> str:
        """The figure's HTML anchor id: its file name's stem, ``fig-`` prefixed when it is not already
        (``fig-simulation.svg`` -> ``fig-simulation``)."""
        stem = self.filename.rsplit(".", 1)[0]
        return stem if stem.startswith("fig-") else "fig-" + stem


def on_scale(levels: Sequence[float], *signals: Any) -> bool:
    """True when every level (same unit as the signals) can be drawn without squashing the ``signals``.

    The signals' finite samples span ``[lo, hi]``; a level is on scale within ``OFF_SCALE * extent`` of
    that span, ``extent`` being ``hi - lo`` or, for a constant signal, its magnitude.  Non-finite levels,
    levels beyond :data:`~designkit.display.svg.MAX_DRAWN` and signals without a finite sample are off scale.

    Examples
    --------
    >>> on_scale([1.1], [0.0, 1.0]), on_scale([1e308], [0.0, 1.0]), on_scale([0.5 + 1e-300], [0.0, 1.0])
    (True, False, True)
    """
    values = np.concatenate([np.ravel(drawable(s)) for s in signals]) if signals else np.array([])
    values = values[np.isfinite(values)]
    levels = np.asarray(levels, dtype=float)
    if values.size == 0 or not np.all(np.abs(levels) <= MAX_DRAWN):
        return False
    lo, hi = float(np.min(values)), float(np.max(values))
    extent = (hi - lo) or abs(hi)
    if extent == 0.0:
        return bool(np.all(levels == 0.0))
    return bool(np.all((levels >= lo - OFF_SCALE * extent) & (levels <= hi + OFF_SCALE * extent)))


def off_scale_entry(ax: Any, label: str, **style: Any) -> list[Any]:
    """A legend entry for a level that is not drawn (returns the empty line carrying it)."""
    return ax.plot([], [], label=f"{label} (off scale)", **style)


def few_log_ticks(ax: Any) -> None:
    """Minor ticks of a log x axis at 2 and 5 times each decade only (readable, and fewer tick artists to lay
    out), and plain tick labels (:func:`plain_ticks`)."""
    from matplotlib.ticker import LogLocator, NullFormatter

    ax.xaxis.set_minor_locator(LogLocator(base=10.0, subs=(2.0, 5.0)))
    ax.xaxis.set_minor_formatter(NullFormatter())
    plain_ticks(ax.xaxis)


def plain_ticks(axis: Any) -> None:
    """Label a log or symlog ``axis`` with plain numbers (``0.1``, ``100``, ``1e+04``) instead of matplotlib's
    mathtext powers of ten: the labels stay searchable text, and parsing mathtext is the costliest step of
    drawing a log axis."""
    from matplotlib.ticker import FuncFormatter

    axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}".replace("-", "−")))


def joint_units(plant: Any, which: str) -> str:
    """The distinct units of a plant's ``"inputs"`` or ``"positions"``, typeset and joined (``"N·m, N"`` for an arm
    with a prismatic joint); ``"N·m"`` / ``"rad"`` when the plant names none."""
    from designkit.display.numbers import unit as typeset

    if which == "inputs":
        units = [getattr(s, "unit", "") for s in getattr(plant, "inputs", ())]
        default = "N·m"
    else:
        states = getattr(plant, "states", ())
        units = [getattr(states[i], "unit", "") for i in getattr(plant, "positions", ()) if i < len(states)]
        default = "rad"
    found = [typeset(u) for u in dict.fromkeys(u for u in units if u)]
    return ", ".join(found) if found else default
