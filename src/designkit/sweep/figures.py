"""The sweep report's figures, as SVG text: margin histograms, the samples over the box, the worst runs."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.numbers import unit
from designkit.sweep.margins import REQUIREMENTS

__all__ = ["box_figure", "margin_figure", "trajectory_figure"]

WORDS = {"overshoot": "overshoot", "settling_time": "settling time", "rise_time": "rise time",
         "steady_state_error": "steady-state error", "tracking_error": "tracking error",
         "max_control": "peak commanded control"}
"""The requirements in words."""


def margin_figure(result: Any) -> str | None:
    """One histogram per requirement of its margin (limit minus achieved; left of zero: broken)."""
    from designkit.display.svg import new_figure, render

    names = result.requirements
    if not names:
        return None

    def draw() -> Any:
        fig, axes = new_figure(6.4, 1.1 + 1.5 * len(names), rows=len(names), sharex=False)
        for ax, (r, name) in zip(axes, enumerate(names), strict=True):
            m = result.margin[:, r]
            floor = -3.0 * result.limits[name]
            ok = m[np.isfinite(m) & (m >= floor)]
            beyond = int(np.count_nonzero(np.isfinite(m) & (m < floor)))
            if ok.size:
                ax.hist(ok, bins=min(60, max(10, int(np.sqrt(ok.size)))), color="#4878a8")
            ax.axvline(0.0, color="#c0392b", lw=1.2)
            undefined = int(np.count_nonzero(~np.isfinite(m)))
            extra = f"; {undefined} undefined" if undefined else ""
            extra += f"; {beyond} below −3 × the limit, not drawn" if beyond else ""
            extra = f" ({extra[2:]})" if extra else ""
            ax.set_xlabel(f"margin of the {WORDS[name]} ({unit(REQUIREMENTS[name])}){extra}")
            ax.set_ylabel("samples")
        return fig

    return render(draw)


def box_figure(result: Any) -> str | None:
    """The samples over the first two sampled quantities (or the worst margin against the one), passed or not."""
    from designkit.display.svg import new_figure, render

    dims = result.dimensions
    if not dims:
        return None
    keep = np.arange(result.samples) if result.samples <= 20_000 else np.linspace(
        0, result.samples - 1, 20_000).astype(int)
    ok = result.passed[keep]

    def draw() -> Any:
        fig, (ax,) = new_figure(6.4, 3.6)
        x = result.values[keep, 0]
        if len(dims) >= 2:
            y = result.values[keep, 1]
            ax.set_ylabel(f"{dims[1].name} ({unit(dims[1].unit)})" if dims[1].unit else dims[1].name)
        else:
            lim = np.array([result.limits[k] for k in result.requirements])
            norm = result.margin[keep] / lim[None, :]
            y = np.nanmin(np.where(np.isfinite(norm), norm, -1.0), axis=1)
            ax.axhline(0.0, color="#c0392b", lw=1.0)
            ax.set_ylabel("worst margin / limit")
        ax.scatter(x[ok], y[ok], s=4, color="#4878a8", label="met every requirement")
        ax.scatter(x[~ok], y[~ok], s=6, color="#c0392b", label="broke a requirement")
        f = result.falsification
        if f is not None and len(dims) >= 2:
            ax.scatter([f.values[0]], [f.values[1]], marker="x", s=60, color="black", label="falsification's worst")
        ax.set_xlabel(f"{dims[0].name} ({unit(dims[0].unit)})" if dims[0].unit else dims[0].name)
        ax.legend(loc="best")
        return fig

    return render(draw)


def trajectory_figure(time: np.ndarray, runs: list[tuple[str, np.ndarray, np.ndarray]], units: str) -> str | None:
    """The tracked positions of the worst runs against the reference, joint by joint."""
    from designkit.display.svg import new_figure, plot_decimated, render

    if not runs:
        return None
    n = runs[0][1].shape[1]

    def draw() -> Any:
        fig, axes = new_figure(6.4, 1.2 + 1.7 * n, rows=n)
        for j, ax in enumerate(axes):
            ax.plot(time, runs[0][2][:, j], color="black", lw=1.0, ls="--", label="reference")
            for label, y, _ in runs:
                plot_decimated(ax, time, y[:, j], lw=1.0, label=label)
            ax.set_ylabel(f"joint {j + 1} ({unit(units)})")
        axes[-1].set_xlabel("time (s)")
        axes[0].legend(loc="best", fontsize=7)
        return fig

    return render(draw)
