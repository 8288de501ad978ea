"""The robustness checks' figure: the margin of the closed loop over the parameter lattice of the certificate."""

from __future__ import annotations

from typing import Any

from designkit.display.figure import Figure
from designkit.display.heatmap import robustness_svg
from designkit.display.svg import svg_keys

__all__ = ['pole_migration_figure', 'robustness_figure']


def robustness_figure(result: Any, check: Any) -> Figure | None:
    """The robust_grid check's margin over its parameter lattice (axes from the certificate)."""
    svg = robustness_svg(check.name, check.certificate)
    if svg is None:
        return None
    keys = svg_keys(svg)
    axes = check.certificate["grid"]["axes"]
    names = " and ".join(a["name"] for a in axes)
    label = str(check.certificate["grid"].get("label", "margin")).split(";", 1)[0].strip()
    caption = f"{label[:1].upper()}{label[1:]} of the closed loop over the lattice of {names}"
    if len(axes) == 2:
        caption += "; green where it is above zero, red below"
        caption += (", and the black line is where the value is zero." if "zero-contour" in keys else
                    "; the value does not change sign over the lattice.")
    else:
        caption += "; above zero (the grey line) is robust."
    return Figure(f"Robustness over {names}", caption, svg, f"fig-robustness-{_slug(check.name)}.svg", (check.name,))


def _slug(text: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in text)[:60] or "check"


def _draw_migration(poles: Any, values: Any, label: str) -> Any:
    import numpy as np

    from designkit.display.svg import GREY, new_figure

    fig, (ax,) = new_figure(6.4, 4.2, layout="constrained")
    p = np.asarray(poles)
    v = np.repeat(np.asarray(values, float)[:, None], p.shape[1], axis=1)
    sc = ax.scatter(p.real.ravel(), p.imag.ravel(), c=v.ravel(), s=9, cmap="viridis", marker="x", linewidths=0.8)
    fig.colorbar(sc, ax=ax, label=label)
    ax.axvline(0.0, color=GREY, lw=0.8)
    ax.axhline(0.0, color=GREY, lw=0.6)
    ax.set_xlabel("Re (1/s)")
    ax.set_ylabel("Im (1/s)")
    return fig


def pole_migration_figure(result: Any, check: Any) -> Figure | None:
    """The closed-loop poles of every plant of the lattice, coloured by the first varying parameter (root locus over
    the box)."""
    import numpy as np

    from designkit.display.numbers import unit as typeset
    from designkit.display.svg import render

    data = check.data or {}
    if "poles" not in data:
        return None
    values = np.asarray(data["values"], float)
    label = data["parameter"] + (f" ({typeset(data['unit'])})" if data.get("unit") else "")
    right = float(np.max(np.asarray(data["poles"]).real))
    caption = (f"The closed-loop poles of each of the {len(values)} plants of the robustness lattice (×), coloured by "
               f"{label}: how the poles move over the uncertainty box. The rightmost is at Re = {right:.3g} 1/s"
               + ("; left of the imaginary axis (grey), every plant is stable." if right < 0 else
                  "; on or right of the imaginary axis (grey): some plants are not stable."))
    return Figure("Pole migration over the uncertainty box", caption, render(_draw_migration, data["poles"], values,
                  label), f"fig-pole-migration-{_slug(check.name)}.svg", (check.name,))
