"""The rate study's figure: the command's switching component and the steady error against the sampling rate,
logarithmic axes, a filled marker where every required check passes and an open one where it does not."""

from __future__ import annotations

import math
from typing import Any

from designkit.display.figure import Figure
from designkit.display.numbers import unit
from designkit.display.svg import BLUE, GREEN, ORANGE, new_figure, render_tagged, tag

__all__ = ["TITLE", "rate_figure"]

TITLE = "Chattering and precision against the sampling rate"
"""The figure's title."""
WIDTH_IN, HEIGHT_IN = 4.6, 4.4


def _finite(rows: list[Any], key: str) -> list[tuple[float, float, bool]]:
    out = []
    for r in rows:
        v = r.metrics.get(key)
        if v is not None and math.isfinite(v) and v > 0:
            out.append((float(r.value), float(v), r.passed))
    return out


def _series(ax: Any, fig: Any, points: list[tuple[float, float, bool]], color: str, marker: str, label: str,
            key: str) -> None:
    if not points:
        return
    x = [p[0] for p in points]
    y = [p[1] for p in points]
    (line,) = ax.plot(x, y, "-", color=color, lw=1.0, label=label)
    tag(fig, key, line)
    ok = [(a, b) for a, b, passed in points if passed]
    bad = [(a, b) for a, b, passed in points if not passed]
    if ok:
        (m,) = ax.plot([a for a, _ in ok], [b for _, b in ok], marker, color=color, ms=5, ls="none")
        tag(fig, "verified", m)
    if bad:
        (m,) = ax.plot([a for a, _ in bad], [b for _, b in bad], marker, mfc="white", mec=color, mew=1.3, ms=6,
                       ls="none")
        tag(fig, "not-verified", m)


def _draw(rows: list[Any], eu: str, cu: str) -> Any:
    from designkit.display.figure import few_log_ticks, plain_ticks

    fig, (top, bottom) = new_figure(WIDTH_IN, HEIGHT_IN, rows=2, sharex=True)
    _series(top, fig, _finite(rows, "chatter_rms"), BLUE, "o", "RMS", "chatter-rms")
    _series(top, fig, _finite(rows, "chatter_peak"), ORANGE, "s", "peak", "chatter-peak")
    top.set_ylabel(f"switching part ({unit(cu)})" if cu else "switching part")
    top.set_yscale("log")
    top.legend(loc="best", fontsize=8)
    _series(bottom, fig, _finite(rows, "steady_error"), GREEN, "D", "steady error", "steady-error")
    bottom.set_ylabel(f"steady |x − xD| ({unit(eu)})" if eu else "steady |x − xD|")
    bottom.set_yscale("log")
    bottom.set_xscale("log")
    bottom.set_xlabel("sampling rate (Hz)")
    few_log_ticks(bottom)
    plain_ticks(top.yaxis)
    plain_ticks(bottom.yaxis)
    return fig


def rate_figure(rows: list[Any], eu: str, cu: str, filename: str = "fig-rate-study.svg") -> Figure | None:
    """The figure of the module docstring from the study's ``rows`` (increasing rate); None when no row has a
    finite positive number to draw."""
    if not any(_finite(rows, k) for k in ("chatter_rms", "chatter_peak", "steady_error")):
        return None
    svg, keys, _ = render_tagged(_draw, rows, eu, cu)
    if svg is None:
        return None
    drawn = []
    if "chatter-rms" in keys or "chatter-peak" in keys:
        what = " and ".join(w for k, w in (("chatter-rms", "RMS"), ("chatter-peak", "peak")) if k in keys)
        drawn.append(f"top: the {what} of the command's switching component (the command minus its moving average "
                     "over the loop's time scale)")
    if "steady-error" in keys:
        drawn.append("bottom: the largest |x − xD| over the last tenth of the reference's last plateau")
    marks = []
    if "verified" in keys:
        marks.append("a filled marker where every required check passes")
    if "not-verified" in keys:
        marks.append("an open one where a required check does not")
    left = [r for r in rows if not any(r.metrics.get(k) is not None and math.isfinite(r.metrics[k])
                                       for k in ("chatter_rms", "steady_error"))]
    caption = (f"One run of the spec per sampling rate, the command computed once a period and held (logarithmic "
               f"axes); {'; '.join(drawn)}; {' and '.join(marks)}.")
    if left:
        caption += " Not drawn: " + ", ".join(f"{r.value:g} Hz ({r.outcome})" for r in left) + "."
    return Figure(TITLE, caption, svg, filename, ())
