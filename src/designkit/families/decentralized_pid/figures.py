"""The workspace certificate's figure: each joint loop's time constant over the workspace against its stable range."""

from __future__ import annotations

import math
from typing import Any

from designkit.display.figure import Figure, plain_ticks
from designkit.display.svg import GREEN, GREY, RED, new_figure, render

__all__ = ['workspace_figure']


def _draw_workspace(data: Any) -> Any:
    joints = [j for j in data["joints"] if math.isfinite(j["tau_stable"][1]) and j["tau_stable"][1] > 0]
    if not joints:
        return None
    fig, (ax,) = new_figure(6.8, 1.5 + 0.4 * len(joints), layout="constrained")  # outside legend
    ratios = [1.0]
    for k, j in enumerate(joints):
        crit, y = j["tau_stable"][1], len(joints) - 1 - k
        lo, hi, nominal = j["tau"][0] / crit, j["tau"][1] / crit, j["tau_nominal"] / crit
        ratios += [lo, hi, nominal]
        ax.plot([lo, hi], [y, y], color=GREEN if hi < 1.0 else RED, lw=7, solid_capstyle="butt", marker="|",
                ms=14, label="τ_i over the workspace" if k == 0 else None)
        ax.plot(nominal, y, "o", color=GREY, ms=5, label="τ_i at q*" if k == 0 else None)
    ax.axvline(1.0, color=RED, ls="--", lw=1.0, label="stability limit")
    if max(ratios) / min(ratios) > 10.0:
        ax.set_xscale("log")
        plain_ticks(ax.xaxis)
    ax.set_yticks(range(len(joints)), [f"joint {j['joint']}" for j in reversed(joints)])
    ax.set_ylim(-0.7, len(joints) - 0.3)
    ax.set_xlabel("τ_i / τ_crit,i  =  D_ii(q) / D_crit,i")
    fig.legend(loc="outside lower center", ncols=3, framealpha=0.9)
    return fig


def workspace_figure(result: Any, check: Any) -> Figure | None:
    """Each joint's range of tau over the workspace against its stability limit (workspace check data)."""
    if not check.data.get("joints"):
        return None
    svg = render(_draw_workspace, check.data)
    if svg is None:
        return None
    worst = check.certificate["smallest_margin"]
    at = ", ".join(f"{v:.3g}" for v in worst["configuration"])
    tol = check.certificate.get("tolerance")
    proven = (f"from the proven lower to the proven upper bound of D_ii over the box, each within {tol:.3g} "
              "(relative) of a configuration where it is attained" if tol else "from the smallest to the largest D_ii")
    caption = ("Each joint's time constant τ_i = D_ii(q)/f_i over the workspace box (bar, " + proven + "; green "
               "when stable throughout, red when not) and at the design configuration "
               "(dot), divided by the largest τ_i its PID loop tolerates, τ_crit,i = K1 (1 + Km K2)/K3: the loop is "
               f"stable left of the dashed line. Smallest margin 1 − τ/τ_crit = {worst['margin']:.3g} on joint "
               f"{worst['joint']} at q = [{at}].")
    return Figure("Joint loops over the workspace", caption, svg, "fig-workspace.svg", (check.name,))
