"""The robustness checks' figure: the margin of the closed loop over the parameter lattice of the certificate."""

from __future__ import annotations

from typing import Any

from designkit.display.figure import Figure
from designkit.display.heatmap import robustness_svg
from designkit.display.svg import svg_keys

__all__ = ['robustness_figure']


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
