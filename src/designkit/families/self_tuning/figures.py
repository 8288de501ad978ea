"""The self-tuning regulator's figures, drawn from a run: the estimates against the true sampled link's parameters,
the output against the reference with the command, and the excitation indicator with the Sylvester matrix's
condition number.

Captions are written from the keys of what was drawn (:func:`~designkit.display.svg.render_tagged`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, LIMIT_STYLE, REFERENCE_STYLE, Figure
from designkit.display.svg import BLUE, GREEN, GREY, ORANGE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.self_tuning.checks import EXCITATION_MIN, excitation_summary
from designkit.families.self_tuning.runs import samples, sylvester_condition, true_theta

__all__ = ["FIGURES", "conditioning_figure", "estimates_figure", "loop_figure"]


def _context(result: Any) -> Any:
    from designkit.verification.suite import Context

    return Context(result.loaded.spec, result.simulation, result.loaded.spec.numerics.solver, result.plant)


def _plant(result: Any) -> Any:
    return result.plant if result.plant is not None else result.design.plant


def _present(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


def _onset(result: Any, axes: Sequence[Any], fig: Any) -> float | None:
    change = result.loaded.spec.simulation.plant_change
    if change is None:
        return None
    for ax in axes:
        tag(fig, "plant-change", ax.axvline(change.time, color=RED, **EVENT_STYLE))
    return float(change.time)


def _draw_estimates(result: Any) -> tuple[Any, dict[str, Any]]:
    d = result.design
    s = samples(result.simulation, d)
    true = true_theta(result.loaded.spec, _plant(result), d, s.t)
    names = d.data.parameters
    what = "plant" if d.data.settings.form == "arx" else "link"
    fig, axes = new_figure(6.8, 1.9 * len(names) + 0.8, rows=len(names))
    axes = list(np.atleast_1d(axes))
    for j, ax in enumerate(axes):
        tag(fig, "true", *plot_decimated(ax, s.t, true[:, j], color=GREEN, **LIMIT_STYLE,
                                         label=f"{names[j]} of the true sampled {what}"))
        tag(fig, "estimate", *plot_decimated(ax, s.t, s.theta[:, j], color=BLUE, lw=1.2,
                                             label=f"{names[j]} estimated"))
        lo, hi = np.nanmin(np.r_[true[:, j], s.theta[:, j]]), np.nanmax(np.r_[true[:, j], s.theta[:, j]])
        pad = 0.15 * ((hi - lo) or abs(hi) or 1.0)
        if np.isfinite(lo) and np.isfinite(hi):
            ax.set_ylim(lo - pad, hi + pad)
        unit = d.data.units[j]
        ax.set_ylabel(names[j] + (f" ({unit})" if unit else ""), fontsize=7)
        ax.legend(loc="best", framealpha=0.9, fontsize=7)
    info = {"onset": _onset(result, axes, fig)}
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(s.t[0], s.t[-1])
    return fig, info


def estimates_figure(result: Any) -> Figure | None:
    """The estimates against the exactly discretized parameters of the true link, one panel per parameter."""
    if result.simulation is None:
        return None
    svg, keys, info = render_tagged(_draw_estimates, result)
    st = result.design.data.settings
    form = {"speed": "speed measured", "position": "speed not measured (position differences)"}.get(
        st.form, "ARX model (na = {}, nb = {}, d = {})".format(*st.orders) if st.orders else "")
    what = "plant" if st.form == "arx" else "link"
    caption = (f"The recursive least-squares estimates ({form}, blue) against the parameters of the true {what} "
               "discretized exactly with a zero-order hold (dashed green), one panel per parameter, at the sample "
               "instants.")
    if "plant-change" in keys:
        caption += (f" The dotted red line marks the step change of the link at t = {info['onset']:.4g} s, which "
                    "the controller is not told of.")
    return Figure(f"Estimated against true sampled-{what} parameters", caption, svg, "fig-selftune-estimates.svg",
                  _present(result, ("estimate_convergence", "parameter_step")))


def _draw_loop(result: Any) -> tuple[Any, dict[str, Any]]:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    fig, (ax, ax_u) = new_figure(6.8, 4.8, rows=2)
    tag(fig, "reference", *plot_decimated(ax, t, sim.desired[:, 0], color=GREY, **REFERENCE_STYLE, label="xD"))
    arx = result.design.data.settings.form == "arx"
    tag(fig, "output", *plot_decimated(ax, t, sim.position, color=BLUE, lw=1.2, label="y" if arx else "x1"))
    tag(fig, "command", *plot_decimated(ax_u, t, np.asarray(sim.u_command)[:, 0], color=ORANGE, lw=1.0,
                                        label="u (held over each sample)"))
    info = {"onset": _onset(result, (ax, ax_u), fig), "peak": float(np.nanmax(np.abs(sim.u_command)))}
    ax.set_ylabel("output" if arx else "position (rad)")
    ax_u.set_ylabel("command" if arx else "command (N·m)")
    ax_u.set_xlabel("time (s)")
    ax_u.set_xlim(t[0], t[-1])
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    ax_u.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, info


def loop_figure(result: Any) -> Figure | None:
    """The link's position against the reference (top) and the command (bottom)."""
    if result.simulation is None:
        return None
    svg, keys, info = render_tagged(_draw_loop, result)
    if result.design.data.settings.form == "arx":
        caption = ("Top: the reference xD (dash-dot) and the plant's output y (blue) under the self-tuning regulator. "
                   f"Bottom: the command u, held between samples (peak |u| = {info['peak']:.4g}).")
    else:
        caption = ("Top: the reference xD (dash-dot) and the link's position x1 (blue) under the self-tuning "
                   f"regulator. Bottom: the command u, held between samples (peak |u| = {info['peak']:.4g} N·m).")
    if "plant-change" in keys:
        caption += f" The dotted red line marks the change of the plant at t = {info['onset']:.4g} s."
    return Figure("Self-tuning loop: output and command", caption, svg, "fig-selftune-loop.svg",
                  _present(result, ("true_loop",)))


