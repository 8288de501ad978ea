"""The feedforward/feedback MRAC's figure: the plant's output against the reference model's and the command (top),
the adapted parameters against their ideal values (bottom) -- Astrom and Wittenmark's Figs. 5.4 and 5.5 in one."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.figure import LIMIT_STYLE, REFERENCE_STYLE, Figure
from designkit.display.svg import BLUE, GREEN, GREY, ORANGE, PURPLE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.mrac.data import RegressorData

__all__ = ["regressor_figure"]

COLORS = (BLUE, ORANGE, PURPLE, RED, GREEN, GREY)


def _draw(result: Any) -> tuple[Any, dict[str, Any]]:
    from designkit.families.mrac.regressor_checks import final_ideal

    sim, d = result.simulation, result.design
    x: RegressorData = d.data
    t = np.asarray(sim.time, dtype=float)
    y = np.asarray(sim.state, dtype=float)[:, sim.positions[0]]
    fig, (ax, bx) = new_figure(6.8, 5.2, rows=2)
    tag(fig, "command", *plot_decimated(ax, t, np.asarray(sim.reference, dtype=float)[:, 0, 0], color=GREY,
                                        **REFERENCE_STYLE, label="command uc"))
    tag(fig, "model", *plot_decimated(ax, t, sim.signals["ym"], color=GREEN, lw=2.2, alpha=0.7, label="model ym"))
    tag(fig, "output", *plot_decimated(ax, t, y, color=BLUE, lw=1.2, label="plant y"))
    ax.set_ylabel("output")
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    plant = result.plant if result.plant is not None else d.plant
    end = final_ideal(d, result.loaded.spec, plant)
    change = result.loaded.spec.simulation.plant_change
    info: dict[str, Any] = {"final": [], "ideal": list(x.structure.ideal), "end": list(end) if end else None}
    for i, name in enumerate(x.parameters):
        c = COLORS[i % len(COLORS)]
        theta = np.asarray(sim.signals[name], dtype=float)
        info["final"].append(float(theta[-1]))
        tag(fig, "theta", *plot_decimated(bx, t, theta, color=c, label=name))
        want = np.full(t.size, x.structure.ideal[i])
        if change is not None and end is not None:
            want[t >= change.time - 1e-12] = end[i]
        tag(fig, "ideal", *plot_decimated(bx, t, want, color=c, **LIMIT_STYLE))
    bx.set_ylabel("parameters")
    bx.set_xlabel("time (s)")
    bx.legend(loc="best", framealpha=0.9, fontsize=7, ncol=2)
    for a in (ax, bx):
        a.set_xlim(t[0], t[-1])
    return fig, info


def regressor_figure(result: Any) -> Figure | None:
    """The run of a feedforward/feedback MRAC (module docstring); None for the coefficient form or without a run."""
    if result.simulation is None or not isinstance(result.design.data, RegressorData):
        return None
    svg, keys, info = render_tagged(_draw, result)
    names = ", ".join(result.design.data.parameters)
    caption = ("Drawn: top, the command (grey), the reference model's output (green) and the plant's output (blue); "
               f"bottom, the adapted parameters {names} (solid) and the ideal values that make the nominal loop the "
               f"model, {', '.join(f'{v:.4g}' for v in info['ideal'])} (dashed, same colours"
               + (", stepping to the ideal values of the changed plant" if result.loaded.spec.simulation.plant_change
                  is not None else "") + f"). Final values: {', '.join(f'{v:.4g}' for v in info['final'])}.")
    return Figure("Output and adapted parameters", caption, svg, "fig-mrac-regressor.svg",
                  ("adaptive_stability", "parameter_convergence"))
