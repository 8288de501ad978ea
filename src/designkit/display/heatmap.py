"""Robustness figure: a check's margin over the lattice of its uncertain plant parameters.

A check opts in by putting a ``"grid"`` mapping in its certificate (see :func:`robustness_grid`):
its ``axes`` (name, unit, values of each varying parameter -- one or two) and the margin at every
lattice point.  Two axes give a heat map, green where robust and red where not, with the zero
contour; one axis a line.  Artists are tagged (:func:`designkit.display.svg.tag`: ``margin-map``,
``zero-contour``, ``margin-line``, ``zero-line``) so a caption can name what is drawn.
The axes are the certificate's: nothing here knows which plant
parameters exist.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.svg import BLUE, GREY, new_figure, render, tag

__all__ = ["GridData", "robustness_grid", "robustness_svg"]


@dataclass(frozen=True)
class GridData:
    """A margin over a lattice of one or two parameters.

    Parameters
    ----------
    axes : tuple of (name, unit, values)
        The varying parameters (values as arrays).
    values : ndarray
        Shape ``(len(y), len(x))`` for two axes, ``(len(x),)`` for one.
    label : str
        What the values are.
    """

    axes: tuple[tuple[str, str, np.ndarray], ...]
    values: np.ndarray
    label: str


def robustness_grid(certificate: Mapping[str, Any]) -> GridData | None:
    """The ``"grid"`` entry of a certificate, checked, else ``None``.

    Accepted form: ``certificate["grid"] = {"axes": [{"name", "unit", "values"}, ...], "values": ...,
    "label": "..."}`` with one or two axes; for two, ``values`` has shape ``(len(axis 2), len(axis 1))``.
    """
    grid = certificate.get("grid") if isinstance(certificate, Mapping) else None
    if not isinstance(grid, Mapping) or "axes" not in grid or "values" not in grid:
        return None
    try:
        axes = tuple((str(a["name"]), str(a.get("unit", "")), np.asarray(a["values"], float).ravel())
                     for a in grid["axes"])
        values = np.asarray(grid["values"], float)
    except (TypeError, ValueError, KeyError):
        return None
    if len(axes) == 2:
        shape = (axes[1][2].size, axes[0][2].size)
    elif len(axes) == 1:
        shape = (axes[0][2].size,)
    else:
        return None
    if values.shape != shape or min(a[2].size for a in axes) < 2:
        return None
    return GridData(axes=axes, values=values, label=str(grid.get("label", "margin")))


def robustness_svg(name: str, certificate: Mapping[str, Any]) -> str | None:
    """The figure of a check's lattice (``None`` without grid data)."""
    data = robustness_grid(certificate)
    if data is None:
        return None
    return render(_draw, name, data)


def _axis_label(axis: tuple[str, str, np.ndarray]) -> str:
    return f"{axis[0]} ({axis[1].replace('*', '·')})" if axis[1] else axis[0]


def _draw(name: str, data: GridData) -> Any:
    fig, (ax,) = new_figure(6.4, 4.0, layout="constrained")  # colour bar and title
    finite = data.values[np.isfinite(data.values)]
    if len(data.axes) == 1:
        x = data.axes[0][2]
        tag(fig, "margin-line", *ax.plot(x, data.values, color=BLUE))
        tag(fig, "zero-line", ax.axhline(0.0, color=GREY, lw=0.8))
        ax.set_xlabel(_axis_label(data.axes[0]))
        ax.set_ylabel(data.label)
    else:
        vmax = float(np.max(np.abs(finite))) if finite.size else 1.0
        vmax = vmax if vmax > 0 else 1.0
        x, y = data.axes[0][2], data.axes[1][2]
        mesh = ax.pcolormesh(x, y, data.values, shading="nearest", cmap="RdYlGn", vmin=-vmax, vmax=vmax)
        tag(fig, "margin-map", mesh)
        if finite.size and np.min(finite) < 0 < np.max(finite):
            tag(fig, "zero-contour", ax.contour(x, y, data.values, levels=[0.0], colors="black", linewidths=1.2))
        fig.colorbar(mesh, ax=ax, label=data.label)
        ax.set_xlabel(_axis_label(data.axes[0]))
        ax.set_ylabel(_axis_label(data.axes[1]))
    ax.set_title(data.label[:1].upper() + data.label[1:])  # the quantity in words; the check is the figure's caption
    return fig
