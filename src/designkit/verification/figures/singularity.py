"""The singularity check's figure: the condition number of the task Jacobian along the path."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.figure import Figure, plain_ticks
from designkit.display.svg import BLUE, GREEN, RED, new_figure, render

__all__ = ['singularity_figure']


def _draw_singularity(data: Any) -> Any:
    t = np.asarray(data["time"], float)
    fig, (ax_c, ax_w) = new_figure(6.8, 4.6, rows=2)
    ax_c.semilogy(t, np.asarray(data["condition"], float), color=BLUE, label="condition number of J")
    plain_ticks(ax_c.yaxis)
    ax_c.axhline(float(data["limit"]), color=RED, ls="--", lw=1.0, label=f"near-singular above {data['limit']:g}")
    ax_c.set_ylabel("κ(J)")
    ax_c.legend(loc="best", framealpha=0.9)
    ax_w.plot(t, np.asarray(data["manipulability"], float), color=GREEN, label="manipulability √det(J Jᵀ)")
    ax_w.set_ylabel("manipulability")
    ax_w.set_xlabel("time (s)")
    ax_w.set_xlim(t[0], t[-1])
    ax_w.legend(loc="best", framealpha=0.9)
    return fig


def singularity_figure(result: Any, check: Any) -> Figure | None:
    """Conditioning of the task Jacobian along the exact joint path (singularity check data)."""
    if not check.data:
        return None
    cert = check.certificate
    caption = (f"Conditioning of the task Jacobian J along the joint path that tracks the reference exactly "
               f"({cert['samples']} instants of inverse kinematics): its condition number (top, the limit "
               f"{cert['max_condition_allowed']:g} dashed) peaks at {cert['worst_condition']:.4g} at "
               f"t = {cert['worst_at_s']:.3g} s; manipulability (bottom) down to "
               f"{cert['smallest_manipulability']:.3g}.")
    if cert.get("damping"):
        caption += (f" Damped least squares (λ = {cert['damping']:g}) keeps the resolution bounded; the task gain "
                    f"along the weakest direction at the worst point is {cert['task_gain_at_worst']:.3g}.")
    return Figure("Distance to singular configurations along the path", caption,
                  render(_draw_singularity, check.data), "fig-singularity.svg", (check.name,))
