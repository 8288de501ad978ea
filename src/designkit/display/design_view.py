"""The Jupyter view of a design alone: gains with units, requested and achieved poles, the closed loop's signals.

:func:`design_html` is :meth:`designkit.synthesis.design.Design._repr_html_`; no check is run.  It reads the
design's own fields only (``design.label`` is the family in words, set by the registry's synthesis), so it sits
with the other presentation primitives below every package it describes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from designkit.display.html import esc, heading, para, table
from designkit.display.numbers import fmt_number, plain_complex, unit

__all__ = ["design_html"]



def _fmt(value: Any, digits: int = 6) -> str:
    return fmt_number(value, digits)


def _gain_text(value: Any) -> str:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return _fmt(float(arr))
    if arr.ndim == 1:
        return "; ".join(f"joint {j + 1}: {_fmt(v)}" for j, v in enumerate(arr))
    return "; ".join("[" + ", ".join(_fmt(v) for v in row) + "]" for row in arr)


def _pole_rows(poles: Iterable[complex]) -> list[list[str]]:
    rows = []
    for p in sorted((complex(p) for p in poles), key=lambda z: (z.real, z.imag)):
        wn = abs(p)
        rows.append([_fmt(p), _fmt(-p.real / wn, 4) if wn > 0 else "—", _fmt(wn, 4)])
    return rows


def design_html(design: Any) -> str:
    """A design as an HTML fragment for Jupyter (no check is run).

    Parameters
    ----------
    design : Design

    Returns
    -------
    str
        One ``<div>``: controller and plant, gains with their units and roles, requested poles
        and zeros (1/s), the achieved closed-loop poles with damping ratio and natural frequency
        (rad/s), the closed loop's inputs, outputs and states, per-joint loops and the notes.
    """
    label = design.label or design.kind
    parts = ['<div class="designkit-design" style="font-family:sans-serif;line-height:1.35">',
             f'<h3 style="margin:0.2em 0">{esc(label)} ({esc(design.kind)}) on a {esc(design.plant.kind)} plant</h3>',
             heading("Gains"),
             table(("Gain", "Value", "Unit", "Meaning"),
                    ([k, _gain_text(v), unit(str(design.gains.unit(k))), design.gains.meaning(k)]
                     for k, v in design.gains.items()))]
    if design.poles or design.zeros:
        rows = [["pole", _fmt(p)] for p in design.poles] + [["zero", _fmt(z)] for z in design.zeros]
        parts += [heading("Requested"), table(("", "Value (1/s)"), rows)]
    cl = design.closed_loop
    if cl is not None:
        poles = np.linalg.eigvals(np.asarray(cl.A, float))
        abscissa = float(np.max(poles.real)) if poles.size else -math.inf
        stable = "asymptotically stable" if abscissa < 0 else "not asymptotically stable"
        parts += [
            heading("Nominal closed loop (linearized at the operating point)"),
            para(f"{len(cl.states)} states ({', '.join(cl.states)}); inputs {', '.join(cl.inputs)}; "
                  f"outputs {', '.join(cl.outputs)}. {stable.capitalize()}: the slowest pole has real part "
                  f"{_fmt(abscissa, 4)} 1/s."),
            table(("Achieved pole (1/s)", "ζ", "ωn (rad/s)"), _pole_rows(poles)),
        ]
    for name, loop in zip(design.loop_names, design.loops, strict=False):
        if loop.closed_loop is not None:
            parts += [heading(f"Loop {name}"),
                      table(("Achieved pole (1/s)", "ζ", "ωn (rad/s)"),
                             _pole_rows(np.linalg.eigvals(np.asarray(loop.closed_loop.A, float))))]
    if design.notes:
        parts.append(heading("Notes"))
        parts.append("<ul>" + "".join(f"<li>{esc(plain_complex(n))}</li>" for n in design.notes) + "</ul>")
    parts.append(para("No check has been run on this design: designkit.run(spec) verifies it."))
    parts.append("</div>")
    return "".join(parts)

