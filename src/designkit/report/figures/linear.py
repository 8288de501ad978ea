"""The ideal linear response: the nominal closed loop driven by the spec's reference, and the control it needs."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from designkit.display.figure import JOINT_COLORS, REFERENCE_STYLE, Figure, joint_units
from designkit.display.svg import drawable, new_figure, render_tagged, tag
from designkit.report.figures.control import common_limit, control_limit
from designkit.report.figures.naming import joint_label, position_name

__all__ = ["linear_figure"]


def _time_grid(design: Any, spec: Any, horizon: float) -> np.ndarray:
    duration = spec.simulation.duration
    if duration is None:
        slowest = min((abs(p.real) for p in np.linalg.eigvals(design.closed_loop.A) if abs(p.real) > 1e-9),
                      default=1.0)
        duration = 8.0 / slowest
        req = spec.requirements
        if req is not None and req.settling_time is not None:
            duration = max(duration, 2.0 * req.settling_time)
        duration += horizon
    return np.linspace(0.0, float(duration), 1500)


def _draw_linear(design: Any, t: np.ndarray, ref: np.ndarray, positions: np.ndarray, u: np.ndarray,
                 limit: float | None) -> Any:
    fig, (ax, ax_u) = new_figure(6.8, 4.6, rows=2)
    n = positions.shape[1]
    for j in range(n):
        color = JOINT_COLORS[j % len(JOINT_COLORS)]
        tag(fig, "reference", *ax.plot(t, drawable(ref[:, j, 0]), color=color, **REFERENCE_STYLE,
                                       label=f"xD{joint_label(design, j)} (reference)"))
        tag(fig, "position", *ax.plot(t, drawable(positions[:, j]), color=color,
                                      label=f"{position_name(design, j)} (linear, nominal)"))
    ax.set_ylabel(f"position ({joint_units(design.plant, 'positions')})")
    ax.legend(loc="best", framealpha=0.9)
    for k in range(u.shape[1]):
        tag(fig, "control", *ax_u.plot(t, drawable(u[:, k]), color=JOINT_COLORS[k % len(JOINT_COLORS)],
                                       label=design.plant.inputs[k].name))
    info = {}
    if limit is not None:
        control_limit(fig, ax_u, limit, u)
        info["limit"] = limit
    ax_u.set_xlabel("time (s)")
    ax_u.set_ylabel(f"control ({joint_units(design.plant, 'inputs')})")
    ax_u.legend(loc="best", framealpha=0.9)
    ax_u.set_xlim(t[0], t[-1])
    return fig, info


def _linear_caption(keys: Sequence[str], word: str, info: Mapping[str, Any]) -> str:
    text = "The nominal closed loop linearized at its operating point"
    if "reference" in keys:
        text += f", driven by the {word} reference (dash-dot)"
    text += ", without saturation, delay, noise or perturbation: the response the design predicts."
    if "control" in keys:
        text += " Bottom: the control it needs"
        if "control-limit" in keys:
            text += f", with the limit |u| ≤ {info['limit']:g} N·m (dashed)."
        elif "control-limit-offscale" in keys:
            text += f" (the limit |u| ≤ {info['limit']:g} N·m is off scale, named in the legend only)."
        else:
            text += "."
    return text


def linear_figure(result: Any) -> Figure | None:
    """The nominal linear closed loop driven by the spec's reference (no nonlinearity, delay, noise)."""
    from designkit.families import family
    from designkit.simulation.linear import linear_response
    from designkit.simulation.reference import reference_for

    design, spec = result.design, result.loaded.spec
    if design.closed_loop is None or family(design.kind).motion is not None:
        return None  # a task-space reference does not drive the joint-space linearization
    kind = family(design.kind).reference
    reference = reference_for(kind, spec.simulation, len(design.plant.positions))
    t = _time_grid(design, spec, reference.horizon)
    ref = reference.evaluate(t)
    positions, u = linear_response(design, t, ref)
    req = spec.requirements
    limit = common_limit(req.max_control) if req is not None else None
    word = "trajectory" if kind == "trajectory" else "step"
    svg, keys, info = render_tagged(_draw_linear, design, t, ref, positions, u, limit)
    return Figure(f"Ideal linear {word} response", _linear_caption(keys, word, info), svg,
                  "fig-linear-response.svg")
