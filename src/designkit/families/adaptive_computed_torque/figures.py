"""The adaptive computed torque's figures, drawn from a run: the tracking error per joint, the estimates against the
true values, the excitation indicator along the desired trajectory, and Re H(jw) per joint with the SPR margin.

Captions are written from the keys of what was drawn (:func:`~designkit.display.svg.render_tagged`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.figure import JOINT_COLORS, LIMIT_STYLE, Figure
from designkit.display.svg import BLUE, GREEN, GREY, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.adaptive_computed_torque.laws import KIND, estimates
from designkit.families.adaptive_computed_torque.spr import frequency_grid, re_h
from designkit.families.adaptive_computed_torque.words import describe, unit_text

__all__ = ["FIGURES", "excitation_figure", "error_figure", "estimates_figure", "spr_figure"]

def _ours(result: Any) -> bool:
    return result.design.kind == KIND and result.simulation is not None


def _draw_error(result: Any) -> Any:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    n = result.design.plant.n_joints
    e = np.asarray(sim.reference, dtype=float)[:, :, 0] - np.asarray(sim.state, dtype=float)[:, :n]
    fig, (ax,) = new_figure(6.8, 3.4)
    for j in range(n):
        tag(fig, "error", *plot_decimated(ax, t, e[:, j], color=JOINT_COLORS[j % len(JOINT_COLORS)],
                                          label=f"joint {j + 1}"))
    check = next((c for c in result.checks if c.name == "tracking_convergence"), None)
    window = None
    if check is not None and "window_maxima_rad" in check.certificate:
        c = check.certificate
        window = float(c["window_s"])
        ends = np.asarray(c["window_ends_s"], dtype=float)
        starts = np.concatenate([[t[0]], ends[:-1]])
        for j, row in enumerate(c["window_maxima_rad"]):
            xs = np.column_stack([starts, ends]).ravel()
            ys = np.repeat(np.asarray(row, dtype=float), 2)
            tag(fig, "envelope", *ax.plot(xs, ys, color=JOINT_COLORS[j % len(JOINT_COLORS)], ls="--", lw=0.9,
                                          label="largest |e| per window" if j == 0 else None))
    ax.set_xlabel("time (s)")
    ax.set_ylabel("e = qD − q (rad)")
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="best", framealpha=0.9, fontsize=7, ncol=min(n + 1, 3))
    return fig, {"n": n, "last": float(np.max(np.abs(e[t >= t[-1] - 0.1 * (t[-1] - t[0])]))), "window": window}


def error_figure(result: Any) -> Figure | None:
    """The tracking error of every joint against time."""
    if not _ours(result):
        return None
    svg, keys, info = render_tagged(_draw_error, result)
    caption = (f"Drawn: the tracking error qD − q of each of the {info['n']} joints against time (rad). Over the last "
               f"tenth of the run its largest magnitude is {info['last']:.3g} rad.")
    if "envelope" in keys:
        caption += (f" Dashed: the largest |e| of each joint over each window of {info['window']:.4g} s, the bound "
                    "the tracking judgement asks to decrease.")
    return Figure("Tracking error", caption, svg, "fig-adaptive-ct-error.svg", ("tracking_convergence",))


def _draw_estimates(result: Any) -> Any:
    d, sim = result.design, result.simulation
    a = d.data.adaptation
    names, units, true = a.names, d.data.units, d.data.true
    t = np.asarray(sim.time, dtype=float)
    est = estimates(sim, names)
    fig, axes = new_figure(6.8, 1.5 + 1.3 * len(names), rows=len(names))
    for k, ax in enumerate(axes):
        tag(fig, "true", ax.axhline(true[k], color=GREEN, **LIMIT_STYLE, label=f"true {true[k]:.4g}"))
        tag(fig, "estimate", *plot_decimated(ax, t, est[:, k], color=BLUE, label="estimate"))
        if a.bounds is not None and np.isfinite(a.bounds[k][0]):
            for b in a.bounds[k]:
                tag(fig, "bound", ax.axhline(b, color=GREY, ls=":", lw=1.0))
        ax.set_ylabel(f"{names[k]} ({unit_text(units[k])})", fontsize=8)
        ax.legend(loc="best", framealpha=0.9, fontsize=7)
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(t[0], t[-1])
    return fig, {"names": names}


def estimates_figure(result: Any) -> Figure | None:
    """Each adapted parameter's estimate against time, with its true value."""
    if not _ours(result):
        return None
    svg, keys, info = render_tagged(_draw_estimates, result)
    caption = ("Drawn: the estimate of each adapted parameter against time (blue; "
               + "; ".join(describe(x) for x in info["names"]) + ")")
    if "true" in keys:
        caption += " and its true value (dashed green)"
    if "bound" in keys:
        caption += "; dotted grey: the projection bounds"
    caption += "."
    return Figure("Parameter estimates", caption, svg, "fig-adaptive-ct-estimates.svg",
                  ("estimate_convergence", "frozen_final"))


