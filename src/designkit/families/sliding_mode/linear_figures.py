"""The sliding-mode servo's own figures on a linear plant: the sliding function against the band a held step can
leave, and the command against its equivalent part (:mod:`~designkit.families.sliding_mode.linear`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, Figure, plain_ticks
from designkit.display.numbers import sci
from designkit.display.svg import BLUE, GREEN, ORANGE, PURPLE, new_figure, plot_decimated, render_tagged, tag
from designkit.families.sliding_mode.linear import LinearSlidingData

__all__ = ["LINEAR_FIGURES"]


def _errors(result: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    info: LinearSlidingData = result.design.data
    sim = result.simulation
    t = np.asarray(sim.time, float)
    xd = np.asarray(sim.reference, float)[:, 0, 0]
    err = np.asarray(sim.state, float) - np.outer(xd, np.asarray(info.x_rest, float))
    return t, err, xd


def _draw_s(t: np.ndarray, s: np.ndarray, band: np.ndarray, t_reach: float | None, unit: str) -> tuple[Any, dict]:
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "band", ax.fill_between(t, -band, band, color=GREEN, alpha=0.2, lw=0, label="band |s| ≤ h S(x̃)"))
    tag(fig, "s", *plot_decimated(ax, t, s, color=BLUE, lw=1.0, label="s = c (x − x* xD)"))
    if t_reach is not None:
        tag(fig, "reaching", ax.axvline(t_reach, color=PURPLE, **EVENT_STYLE, label="reaching time"))
    floor = float(np.min(band[band > 0])) if np.any(band > 0) else 1.0
    ax.set_yscale("symlog", linthresh=floor, linscale=1.0)
    plain_ticks(ax.yaxis)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"s ({unit})")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


def sliding_function(result: Any) -> Figure | None:
    """``s(t)`` on a symmetric-log axis with the band ``h S(x~(t))`` and the reaching time."""
    if result.simulation is None or not isinstance(result.design.data, LinearSlidingData):
        return None
    info: LinearSlidingData = result.design.data
    t, err, _ = _errors(result)
    s = err @ np.asarray(info.c, float)
    band = float(info.max_step) * info.rate_bound(err)
    if info.boundary_layer is not None:
        band = np.maximum(band, float(info.boundary_layer))
    inside = np.flatnonzero(np.abs(s) <= band)
    t_reach = float(t[inside[0]]) if inside.size else None
    unit = f"{result.design.plant.inputs[0].unit}·s"
    svg, keys, _ = render_tagged(_draw_s, t, s, band, t_reach, unit)
    phrases = {"band": "the band h S(x̃) (green) a command held over one step can leave around s = 0",
               "s": "the sliding function (blue)", "reaching": "the reaching time (dotted)"}
    drawn = [phrases[k] for k in keys if k in phrases]
    caption = (f"The sliding function over the run (linear within ±{sci(float(np.min(band)))} {unit} and logarithmic "
               "beyond): the switching gain drives it onto s = 0, and the held command keeps it within the band."
               + (" Drawn: " + "; ".join(drawn) + "." if drawn else ""))
    return Figure("Sliding mode: the sliding function", caption, svg, "fig-sliding_mode-linear-s.svg",
                  tuple(n for n in ("sliding_linear_reaching_time", "sliding_linear_band")
                        if n in {c.name for c in result.checks}))


def _draw_u(t: np.ndarray, u: np.ndarray, ueq: np.ndarray, unit: str) -> tuple[Any, dict]:
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "u", *plot_decimated(ax, t, u, color=BLUE, lw=0.6, label="u (held over each step)"))
    tag(fig, "ueq", *plot_decimated(ax, t, ueq, color=ORANGE, lw=1.2, label="u* xD − c A0 x̃ (nominal equivalent)"))
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"u ({unit})")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


def command(result: Any) -> Figure | None:
    """``u(t)`` against the nominal equivalent control ``u* xD - c A0 x~``: the switching term is the gap."""
    if result.simulation is None or not isinstance(result.design.data, LinearSlidingData):
        return None
    info: LinearSlidingData = result.design.data
    t, err, xd = _errors(result)
    u = np.asarray(result.simulation.u_command, float).reshape(len(t), -1)[:, 0]
    ueq = info.u_rest * xd - err @ np.asarray(info.cA0, float)
    unit = result.design.plant.inputs[0].unit
    svg, keys, _ = render_tagged(_draw_u, t, u, ueq, unit)
    caption = ("The command over the run against the nominal model's equivalent control: their gap is the switching "
               "term −(k0 + Σ kᵢ|x̃ᵢ|) sign(s), which dominates the perturbation and what the nominal model gets "
               "wrong on the box.")
    return Figure("Sliding mode: the command", caption, svg, "fig-sliding_mode-linear-u.svg", ())


LINEAR_FIGURES = (sliding_function, command)
