"""The control axis shared by the linear and the simulation figures: the control limit, drawn or named off
scale, and the symmetric-logarithmic scale that keeps small levels visible next to a large command."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import LIMIT_STYLE, OFF_SCALE, off_scale_entry
from designkit.display.svg import RED, drawable, tag

__all__ = ["SYMLOG_RATIO", "common_limit", "control_limit", "control_linthresh", "limit_on_scale", "signal_peak"]


def common_limit(limit: Any) -> float | None:
    """One control limit to draw: the limit itself, or the common value of per-input limits (None when they
    differ -- they are then only in the max_control check)."""
    if limit is None:
        return None
    arr = np.atleast_1d(np.asarray(limit, dtype=float))
    return float(arr[0]) if np.all(arr == arr[0]) else None


def limit_on_scale(limit: float, *signals: Any) -> bool:
    """A symmetric limit ``|u| <= limit`` is drawn when it is at most ``OFF_SCALE`` times the signals' peak."""
    peak = signal_peak(*signals)
    return bool(peak > 0.0 and limit <= OFF_SCALE * peak)


def signal_peak(*signals: Any) -> float:
    """Largest drawable magnitude of the ``signals`` (0 without a finite sample)."""
    values = np.concatenate([np.ravel(drawable(s)) for s in signals])
    values = values[np.isfinite(values)]
    return float(np.max(np.abs(values))) if values.size else 0.0


def control_limit(fig: Any, ax: Any, limit: float, *signals: Any) -> None:
    """Draw ``|u| <= limit`` (dashed); a limit far beyond the signals (more than ``OFF_SCALE`` times their peak)
    is named in the legend only."""
    label = f"|u| ≤ {limit:g} N·m"
    if limit_on_scale(limit, *signals):
        tag(fig, "control-limit", ax.axhline(limit, color=RED, **LIMIT_STYLE, zorder=1.5, label=label),
            ax.axhline(-limit, color=RED, **LIMIT_STYLE, zorder=1.5))
    else:
        tag(fig, "control-limit-offscale", *off_scale_entry(ax, label, color=RED, **LIMIT_STYLE))


SYMLOG_RATIO = 20.0
"""The control axis becomes symmetric-logarithmic when the peak |u| exceeds this many times the smallest
level drawn on it (a limit would otherwise be a hairline on the zero line)."""


def control_linthresh(levels: Sequence[float], *signals: Any) -> float | None:
    """The linear range ``±linthresh`` (N·m) of a symmetric-log control axis, or None for a linear axis.

    A symlog axis is used when the signals' peak |u| exceeds :data:`SYMLOG_RATIO` times the smallest
    positive finite level: the range is then twice that level, so the levels sit in the linear part.

    Examples
    --------
    >>> control_linthresh([5.0], [0.0, 1.3e4]), control_linthresh([5.0], [0.0, 30.0]), control_linthresh([], [1e4])
    (10.0, None, None)
    """
    lv = [abs(float(x)) for x in levels if math.isfinite(x) and x != 0.0]
    if not lv:
        return None
    smallest = min(lv)
    return 2.0 * smallest if signal_peak(*signals) > SYMLOG_RATIO * smallest else None
