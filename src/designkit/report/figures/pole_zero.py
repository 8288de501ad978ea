"""The pole-zero map: achieved (or coupled) closed-loop poles against the requested or derived ones."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from designkit.display.figure import Figure
from designkit.display.svg import BLUE, GREY, ORANGE, new_figure, render_tagged, tag
from designkit.report.figures.naming import present_checks
from designkit.verification.loop import achieved_zeros

__all__ = ["pole_origin", "pole_zero_figure"]


def _requested_poles(design: Any) -> np.ndarray:
    return np.array([*design.poles, *[p for loop in design.loops for p in loop.poles]], dtype=complex)


def pole_origin(result: Any) -> tuple[str, str]:
    """Where the design's poles and zero come from: ``"requested"`` (given in the spec's controller) or
    ``"derived"`` (computed by the design from the requirements or its own rule), for the poles and
    for the zero."""
    ctrl = getattr(result.loaded.spec, "controller", None)
    poles = "derived" if ctrl is not None and hasattr(ctrl, "poles") and ctrl.poles is None else "requested"
    zero = "derived" if ctrl is not None and getattr(ctrl, "zero", None) is None else "requested"
    return poles, zero


_POLE_LABELS = {
    "requested": ("requested poles", "requested-poles"),
    "derived": ("poles derived from the requirements", "derived-poles"),
}


def _draw_pole_zero(design: Any, origin: tuple[str, str]) -> Any:
    fig, (ax,) = new_figure(6.4, 3.0)
    achieved = np.linalg.eigvals(design.closed_loop.A)
    zeros = achieved_zeros(design)
    req_p = _requested_poles(design)
    req_z = np.array(design.zeros, dtype=complex)
    ax.axvline(0.0, color=GREY, lw=0.8)
    ax.axhline(0.0, color=GREY, lw=0.8)
    per_loop = bool(design.loops)
    if req_p.size:
        label, key = _POLE_LABELS[origin[0]]
        (line,) = ax.plot(req_p.real, req_p.imag, "o", ms=13, mfc="none", mec=ORANGE, mew=1.6, ls="none",
                          label=f"{label} (per joint loop)" if per_loop else label)
        tag(fig, key, line)
    (line,) = ax.plot(achieved.real, achieved.imag, "x", ms=9, color=BLUE, mew=2.0, ls="none",
                      label="coupled closed-loop poles" if per_loop else "achieved poles")
    tag(fig, "coupled-poles" if per_loop else "achieved-poles", line)
    if req_z.size:
        (line,) = ax.plot(req_z.real, req_z.imag, "s", ms=13, mfc="none", mec=ORANGE, mew=1.6, ls="none",
                          label="requested zero" if origin[1] == "requested" else "zero chosen by the design")
        tag(fig, f"{origin[1]}-zero", line)
    if zeros.size:
        (line,) = ax.plot(zeros.real, zeros.imag, "o", ms=7, mfc="none", mec=BLUE, mew=1.8, ls="none",
                          label="achieved zero (xD→x1)")
        tag(fig, "achieved-zero", line)
    pts = np.concatenate([achieved, zeros, req_p, req_z, [0j]])
    re_lo, re_hi = float(np.min(pts.real)), float(np.max(pts.real))
    span = max(re_hi - re_lo, 1e-6)
    im = max(float(np.max(np.abs(pts.imag))), 0.2 * span)
    ax.set_xlim(re_lo - 0.08 * span, max(re_hi, 0.0) + 0.08 * span)
    ax.set_ylim(-1.25 * im, 1.25 * im)
    ax.set_xlabel("Re s (1/s)")
    ax.set_ylabel("Im s (rad/s)")
    ax.legend(loc="best", ncols=2, framealpha=0.9)
    return fig


def _pole_zero_caption(keys: Sequence[str], n_ach: int, n_req: int, extra: Mapping[str, Any]) -> str:
    """The pole-zero map's caption, from the keys of what is drawn."""
    if "coupled-poles" in keys:
        text = (f"The {n_ach} poles of the coupled arm's closed loop, linearized at the design configuration (×)")
    else:
        text = f"The {n_ach} achieved closed-loop poles (eigenvalues of the linearized closed loop, ×)"
    per_loop = " each joint loop places on its own simplified link model" if "coupled-poles" in keys else ""
    if "requested-poles" in keys:
        text += f", against the {n_req} poles requested in the spec{per_loop} (○)"
    elif "derived-poles" in keys:
        zw = ""
        if isinstance(extra.get("zeta"), int | float) and isinstance(extra.get("wn"), int | float):
            zw = f", ζ = {extra['zeta']:.3g} and ωn = {extra['wn']:.3g} rad/s"
        text += f", against the {n_req} poles the design derived from the requirements{zw}{per_loop} (○)"
    if "coupled-poles" in keys and any(k in keys for k in ("requested-poles", "derived-poles")):
        text += "; the distance between them is the intercoupling the per-link design ignores."
    elif any(k in keys for k in ("requested-poles", "derived-poles")):
        text += "; each × should sit in the centre of a ○."
    else:
        text += "."
    zero = ("the requested zero" if "requested-zero" in keys else
            "the zero the design chose" if "derived-zero" in keys else None)
    if "achieved-zero" in keys:
        text += " Zeros of the reference-to-position transfer xD→x1 (small ○)" + (f" against {zero} (□)."
                                                                                   if zero else ".")
    elif zero:
        text += f" Also drawn: {zero} (□)."
    return text


def pole_zero_figure(result: Any) -> Figure | None:
    """Achieved (or coupled) closed-loop poles against the requested or derived ones."""
    design = result.design
    if design.closed_loop is None:
        return None
    svg, keys, _ = render_tagged(_draw_pole_zero, design, pole_origin(result))
    caption = _pole_zero_caption(keys, len(design.closed_loop.A), len(_requested_poles(design)),
                                 design.extra or {})
    return Figure("Pole-zero map", caption, svg, "fig-pole-zero.svg",
                  present_checks(result, ("pole_placement", "error_poles")))
