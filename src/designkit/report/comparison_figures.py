"""The figures of a comparison report: every controller's output and error overlaid, each one's command alone.

The output with the reference, the departure caused by a plant change and the tracking error are drawn on one
axis, one colour per controller; the commands, whose scales may differ by orders of magnitude (a switching law's
tens of volts against a smooth law's few), get one panel per controller, each on its own scale; a load step
(``simulation.perturbation`` inside the run) gets a zoom on the outputs around it.  The plant change and the load
step are marked by dotted vertical lines.  Captions are written from what was drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, JOINT_COLORS, REFERENCE_STYLE, Figure
from designkit.display.numbers import fmt_number, unit
from designkit.display.svg import GREY, new_figure, plot_decimated, render_tagged, tag

__all__ = ["LOAD_LEAD", "comparison_figures"]

LOAD_LEAD = 0.1
"""The load-step zoom starts this fraction of the time from the onset to the end of the run before the onset."""


def _change_time(result: Any) -> float | None:
    change = result.loaded.spec.simulation.plant_change
    return None if change is None else float(change.time)


def _load(result: Any) -> tuple[float, float, str] | None:
    """The load step drawn in the zoom: its onset (s), its value and its unit; None when the scenario has none
    inside every run."""
    perturbation = result.loaded.spec.simulation.perturbation
    runs = [r.simulation for r in result.results if r.simulation is not None]
    if perturbation is None or not runs:
        return None
    tp = float(perturbation.time)
    if not all(0.0 < tp < float(np.asarray(sim.time)[-1]) for sim in runs):
        return None
    value = perturbation.value
    value = value[0] if isinstance(value, list | tuple) and len(value) == 1 else value
    plant = result.results[0].plant if result.results[0].plant is not None else result.results[0].design.plant
    units = list(dict.fromkeys(unit(s.unit) for s in getattr(plant, "disturbances", ())))
    shown = fmt_number(value, 4) if isinstance(value, int | float) else ", ".join(fmt_number(v, 4) for v in value)
    return tp, shown, (units[0] if len(units) == 1 else "")


def _runs(result: Any, what: str) -> list[tuple[int, str, Any, Any]]:
    unchanged = result.unchanged or (None,) * len(result.results)
    return [(k, label, r.simulation, base) for k, (label, r, base) in
            enumerate(zip(result.labels, result.results, unchanged, strict=True))
            if r.simulation is not None and (what != "departure" or base is not None)]


def _column(values: Any, t: np.ndarray) -> np.ndarray:
    return np.asarray(values, dtype=float).reshape(len(t), -1)[:, 0]


def _draw(result: Any, what: str) -> tuple[Any, dict[str, Any]] | None:
    runs = _runs(result, what)
    if not runs:
        return None
    fig, (ax,) = new_figure(7.2, 3.0)
    table = result.table
    for k, label, sim, base in runs:
        t = np.asarray(sim.time, dtype=float)
        if what == "departure":
            x, x0 = _column(sim.tracked_positions, t), _column(base.tracked_positions, np.asarray(base.time))
            n = min(len(x), len(x0))
            t, y = t[:n], x[:n] - x0[:n]
        elif what == "output":
            y = _column(sim.tracked_positions, t)
        else:
            y = _column(sim.tracking_errors, t)
        (line,) = plot_decimated(ax, t, y, color=JOINT_COLORS[k % len(JOINT_COLORS)], lw=1.0, label=label)
        tag(fig, "controller", line)
    if what == "output":
        sim = runs[0][2]
        t = np.asarray(sim.time, dtype=float)
        (ref,) = plot_decimated(ax, t, _column(sim.desired, t), color=GREY, label="reference xD", **REFERENCE_STYLE)
        tag(fig, "reference", ref)
    tc = _change_time(result)
    if tc is not None:
        tag(fig, "plant-change", ax.axvline(tc, color=GREY, label="plant change", **EVENT_STYLE))
    names = {"output": "output x", "error": "tracking error xD − x", "departure": "departure x − x0"}
    ax.set_ylabel(f"{names[what]} ({table.error_unit})")
    ax.set_xlabel("time (s)")
    ax.legend(loc="upper right", fontsize=7, ncols=min(4, len(runs) + 2))
    ax.grid(True, lw=0.3)
    return fig, {"tc": tc}


def _draw_commands(result: Any) -> tuple[Any, dict[str, Any]] | None:
    """One panel per controller, each on its own vertical scale, sharing the time axis."""
    runs = _runs(result, "command")
    if not runs:
        return None
    fig, axes = new_figure(7.2, 0.7 + 1.25 * len(runs), rows=len(runs))
    tc = _change_time(result)
    unit_text = result.table.command_unit
    for ax, (k, label, sim, _) in zip(axes, runs, strict=True):
        t = np.asarray(sim.time, dtype=float)
        (line,) = plot_decimated(ax, t, _column(sim.u_command, t), color=JOINT_COLORS[k % len(JOINT_COLORS)],
                                 lw=0.8, label=label)
        tag(fig, "controller", line)
        if tc is not None:
            tag(fig, "plant-change", ax.axvline(tc, color=GREY, **EVENT_STYLE))
        ax.set_ylabel(f"u ({unit_text})" if unit_text else "u")
        ax.legend(loc="upper right", fontsize=7)
        ax.grid(True, lw=0.3)
    axes[-1].set_xlabel("time (s)")
    return fig, {"tc": tc, "panels": len(runs)}


def _draw_load(result: Any) -> tuple[Any, dict[str, Any]] | None:
    """The outputs around the load step, on axes scaled to that window."""
    load = _load(result)
    runs = _runs(result, "output")
    if load is None or not runs:
        return None
    tp = load[0]
    end = min(float(np.asarray(sim.time)[-1]) for _, _, sim, _ in runs)
    start = max(0.0, tp - LOAD_LEAD * (end - tp))
    fig, (ax,) = new_figure(7.2, 3.0)
    for k, label, sim, _ in runs:
        t = np.asarray(sim.time, dtype=float)
        keep = (t >= start) & (t <= end)
        (line,) = plot_decimated(ax, t[keep], _column(sim.tracked_positions, t)[keep],
                                 color=JOINT_COLORS[k % len(JOINT_COLORS)], lw=1.0, label=label)
        tag(fig, "controller", line)
    sim = runs[0][2]
    t = np.asarray(sim.time, dtype=float)
    keep = (t >= start) & (t <= end)
    (ref,) = plot_decimated(ax, t[keep], _column(sim.desired, t)[keep], color=GREY, label="reference xD",
                            **REFERENCE_STYLE)
    tag(fig, "reference", ref)
    tag(fig, "load-step", ax.axvline(tp, color=GREY, label="load step", **EVENT_STYLE))
    ax.set_xlim(start, end)
    ax.set_ylabel(f"output x ({result.table.error_unit})")
    ax.set_xlabel("time (s)")
    ax.legend(loc="best", fontsize=6.5, ncols=min(3, len(runs) + 2), framealpha=0.85)
    ax.grid(True, lw=0.3)
    return fig, {"tp": tp, "start": start, "end": end, "value": load[1], "unit": load[2]}


def _caption(what: str, keys: Sequence[str], info: dict[str, Any], labels: Sequence[str]) -> str:
    names = {"output": "The output x of each controller's run", "error": "The tracking error xD − x of each run",
             "departure": "What the plant change does to each controller: x − x0, x0 being its output in a run on "
                          "the unchanged plant"}
    if what == "command":
        parts = [f"The command u each controller computed ({', '.join(labels)}), one panel per controller, each on "
                 "its own vertical scale, the time axis shared"]
    elif what == "load":
        size = f" of {info['value']} {info['unit']}".rstrip() if info.get("value") else ""
        parts = [f"Zoom on the load step{size} at {fmt_number(info['tp'], 4)} s: the output x of each controller "
                 f"({', '.join(labels)}) from {fmt_number(info['start'], 4)} s to {fmt_number(info['end'], 4)} s, "
                 "on axes scaled to that window, one colour per controller", "the load step's onset dotted"]
    else:
        parts = [f"{names[what]} ({', '.join(labels)}), one colour per controller, on the same axes"]
    if "reference" in keys:
        parts.append("the reference xD dash-dotted")
    if "plant-change" in keys:
        parts.append(f"the plant change at {fmt_number(info['tc'], 4)} s dotted")
    return "; ".join(parts) + ". Each run is the controller's own run of the shared task."


def comparison_figures(result: Any) -> tuple[Figure, ...]:
    """The figures of a :class:`~designkit.pipeline.ComparisonResult`: outputs, departure from the run on the
    unchanged plant (when there is a plant change), tracking errors (overlaid), the commands (one panel per
    controller) and a zoom on the load step (when the scenario has one)."""
    out = []
    titles = {"output": "Outputs of every controller", "error": "Tracking errors of every controller",
              "command": "Command of each controller", "departure": "Departure caused by the plant change",
              "load": "Response to the load step"}
    for what in ("output", "load", "departure", "error", "command"):
        if what == "command":
            svg, keys, info = render_tagged(_draw_commands, result)
        elif what == "load":
            svg, keys, info = render_tagged(_draw_load, result)
        else:
            svg, keys, info = render_tagged(_draw, result, what)
        if svg is None:
            continue
        labels = [label for _, label, _, _ in _runs(result, what)]
        out.append(Figure(titles[what], _caption(what, keys, info, labels), svg, f"comparison-{what}.svg"))
    return tuple(out)
