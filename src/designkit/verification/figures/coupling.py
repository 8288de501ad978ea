"""The coupling check's figure: each joint's coupled response against its decoupled prediction."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import JOINT_COLORS, Figure
from designkit.display.svg import GREY, new_figure, plot_decimated, render

__all__ = ['coupling_figure']


def _draw_coupling(data: Any, names: Sequence[str]) -> Any:
    t = np.asarray(data["time"], float)
    coupled, decoupled = np.asarray(data["coupled"]), np.asarray(data["decoupled"])
    fig, (ax, ax_e) = new_figure(6.8, 4.6, rows=2)
    for j in range(coupled.shape[1]):
        color = JOINT_COLORS[j % len(JOINT_COLORS)]
        plot_decimated(ax, t, decoupled[:, j], color=color, ls="--", lw=1.0, label=f"{names[j]} own loop alone")
        plot_decimated(ax, t, coupled[:, j], color=color, label=f"{names[j]} coupled arm")
        plot_decimated(ax_e, t, coupled[:, j] - decoupled[:, j], color=color, label=f"{names[j]}")
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9, ncols=2)
    ax_e.axhline(0.0, color=GREY, lw=0.8)
    ax_e.set_ylabel("intercoupling error (rad)")
    ax_e.set_xlabel("time (s)")
    ax_e.set_xlim(t[0], t[-1])
    ax_e.legend(loc="best", framealpha=0.9)
    return fig


def coupling_figure(result: Any, check: Any) -> Figure | None:
    """Each joint on the coupled arm against its own loop on its simplified model (coupling check data)."""
    if not check.data:
        return None
    plant = result.design.plant
    names = [plant.states[i].name for i in plant.positions]
    rows = check.certificate.get("intercoupling_error", [])
    worst = max(rows, key=lambda r: r["max_abs_rad"]) if rows else None
    caption = ("Top: each joint on the full nonlinear coupled arm (solid) and as its own loop predicts on its "
               "simplified link model, alone (dashed). Bottom: their difference, the intercoupling error the "
               "per-joint PIDs leave")
    if worst is not None:
        caption += f" (largest {worst['max_abs_rad']:.3g} rad, joint {worst['joint']}, t = {worst['at_s']:.3g} s)."
    return Figure("Intercoupling between the joint loops", caption, render(_draw_coupling, check.data, names),
                  "fig-coupling.svg", (check.name,))
