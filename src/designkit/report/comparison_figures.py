"""The figures of a comparison report: every controller's output, error and command on the same axes.

One figure per quantity (output with the reference, tracking error, command), one colour per controller,
the plant change marked by a dotted vertical line.  Captions are written from what was drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, JOINT_COLORS, REFERENCE_STYLE, Figure
from designkit.display.svg import GREY, new_figure, plot_decimated, render_tagged, tag

__all__ = ["comparison_figures"]


def _change_time(result: Any) -> float | None:
    change = result.loaded.spec.simulation.plant_change
    return None if change is None else float(change.time)


def _draw(result: Any, what: str) -> tuple[Any, dict[str, Any]] | None:
    unchanged = result.unchanged or (None,) * len(result.results)
    runs = [(label, r.simulation, base) for label, r, base in zip(result.labels, result.results, unchanged,
                                                                   strict=True)
            if r.simulation is not None and (what != "departure" or base is not None)]
    if not runs:
        return None
    fig, (ax,) = new_figure(7.2, 3.0)
    table = result.table
    for k, (label, sim, base) in enumerate(runs):
        t = np.asarray(sim.time, dtype=float)
        if what == "departure":
            x = np.asarray(sim.tracked_positions, dtype=float).reshape(len(t), -1)[:, 0]
            x0 = np.asarray(base.tracked_positions, dtype=float).reshape(len(base.time), -1)[:, 0]
            n = min(len(x), len(x0))
            t, y = t[:n], x[:n] - x0[:n]
        elif what == "output":
            y = np.asarray(sim.tracked_positions, dtype=float).reshape(len(t), -1)[:, 0]
        elif what == "error":
            y = np.asarray(sim.tracking_errors, dtype=float).reshape(len(t), -1)[:, 0]
        else:
            y = np.asarray(sim.u_command, dtype=float).reshape(len(t), -1)[:, 0]
        (line,) = plot_decimated(ax, t, y, color=JOINT_COLORS[k % len(JOINT_COLORS)], lw=1.0, label=label)
        tag(fig, "controller", line)
    if what == "output":
        sim = runs[0][1]
        t = np.asarray(sim.time, dtype=float)
        (ref,) = plot_decimated(ax, t, np.asarray(sim.desired, dtype=float).reshape(len(t), -1)[:, 0],
                                color=GREY, label="reference xD", **REFERENCE_STYLE)
        tag(fig, "reference", ref)
    tc = _change_time(result)
    if tc is not None:
        tag(fig, "plant-change", ax.axvline(tc, color=GREY, label="plant change", **EVENT_STYLE))
    unit = table.command_unit if what == "command" else table.error_unit
    names = {"output": "output x", "error": "tracking error xD − x", "command": "command u",
             "departure": "departure x − x0"}
    ax.set_ylabel(f"{names[what]} ({unit})")
    ax.set_xlabel("time (s)")
    ax.legend(loc="upper right", fontsize=7, ncols=min(4, len(runs) + 2))
    ax.grid(True, lw=0.3)
    return fig, {"tc": tc}


def _caption(what: str, keys: Sequence[str], info: dict[str, Any], labels: Sequence[str]) -> str:
    names = {"output": "The output x of each controller's run", "error": "The tracking error xD − x of each run",
             "command": "The command u each controller computed",
             "departure": "What the plant change does to each controller: x − x0, x0 being its output in a run on "
                          "the unchanged plant"}
    parts = [f"{names[what]} ({', '.join(labels)}), one colour per controller, on the same axes"]
    if "reference" in keys:
        parts.append("the reference xD dash-dotted")
    if "plant-change" in keys:
        parts.append(f"the plant change at {info['tc']:.4g} s dotted")
    return "; ".join(parts) + ". Each run is the controller's own run of the shared task."


def comparison_figures(result: Any) -> tuple[Figure, ...]:
    """The overlay figures of a :class:`~designkit.pipeline.ComparisonResult`: output, departure from the run on
    the unchanged plant (when there is a plant change), tracking error, command."""
    out = []
    titles = {"output": "Outputs of every controller", "error": "Tracking errors of every controller",
              "command": "Commands of every controller", "departure": "Departure caused by the plant change"}
    for what in ("output", "departure", "error", "command"):
        svg, keys, info = render_tagged(_draw, result, what)
        if svg is None:
            continue
        out.append(Figure(titles[what], _caption(what, keys, info, result.labels), svg,
                          f"comparison-{what}.svg"))
    return tuple(out)
