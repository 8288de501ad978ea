"""Figures of PID/sliding mode on a robot, drawn from the run: every joint's ``slm_i`` against its band, the
perturbation ``|xi_i(t)|`` against the proven bound and ``M_i``, and each joint's distance from its sliding motion.

Each joint's curve is scaled by its own band or bound, so that one axis shows every joint; captions are written from
the tags drawn (:func:`designkit.display.svg.render_tagged`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.figure import Figure
from designkit.display.svg import BLUE, GREEN, ORANGE, PURPLE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.pid_sliding_mode.data import RobotSlidingData
from designkit.families.pid_sliding_mode.measure import hold_of
from designkit.families.pid_sliding_mode.robot_checks import IN_BAND, PRECISION, XI, bands, run_perturbation
from designkit.families.pid_sliding_mode.surface import ideal_motion, surface

__all__ = ["ROBOT_FIGURES"]

COLORS = (BLUE, ORANGE, GREEN, PURPLE, RED, "#8c564b", "#17becf", "#7f7f7f")


def _evidence(result: Any, names: tuple[str, ...]) -> tuple[str, ...]:
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


def _ok(result: Any) -> bool:
    sim = result.simulation
    return sim is not None and isinstance(result.design.data, RobotSlidingData) and "slm1" in sim.signals


def _draw_slm(result: Any) -> tuple[Any, dict[str, Any]]:
    info, sim = result.design.data, result.simulation
    t = np.asarray(sim.time, float)
    band = bands(info, hold_of(sim))
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "band", ax.fill_between([t[0], t[-1]], -1.0, 1.0, color=GREEN, alpha=0.15, lw=0,
                                     label="the band, |slm_i| ≤ band_i"))
    for i in range(len(band)):
        s = np.asarray(sim.signals[f"slm{i + 1}"], float) / band[i]
        tag(fig, "slm", *plot_decimated(ax, t, s, color=COLORS[i % len(COLORS)], lw=0.9,
                                        label=f"joint {i + 1} (band {band[i]:.3g} rad·s)"))
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("slm_i / band_i")
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, {}


def sliding_variables_figure(result: Any) -> Figure | None:
    """Every joint's ``slm_i(t)`` divided by its band."""
    if not _ok(result):
        return None
    svg, keys, _ = render_tagged(_draw_slm, result)
    cap = "Each joint's sliding variable divided by its band: the run stays in its band where the curve is within ±1"
    cap += " (the green strip)." if "band" in keys else "."
    return Figure("PID/sliding mode on every joint: the sliding variables", cap, svg, "fig-pid-sm-robot-slm.svg",
                  _evidence(result, (IN_BAND,)))


def _draw_xi(result: Any) -> tuple[Any, dict[str, Any]]:
    info, sim = result.design.data, result.simulation
    t = np.asarray(sim.time, float)
    xi, inside, _ = run_perturbation(result.design, sim, getattr(result, "plant", None))
    bound, M = np.array(info.bound), np.array(info.M)
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "bound", ax.axhline(1.0, color="black", lw=1.0, label="the proven bound"))
    for i in range(len(bound)):
        c = COLORS[i % len(COLORS)]
        tag(fig, "xi", *plot_decimated(ax, t, np.abs(xi[:, i]) / bound[i], color=c, lw=0.9,
                                       label=f"joint {i + 1} (bound {bound[i]:.3g} N·m)"))
        tag(fig, "M", ax.axhline(M[i] / bound[i], color=c, lw=0.8, ls="--"))
        out = ~inside[:, i]
        if out.any():
            tag(fig, "outside", ax.plot(t[out], np.abs(xi[out, i]) / bound[i], ls="none", marker=".", ms=3,
                                        color=c)[0])
    ax.set_yscale("log")
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|ξ_i(t)| / proven sup|ξ_i|")
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, {}


def perturbation_figure(result: Any) -> Figure | None:
    """``|xi_i(t)|`` divided by its proven bound, with ``M_i`` (dashed) and the samples outside the box (dots)."""
    if not _ok(result):
        return None
    svg, keys, _ = render_tagged(_draw_xi, result)
    parts = ["The perturbation each joint's relay met along the run, divided by its proven bound (the black line at 1)"]
    if "M" in keys:
        parts.append("each relay amplitude M_i on the same scale (dashed, the joint's colour)")
    if "outside" in keys:
        parts.append("dots: samples outside the joint's box, where the bound does not speak (the step's instant)")
    return Figure("PID/sliding mode on every joint: the perturbation against the hierarchy's bound",
                  "; ".join(parts) + ".", svg, "fig-pid-sm-robot-xi.svg", _evidence(result, (XI,)))


def _draw_deviation(result: Any) -> tuple[Any, dict[str, Any]]:
    d = result.design
    info, sim = d.data, result.simulation
    t = np.asarray(sim.time, float)
    x, ref = np.asarray(sim.state, float), np.asarray(sim.reference, float)
    sf = surface(d.poles)
    fig, (ax,) = new_figure(6.8, 3.6)
    for i in range(len(info.M)):
        q = x[:, d.plant.positions[i]]
        ideal = ideal_motion(sf, t, ref[:, i, :], info.form, start=float(q[0]))[0]
        tag(fig, "deviation", *plot_decimated(ax, t, q - ideal, color=COLORS[i % len(COLORS)], lw=0.9,
                                              label=f"joint {i + 1}"))
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("q_i − sliding motion (rad)")
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, {}


def deviation_figure(result: Any) -> Figure | None:
    """Each joint's distance from its plant-independent sliding motion."""
    if not _ok(result):
        return None
    svg, _, _ = render_tagged(_draw_deviation, result)
    return Figure("PID/sliding mode on every joint: the distance from the sliding motions",
                  "Each joint's position minus its sliding motion (the reference through 1/(1 + a1 s + a2 s²), or the "
                  "trajectory when tracking): what the boundary layer leaves.", svg, "fig-pid-sm-robot-deviation.svg",
                  _evidence(result, (PRECISION,)))


ROBOT_FIGURES = (sliding_variables_figure, perturbation_figure, deviation_figure)
"""The robot design's figures, in report order."""