def _draw_conditioning(result: Any) -> tuple[Any, dict[str, Any]]:
    d = result.design
    e = excitation_summary(d, _context(result))
    s = e["samples"]
    cond = sylvester_condition(s, d)
    fig, (ax, ax_c) = new_figure(6.8, 4.8, rows=2)
    norm = np.where(np.asarray(e["norm"]) > 0, e["norm"], np.nan)
    tag(fig, "indicator", *plot_decimated(ax, s.t, norm, color=BLUE, lw=1.2,
                                          label="smallest normalized eigenvalue of the windowed information matrix"))
    tag(fig, "threshold", ax.axhline(EXCITATION_MIN, color=RED, **LIMIT_STYLE, label=f"threshold {EXCITATION_MIN:g}"))
    ax.set_yscale("log")
    tag(fig, "condition", *plot_decimated(ax_c, s.t, cond, color=GREEN, lw=1.2, label="Sylvester condition number"))
    ax_c.set_yscale("log")
    info = {"onset": _onset(result, (ax, ax_c), fig), "window": e["window"] * d.data.settings.Ts}
    ax.set_ylabel("excitation (–)")
    ax_c.set_ylabel("condition number (–)")
    ax_c.set_xlabel("time (s)")
    ax_c.set_xlim(s.t[0], s.t[-1])
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    ax_c.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, info


def conditioning_figure(result: Any) -> Figure | None:
    """The excitation indicator with its threshold (top) and the Sylvester matrix's condition number (bottom)."""
    if result.simulation is None:
        return None
    svg, keys, info = render_tagged(_draw_conditioning, result)
    caption = (f"Top: the excitation indicator, the smallest eigenvalue of the information matrix of the last "
               f"{info['window']:g} s of regressors scaled to a unit diagonal (blue, logarithmic; 0, collinear "
               "regressors, is not drawn)")
    caption += ", with the threshold below which the estimator is reported unexcited (dashed red)." if \
        "threshold" in keys else "."
    caption += (" Bottom: the 2-norm condition number of the Sylvester matrix of the estimated model at each sample "
                "(green, logarithmic): it grows as the estimated A and B approach a common factor.")
    if "plant-change" in keys:
        caption += f" The dotted red line marks the change of the link at t = {info['onset']:.4g} s."
    return Figure("Excitation of the estimator and conditioning of the design", caption, svg,
                  "fig-selftune-conditioning.svg", _present(result, ("excitation", "characteristic_polynomial")))


FIGURES = (estimates_figure, loop_figure, conditioning_figure)
"""The family's figures, in report order."""
