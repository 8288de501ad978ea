"""The tracking-bounds check's figure: the error over the uncertainty box against the requirement's band."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import JOINT_COLORS, Figure
from designkit.display.svg import RED, new_figure, plot_decimated, render

__all__ = ["tracking_bounds_figure"]


def _draw(data: Any, names: Sequence[str], limit: float | None, parameter: str | None) -> Any:
    t = np.asarray(data["time"], float)
    envelope = np.asarray(data["envelope"], float)
    peaks = np.asarray(data.get("peaks", []), float)
    thetas = np.asarray(data.get("parameters", []), float)
    scatter = parameter is not None and peaks.size and thetas.ndim == 2 and thetas.shape[1] == 1
    fig, axes = new_figure(6.8, 6.0 if scatter else 3.2, rows=2 if scatter else 1, sharex=False,
                           layout="constrained" if scatter else "fixed")
    ax = axes[0]
    for j in range(envelope.shape[1]):
        plot_decimated(ax, t, envelope[:, j], color=JOINT_COLORS[j % len(JOINT_COLORS)], label=names[j])
    top = float(np.nanmax(envelope)) if np.isfinite(envelope).any() else 1.0
    if limit is not None:
        ax.axhline(limit, color=RED, ls="--", lw=1.2, label="requirement")
        top = max(top, limit)
    ax.set_ylim(0.0, 1.15 * top if top > 0 else 1.0)  # the band is inside the axis range
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("largest |q − qD| over the box (rad)")
    ax.legend(loc="best", framealpha=0.9, ncols=3)
    if scatter:
        ax2 = axes[1]
        order = np.argsort(thetas[:, 0])
        for j in range(peaks.shape[1]):
            ax2.plot(thetas[order, 0], peaks[order, j], "o-", ms=3, lw=0.8, color=JOINT_COLORS[j % len(JOINT_COLORS)],
                     label=names[j])
        if limit is not None:
            ax2.axhline(limit, color=RED, ls="--", lw=1.2, label="requirement")
        ax2.set_xlabel(parameter)
        ax2.set_ylabel("peak |q − qD| of the run (rad)")
        ax2.set_ylim(bottom=0.0)
        ax2.legend(loc="best", framealpha=0.9, ncols=3)
    return fig


def tracking_bounds_figure(result: Any, check: Any) -> Figure | None:
    """The tracking error's envelope over every run of the box (and, for one uncertain parameter, each run's peak
    against the parameter), with the requirement's band."""
    if not check.data or "envelope" not in check.data:
        return None
    plant = result.design.plant
    names = [plant.states[i].name for i in plant.positions]
    params = list(check.data.get("parameter_names", ()))
    parameter = params[0] if len(params) == 1 else None
    if parameter is not None:
        from designkit.display.numbers import unit as typeset

        found = next((p for p in getattr(plant, "parameters", ()) if getattr(p, "name", None) == parameter), None)
        if found is not None and getattr(found, "unit", ""):
            parameter = f"{parameter} ({typeset(found.unit)})"
    req = result.loaded.spec.requirements
    limit = float(req.tracking_error) if req is not None and req.tracking_error is not None else None
    runs = check.certificate.get("runs")
    caption = (f"Top: at each instant, the largest tracking error of each joint over the {runs} runs on the true plant "
               "(the corners of the uncertainty box and its samples)")
    if parameter is not None:
        caption += f"; bottom: each run's peak error against {parameter}"
    caption += (f"; the dashed line is the {limit:g} rad requirement." if limit is not None else
                "; no tracking-error requirement was given.")
    worst = check.certificate.get("worst_parameters", {})
    if worst:
        caption += " The worst run is at " + ", ".join(f"{k} = {v:.4g}" for k, v in worst.items()) + "."
    return Figure("Tracking error over the uncertainty box", caption, render(_draw, check.data, names, limit,
                  parameter), "fig-tracking-bounds.svg", (check.name,))
