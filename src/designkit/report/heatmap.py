"""Robustness heat map: a check's margin over the ``(Km, tau)`` box of plant parameters.

A check opts in by putting a ``"grid"`` mapping in its certificate (see :func:`robustness_grid`);
:func:`robustness_svg` draws it, green where robust and red where not, with the zero contour.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from designkit.report.svg import new_figure, render

_GRID_VALUE_KEYS = ("values", "margin", "margins", "value", "z")


def robustness_grid(certificate: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray, str] | None:
    """``(Km, tau, values[tau, Km], label)`` from a certificate's ``"grid"`` entry, else ``None``.

    Accepted form: ``certificate["grid"] = {"Km": [...], "tau": [...], "values": [[...]],
    "label": "..."}`` where ``values`` has shape ``(len(tau), len(Km))`` or ``(len(Km), len(tau))``
    (the key may also be ``margin``/``margins``/``value``/``z``).
    """
    grid = certificate.get("grid") if isinstance(certificate, Mapping) else None
    if not isinstance(grid, Mapping) or "Km" not in grid or "tau" not in grid:
        return None
    key = next((k for k in _GRID_VALUE_KEYS if k in grid), None)
    if key is None:
        return None
    try:
        km = np.asarray(grid["Km"], float).ravel()
        tau = np.asarray(grid["tau"], float).ravel()
        values = np.asarray(grid[key], float)
    except (TypeError, ValueError):
        return None
    if values.shape == (km.size, tau.size) and km.size != tau.size:
        values = values.T
    if values.shape != (tau.size, km.size) or km.size < 2 or tau.size < 2:
        return None
    return km, tau, values, str(grid.get("label", key))


def robustness_svg(name: str, certificate: Mapping[str, Any]) -> str | None:
    """Heat map of a robustness margin over the ``(Km, tau)`` box (``None`` without grid data)."""
    data = robustness_grid(certificate)
    if data is None:
        return None
    return render(_draw_robustness, name, data)


def _draw_robustness(name: str, data):
    km, tau, values, label = data
    fig, (ax,) = new_figure(6.4, 4.0)
    finite = values[np.isfinite(values)]
    vmax = float(np.max(np.abs(finite))) if finite.size else 1.0
    vmax = vmax if vmax > 0 else 1.0
    mesh = ax.pcolormesh(km, tau, values, shading="nearest", cmap="RdYlGn", vmin=-vmax, vmax=vmax)
    if finite.size and np.min(finite) < 0 < np.max(finite):
        ax.contour(km, tau, values, levels=[0.0], colors="black", linewidths=1.2)
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel("Km ((rad/s)/(N·m))")
    ax.set_ylabel("τ (s)")
    ax.set_title(f"{name}: {label}")
    return fig