def _excitation(result: Any) -> Any:
    check = next((c for c in result.checks if c.name == "estimate_convergence"), None)
    if check is not None and "excitation" in check.data:
        return check.data["excitation"]
    from designkit.families.adaptive_computed_torque.checks import run_excitation

    return run_excitation(result.design, result.simulation)


def _draw_excitation(result: Any, ex: Any) -> Any:
    fig, (ax,) = new_figure(6.8, 3.2)
    ok = np.isfinite(ex.alpha)
    floor = 1e-12
    tag(fig, "alpha", *ax.plot(ex.time[ok], np.maximum(ex.alpha[ok], floor), color=BLUE,
                               label=f"smallest eigenvalue of ∫WᵀW dt over the last {ex.window:.3g} s"))
    ax.set_yscale("log")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("λmin ((N·m per parameter unit)²·s)", fontsize=8)
    ax.set_xlim(ex.time[0], ex.time[-1])
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, {"window": ex.window, "efolds": ex.efolds, "floor": floor}


def excitation_figure(result: Any) -> Figure | None:
    """The notes' persistent-excitation indicator along the desired trajectory."""
    if not _ours(result):
        return None
    ex = _excitation(result)
    if not np.any(np.isfinite(ex.alpha)):
        return None
    svg, keys, info = render_tagged(_draw_excitation, result, ex)
    caption = ("Drawn: the smallest eigenvalue of the integral of WₐᵀWₐ over a sliding window of "
               f"{info['window']:.3g} s along the desired trajectory (Wₐ: the regressor's columns of the adapted "
               "parameters; logarithmic axis, "
               f"values below {info['floor']:g} drawn at it). The averaged update removes "
               f"{info['efolds']:.3g} e-folds of a parameter error in the run (3 or more: exciting).")
    return Figure("Persistent excitation", caption, svg, "fig-adaptive-ct-excitation.svg", ("estimate_convergence",))


def _draw_spr(result: Any) -> Any:
    a = result.design.data.adaptation
    fig, (top, bottom) = new_figure(6.8, 4.8, rows=2)
    info: dict[str, Any] = {"negative": False}
    for j, (k1, k2, psi) in enumerate(zip(a.K1, a.K2, a.psi, strict=True)):
        color = JOINT_COLORS[j % len(JOINT_COLORS)]
        w = frequency_grid(k1, k2)[1:]
        re = re_h(k1, k2, psi, w)
        tag(fig, "re-h", *top.plot(w, re * k1, color=color, label=f"joint {j + 1}"))
        tag(fig, "w2-re-h", *bottom.plot(w, w * w * re, color=color, label=f"joint {j + 1}: ψK2 − 1 = "
                                                                          f"{psi * k2 - 1:.3g}"))
        info["negative"] = info["negative"] or bool(np.any(re < 0))
    tag(fig, "zero", top.axhline(0.0, color=RED, **LIMIT_STYLE), bottom.axhline(0.0, color=RED, **LIMIT_STYLE))
    for ax in (top, bottom):
        ax.set_xscale("log")
        ax.legend(loc="best", framealpha=0.9, fontsize=7)
    top.set_ylabel("K1 · Re H(jω)", fontsize=8)
    bottom.set_ylabel("ω² Re H(jω)", fontsize=8)
    bottom.set_xlabel("ω (rad/s)")
    return fig, info


def spr_figure(result: Any) -> Figure | None:
    """Re H(jw) per joint and w^2 Re H(jw), whose limit is the SPR margin psi K2 - 1."""
    if result.design.kind != KIND or result.design.data.adaptation.scheme != "craig":
        return None
    svg, keys, info = render_tagged(_draw_spr, result)
    caption = ("Drawn: for each joint, Re H(jω) of H(s) = (1 + ψ s)/(s² + K2 s + K1) scaled by K1 (top; 1 at ω = 0) "
               "and ω² Re H(jω) (bottom), which tends to ψ K2 − 1, the SPR margin named in the legend; dashed red: "
               "zero. "
               + ("Re H(jω) is negative at high frequency: the filter is not strictly positive real."
                  if info["negative"] else "Both stay positive at every frequency: strictly positive real."))
    return Figure("SPR condition of the error filter", caption, svg, "fig-adaptive-ct-spr.svg", ("spr_certificate",))


FIGURES = (error_figure, estimates_figure, excitation_figure, spr_figure)
"""The family's figures, in report order."""
