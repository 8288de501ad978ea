"""The sliding-mode servo's figures, drawn from a run: the phase portrait, ``s(t)`` with its band, ``u(t)``.

Each follows the report's conventions (:mod:`designkit.display.figure`: references dash-dot, limits dashed,
events dotted; deterministic SVG with text as ``<text>``, :mod:`designkit.display.svg`): every artist is tagged
with what it shows and the caption is written from the tags drawn, so it names nothing that is not there.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, LIMIT_STYLE, REFERENCE_STYLE, Figure, plain_ticks
from designkit.display.numbers import fmt_number, sci
from designkit.display.svg import BLUE, GREEN, GREY, ORANGE, PURPLE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.sliding_mode.data import SlidingData
from designkit.families.sliding_mode.measure import SlidingRun, measure

__all__ = ["FIGURES", "control_figure", "phase_portrait", "sliding_function_figure"]

MAX_PHASE_POINTS = 4000
"""Points of the phase trajectory drawn per segment (evenly spaced samples)."""
AVERAGE_WINDOW = 2e-3
"""Window (s) of the running mean of the command drawn over the chattering command."""


def _sentence(parts: Sequence[str]) -> str:
    parts = list(parts)
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _present(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


def _onset(t: np.ndarray, pert: np.ndarray) -> float | None:
    idx = np.flatnonzero(np.any(np.asarray(pert, float).reshape(len(t), -1) != 0.0, axis=1))
    return float(t[idx[0]]) if idx.size and idx[0] > 0 else None


def _caption(lead: str, phrases: dict[str, str], keys: Sequence[str]) -> str:
    also = [phrases[k] for k in keys if k in phrases]
    return lead + (" Drawn: " + _sentence(also) + "." if also else "")


# ----------------------------------------------------------------------------- phase portrait


def _draw_phase(run: SlidingRun, c: float) -> tuple[Any, dict[str, Any]]:
    d = run.data
    e, x2 = d["e"], d["x2"]
    fig, (ax,) = new_figure(6.8, 4.6)
    for k, (a, b) in enumerate(run.segments):
        idx = np.unique(np.linspace(a, b - 1, min(b - a, MAX_PHASE_POINTS)).astype(int))
        tag(fig, "trajectory", *ax.plot(e[idx], x2[idx], color=BLUE, lw=1.2,
                                        label="trajectory (e, e')" if k == 0 else None))
        tag(fig, "start", *ax.plot([e[a]], [x2[a]], ls="none", marker="o", ms=5, color=BLUE,
                                   label="start of a segment" if k == 0 else None))
        r = run.reach[k]
        if r is not None:
            tag(fig, "reach", *ax.plot([e[a + r]], [x2[a + r]], ls="none", marker="D", ms=5, color=PURPLE,
                                       label="reaching the band" if k == 0 else None))
    lo_e, hi_e = ax.get_xlim()
    lo_v, hi_v = ax.get_ylim()
    span = max(hi_e - lo_e, 1e-12)
    lo_e, hi_e = min(lo_e, -0.08 * span), max(hi_e, 0.08 * span)  # both sides of the switching line e = 0
    grid = np.array([lo_e - span, hi_e + span])
    tag(fig, "sliding-line", *ax.plot(grid, -c * grid, color=GREEN, **REFERENCE_STYLE,
                                      label=f"sliding line s = 0: e' = −{fmt_number(c)} e"))
    tag(fig, "switching-line", ax.axvline(0.0, color=GREY, **LIMIT_STYLE, label="switching line e = 0"))
    big = 10 * max(abs(lo_v), abs(hi_v), c * span)
    region = ax.fill([0, grid[1], grid[1], 0], [big, big, -c * grid[1], 0], color=ORANGE, alpha=0.08, lw=0,
                     label="e s > 0: ψ = α")
    region += ax.fill([0, grid[0], grid[0], 0], [-big, -big, -c * grid[0], 0], color=ORANGE, alpha=0.08, lw=0)
    tag(fig, "alpha-region", *region)
    ax.set_xlim(lo_e, hi_e)
    ax.set_ylim(lo_v, hi_v)
    ax.set_xlabel("error e = x1 − xD (rad)")
    ax.set_ylabel("e' = x2 (rad/s)")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {"segments": len(run.segments)}


_PHASE = {
    "trajectory": "the simulated trajectory in the error plane (blue)",
    "start": "where each reference segment starts (○)",
    "reach": "where |s| first enters the chattering band (◆)",
    "sliding-line": "the sliding line s = 0, e' = −c e (dash-dot), along which the error decays at the sliding pole",
    "switching-line": "the switching line e = 0 of the gain ψ (dashed)",
    "alpha-region": "the region e s > 0 where ψ = α (shaded); elsewhere ψ = β",
}


def phase_portrait(result: Any) -> Figure | None:
    """``(e, e')`` of the run with the sliding line ``e' = -c e`` and the switching line ``e = 0``."""
    if result.simulation is None or not isinstance(result.design.data, SlidingData):
        return None
    c = float(result.design.data.c)
    run = measure(result.design, result.simulation)
    svg, keys, info = render_tagged(_draw_phase, run, c)
    seg = "" if info["segments"] == 1 else f" over its {info['segments']} reference segments"
    lead = (f"Phase portrait of the simulated run{seg}: the position error against its rate. The law switches "
            f"between two structures across e s = 0 and its relay across s = 0, so the trajectory is driven onto "
            f"the line s = e' + {fmt_number(c)} e = 0 and slides along it to the origin.")
    return Figure("Sliding mode: phase portrait", _caption(lead, _PHASE, keys), svg, "fig-sliding_mode-phase.svg",
                  _present(result, ("sliding_existence", "sliding_reaching")))


# ----------------------------------------------------------------------------- s(t)


def _draw_s(run: SlidingRun, t_pert: float | None) -> tuple[Any, dict[str, Any]]:
    d = run.data
    t, s = d["time"], d["s"]
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "band", ax.fill_between([t[0], t[-1]], -run.band, run.band, color=GREEN, alpha=0.2, lw=0,
                                     label=f"band |s| ≤ {sci(run.band)} rad/s"))
    tag(fig, "s", *plot_decimated(ax, t, s, color=BLUE, lw=1.0, label="s = x2 + c e"))
    for k, (a, _) in enumerate(run.segments):
        r = run.reach[k]
        if r is not None:
            tag(fig, "reaching", ax.axvline(t[a + r], color=PURPLE, **EVENT_STYLE,
                                            label="reaching time" if k == 0 else None))
    if t_pert is not None:
        tag(fig, "perturbation-onset", ax.axvline(t_pert, color=RED, **EVENT_STYLE, label="perturbation onset"))
    ax.set_yscale("symlog", linthresh=run.band, linscale=1.0)
    plain_ticks(ax.yaxis)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("s (rad/s)")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


_S = {
    "band": "the band |s| ≤ δ (green) the command held over one step can leave",
    "s": "the sliding function s (blue)",
    "reaching": "the reaching time, where |s| first enters the band (dotted)",
    "perturbation-onset": "the perturbation's onset (dotted, red)",
}


def sliding_function_figure(result: Any) -> Figure | None:
    """``s(t)`` on a symmetric-log axis linear within the band, with the band and the reaching time."""
    sim = result.simulation
    if sim is None or not isinstance(result.design.data, SlidingData):
        return None
    run = measure(result.design, sim)
    svg, keys, _ = render_tagged(_draw_s, run, _onset(np.asarray(sim.time), sim.perturbation))
    lead = (f"The sliding function over the run. The axis is linear within ±{sci(run.band)} rad/s, the band, and "
            "logarithmic beyond, so the reaching phase and the chattering inside the band are both visible.")
    return Figure("Sliding mode: the sliding function", _caption(lead, _S, keys), svg,
                  "fig-sliding_mode-sliding-function.svg", _present(result, ("reaching_time", "sliding_band",
                                                                             "chattering")))


# ----------------------------------------------------------------------------- u(t)


def _draw_u(run: SlidingRun, pert: np.ndarray, window: int) -> tuple[Any, dict[str, Any]]:
    d = run.data
    t, u = d["time"], d["u"]
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "u", *plot_decimated(ax, t, u, color=ORANGE, lw=0.9, alpha=0.8, label="u (commanded, held per step)"))
    if window > 1 and u.size > window:
        mean = np.convolve(u, np.ones(window) / window, mode="valid")
        tm = t[window // 2: window // 2 + mean.size]
        tag(fig, "u-mean", *plot_decimated(ax, tm, mean, color=PURPLE, lw=1.3, label="u averaged"))
    if np.any(pert != 0):
        tag(fig, "perturbation", *plot_decimated(ax, t, -pert, color=RED, lw=0.9, label="−ξ (perturbation)"))
    ax.axhline(0.0, color=GREY, lw=0.6)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("control (N·m)")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


_U = {
    "u": "the commanded torque (orange; min/max per pixel, so the chattering shows as its envelope)",
    "u-mean": "its running mean over {window} (purple), the equivalent control the switching averages to",
    "perturbation": "the negated perturbation −ξ (red), which the averaged command cancels while sliding",
}


def control_figure(result: Any) -> Figure | None:
    """The command with its running mean (the equivalent control) and the perturbation."""
    sim = result.simulation
    if sim is None or not isinstance(result.design.data, SlidingData):
        return None
    run = measure(result.design, sim)
    dt = float(sim.settings["dt"])
    window = max(1, round(AVERAGE_WINDOW / dt))
    pert = np.asarray(sim.perturbation, float).reshape(len(sim.time), -1)[:, 0]
    svg, keys, _ = render_tagged(_draw_u, run, pert, window)
    phrases = {k: v.format(window=f"{fmt_number(window * dt, 3)} s") for k, v in _U.items()}
    lead = (f"The control the switching law commands, held over each {fmt_number(dt, 3)} s step; after reaching it "
            f"switches {'' if run.switching_frequency is None else fmt_number(run.switching_frequency, 3) + ' '}"
            "times per second.")
    return Figure("Sliding mode: the control", _caption(lead, phrases, keys), svg, "fig-sliding_mode-control.svg",
                  _present(result, ("chattering",)))


FIGURES = (phase_portrait, sliding_function_figure, control_figure)
"""The family's figures, in report order."""
