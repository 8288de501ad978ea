"""The MRAC's figures, drawn from a run: plant against reference-model output with and without adaptation, the
adapted parameters against time, and the adaptation-gain study.

Each function takes the pipeline result and returns a :class:`~designkit.display.figure.Figure` (or None
when there is nothing to draw); captions are written from the keys of what was drawn
(:func:`~designkit.display.svg.render_tagged`), as the report's own figures are.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import (
    EVENT_STYLE,
    LIMIT_STYLE,
    REFERENCE_STYLE,
    Figure,
    few_log_ticks,
    off_scale_entry,
)
from designkit.display.svg import BLUE, GREEN, GREY, ORANGE, PURPLE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.mrac.boundary import GammaRun
from designkit.families.mrac.model import PARAMETERS, UNITS
from designkit.families.mrac.regressor_figures import regressor_figure
from designkit.families.mrac.runs import adapted, assess, final_link, matching

__all__ = ["FIGURES", "gamma_figure", "outputs_figure", "parameters_figure"]


def _sentence(parts: Sequence[str]) -> str:
    parts = list(parts)
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _present(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


def _fixed(result: Any) -> dict[str, np.ndarray] | None:
    """The fixed-gain run's position, error and time: the ``adaptation_error`` check's data, else simulated."""
    check = next((c for c in result.checks if c.name == "adaptation_error" and "fixed_error" in c.data), None)
    if check is not None:
        return {k: np.asarray(check.data[k]) for k in ("time", "fixed_position", "fixed_error")}
    from designkit.families.mrac.checks import fixed_comparison
    from designkit.families.mrac.study import context

    cmp = fixed_comparison(result.design, context(result))
    return {"time": cmp["time_fixed"], "fixed_position": np.asarray(cmp["fixed"].position, dtype=float),
            "fixed_error": cmp["e_fixed"]}


def _onset(result: Any, axes: Sequence[Any], fig: Any, t_end: float) -> float | None:
    change = result.loaded.spec.simulation.plant_change
    if change is None or change.time > t_end:
        return None
    for ax in axes:
        tag(fig, "plant-change", ax.axvline(change.time, color=RED, **EVENT_STYLE))
    return float(change.time)


def _draw_outputs(result: Any) -> tuple[Any, dict[str, Any]]:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    fixed = _fixed(result)
    fig, (ax, ax_e) = new_figure(6.8, 5.2, rows=2)
    tag(fig, "reference", *plot_decimated(ax, t, sim.desired[:, 0], color=GREY, **REFERENCE_STYLE, label="xD"))
    tag(fig, "model", *plot_decimated(ax, t, sim.signals["ym"], color=GREEN, lw=2.2, alpha=0.7,
                                      label="ym (reference model)"))
    if fixed is not None:
        tag(fig, "fixed", *plot_decimated(ax, fixed["time"], fixed["fixed_position"], color=ORANGE, lw=1.1,
                                          label="x1, gains frozen at their initial values"))
        tag(fig, "fixed-error", *plot_decimated(ax_e, fixed["time"], fixed["fixed_error"], color=ORANGE, lw=1.1,
                                                label="e without adaptation"))
    tag(fig, "adaptive", *plot_decimated(ax, t, sim.position, color=BLUE, lw=1.2, label="x1 with adaptation"))
    tag(fig, "adaptive-error", *plot_decimated(ax_e, t, sim.signals["e"], color=BLUE, lw=1.2,
                                               label="e with adaptation"))
    ax_e.axhline(0.0, color=GREY, lw=0.8)
    info = {"onset": _onset(result, (ax, ax_e), fig, float(t[-1]))}
    diverged = assess(sim, result.loaded.spec).diverged_at
    if diverged is not None:  # the diverging run is clipped to the scale of the others, where it leaves marked
        info["leaves"] = diverged
        kept = [sim.desired[:, 0], sim.signals["ym"], *([fixed["fixed_position"]] if fixed is not None else [])]
        ax.set_ylim(*_limits(kept))
        before = np.asarray(sim.signals["e"])[t < diverged]
        ax_e.set_ylim(*_limits([before, *([fixed["fixed_error"]] if fixed is not None else [])]))
        for a in (ax, ax_e):
            tag(fig, "leaves-scale", a.axvline(diverged, color=BLUE, **EVENT_STYLE))
    ax.set_ylabel("position (rad)")
    ax_e.set_ylabel("e = ym − x1 (rad)")
    ax_e.set_xlabel("time (s)")
    ax_e.set_xlim(t[0], t[-1])
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    ax_e.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, info


def _limits(signals: Sequence[np.ndarray], margin: float = 0.25) -> tuple[float, float]:
    """The finite extent of ``signals`` widened by ``margin`` of itself on each side."""
    values = np.concatenate([np.ravel(np.asarray(v, dtype=float)) for v in signals])
    values = values[np.isfinite(values)]
    lo, hi = (float(values.min()), float(values.max())) if values.size else (-1.0, 1.0)
    pad = margin * ((hi - lo) or max(abs(hi), 1.0))
    return lo - pad, hi + pad


def outputs_figure(result: Any) -> Figure | None:
    """The link against the reference model's output, with adaptation and with the gains frozen at their initial
    values (top), and the two output errors (bottom)."""
    if result.simulation is None or "ym" not in result.simulation.signals or "a1" not in result.simulation.signals:
        return None
    svg, keys, info = render_tagged(_draw_outputs, result)
    parts = []
    if "reference" in keys:
        parts.append("the reference xD (dash-dot)")
    if "model" in keys:
        parts.append("the reference model's output ym (wide green)")
    if "adaptive" in keys:
        parts.append("the link's position with adaptation (blue)")
    if "fixed" in keys:
        parts.append("the link's position in the same scenario with the gains frozen at their initial values "
                     "(orange)")
    caption = "Top: " + _sentence(parts) + "."
    if "adaptive-error" in keys:
        caption += (" Bottom: the output error e = ym − x1 with adaptation (blue)"
                    + (" and without (orange)." if "fixed-error" in keys else "."))
    if "plant-change" in keys:
        caption += (f" The dotted red line marks the step change of the link at t = {info['onset']:.4g} s, which "
                    "the controller is not told of.")
    if "leaves-scale" in keys:
        caption += (f" The adaptive run diverges: its output error exceeds ten times the reference's swing at "
                    f"t = {info['leaves']:.4g} s (dotted blue line); the axes keep the scale of the other signals, "
                    "so its curve is clipped.")
    return Figure("Adaptive and fixed-gain loops against the reference model", caption, svg,
                  "fig-mrac-outputs.svg", _present(result, ("adaptation_error", "adaptive_stability")))


def _matching_steps(result: Any, t: np.ndarray) -> np.ndarray:
    """The matching parameters at every instant (they step with the plant change), ``(N, 2)``."""
    spec, d = result.loaded.spec, result.design
    plant = result.plant if result.plant is not None else d.plant
    start = matching(d, (float(plant.parameter("Km").value), float(plant.parameter("tau").value)))
    end = matching(d, final_link(spec, plant))
    change = spec.simulation.plant_change
    out = np.tile(np.asarray(start, dtype=float), (t.size, 1))
    if change is not None:
        out[t >= change.time - 1e-12] = end
    return out


def _draw_parameters(result: Any) -> tuple[Any, dict[str, Any]]:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    alpha = adapted(sim)
    want = _matching_steps(result, t)
    fig, axes = new_figure(6.8, 4.8, rows=2)
    info: dict[str, Any] = {"initial": alpha[0].tolist(), "final": alpha[-1].tolist(), "diverged": False}
    for j, ax in enumerate(axes):
        name, unit = PARAMETERS[j], UNITS[j].replace("^2", "²")
        finite = np.isfinite(alpha[:, j])
        tag(fig, "matching", *plot_decimated(ax, t, want[:, j], color=GREEN, **LIMIT_STYLE,
                                             label=f"{name} matching the link"))
        tag(fig, "adapted", *plot_decimated(ax, t, alpha[:, j], color=BLUE, label=f"{name} adapted"))
        tag(fig, "initial", *ax.plot([t[0]], [alpha[0, j]], ls="none", marker="o", ms=5, color=PURPLE,
                                     label=f"initial {alpha[0, j]:.4g}"))
        if finite[-1]:
            tag(fig, "final", *ax.plot([t[-1]], [alpha[-1, j]], ls="none", marker="s", ms=5, color=RED,
                                       label=f"final {alpha[-1, j]:.4g}"))
        else:
            info["diverged"] = True
            last = np.flatnonzero(finite)
            info["diverged_at"] = float(t[last[-1]]) if last.size else float(t[0])
            tag(fig, "final-offscale", *off_scale_entry(ax, "final not finite", color=RED, marker="s", ls="none"))
        ax.set_ylabel(f"{name} ({unit})")
        ax.legend(loc="best", framealpha=0.9, fontsize=7)
    info["onset"] = _onset(result, axes, fig, float(t[-1]))
    diverged = assess(sim, result.loaded.spec).diverged_at
    if diverged is not None:  # keep the scale of the run before it diverged (and of the matching values)
        info["clipped"] = diverged
        for j, ax in enumerate(axes):
            ax.set_ylim(*_limits([alpha[t < diverged, j], want[:, j]]))
            tag(fig, "diverges", ax.axvline(diverged, color=BLUE, **EVENT_STYLE))
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(t[0], t[-1])
    return fig, info


def parameters_figure(result: Any) -> Figure | None:
    """The adapted coefficients a1, a2 against time, with their initial and final values and the values that put
    the link on the model."""
    if result.simulation is None or "a1" not in result.simulation.controller_state_names:
        return None
    svg, keys, info = render_tagged(_draw_parameters, result)
    parts = ["the adapted closed-loop coefficients a1 (top) and a2 (bottom) (blue)"]
    if "initial" in keys:
        parts.append(f"their initial values {info['initial'][0]:.4g} and {info['initial'][1]:.4g} (circles)")
    if "final" in keys:
        parts.append(f"their final values {info['final'][0]:.4g} and {info['final'][1]:.4g} (squares)")
    if "matching" in keys:
        parts.append("the values that put the true link exactly on the reference model (dashed green"
                     + (", stepping with the link" if "plant-change" in keys else "") + ")")
    caption = "Drawn: " + _sentence(parts) + "."
    if "final-offscale" in keys:
        caption += (f" The parameters stopped being finite at t = {info['diverged_at']:.4g} s: the adaptation "
                    "diverged (the final values are named in the legend only).")
    if "diverges" in keys:
        caption += (f" The run diverges at t = {info['clipped']:.4g} s (dotted blue line, where its output error "
                    "exceeds ten times the reference's swing); the axes keep the scale of the parameters before it, "
                    "so the curves are clipped.")
    if "plant-change" in keys:
        caption += f" The dotted red line marks the link's step change at t = {info['onset']:.4g} s."
    return Figure("Adapted parameters", caption, svg, "fig-mrac-parameters.svg",
                  _present(result, ("parameter_convergence", "frozen_final")))


def _draw_gamma(result: Any, s: Any) -> tuple[Any, dict[str, Any]]:
    gamma = np.asarray(result.design.data.gamma, dtype=float)
    fig, (ax,) = new_figure(6.8, 3.6, rows=1)
    extra = [GammaRun(c.scale, c.stable, c.rms_adaptive, None, c.final, "") for c in s.gains if c.scale is not None]
    runs = sorted([*s.boundary.runs, *extra], key=lambda r: r.scale)
    ok = [r for r in runs if r.stable and math.isfinite(r.rms)]
    bad = [r for r in runs if not r.stable]
    finite = [r.rms for r in runs if math.isfinite(r.rms) and r.rms > 0]
    top = max(finite) * 1.3 if finite else 1.0
    g0 = float(gamma[0])
    if ok:
        tag(fig, "bounded", *ax.plot([g0 * r.scale for r in ok], [max(r.rms, 1e-300) for r in ok], ls="-",
                                     marker="o", color=BLUE, label="bounded: RMS of e over the run"))
    if bad:
        tag(fig, "diverged", *ax.plot([g0 * r.scale for r in bad], [r.rms if math.isfinite(r.rms) else top
                                                                     for r in bad], ls="none", marker="x", ms=8,
                                      color=RED, label="not bounded (× at the top: diverged)"))
    info: dict[str, Any] = {"gamma": g0}
    if s.boundary.lo is not None and s.boundary.hi is not None:
        tag(fig, "bracket", ax.axvspan(g0 * s.boundary.lo, g0 * s.boundary.hi, color=RED, alpha=0.12,
                                       label="simulated boundary bracket"))
        info["bracket"] = (g0 * s.boundary.lo, g0 * s.boundary.hi)
    if s.floquet is not None:
        tag(fig, "floquet", ax.axvline(g0 * s.floquet["scale"], color=PURPLE, **LIMIT_STYLE,
                                       label="linearized loop (Floquet) boundary"))
        info["floquet"] = g0 * s.floquet["scale"]
    if s.frozen is not None:
        tag(fig, "frozen", ax.axvline(g0 * s.frozen["scale"], color=GREEN, **LIMIT_STYLE,
                                      label="frozen-signal Routh bound (Åström & Wittenmark)"))
        info["frozen"] = g0 * s.frozen["scale"]
    tag(fig, "spec-gamma", ax.axvline(g0, color=GREY, **EVENT_STYLE, label=f"the spec's γ1 = {g0:.4g}"))
    ax.set_xscale("log")
    few_log_ticks(ax)
    ax.set_ylim(0.0, top * 1.08)
    ax.set_xlabel("adaptation gain γ1 (all gains scaled together)")
    ax.set_ylabel("RMS e (rad)")
    ax.legend(loc="best", framealpha=0.9, fontsize=7)
    return fig, info


def gamma_figure(result: Any) -> Figure | None:
    """The adaptation-gain study: the RMS output error against the gain scale, which runs diverged, and the three
    boundary estimates (:mod:`designkit.families.mrac.boundary`)."""
    from designkit.families.mrac.study import study

    s = study(result)
    if s is None or not s.boundary.runs:
        return None
    svg, keys, info = render_tagged(_draw_gamma, result, s)
    parts = []
    if "bounded" in keys:
        parts.append("the RMS output error of the runs that stayed bounded (circles)")
    if "diverged" in keys:
        parts.append("the runs that did not (crosses; at the top when the error stopped being finite)")
    caption = ("The spec's scenario re-simulated with every adaptation gain scaled together, against γ1 "
               "(logarithmic axis): " + (_sentence(parts) if parts else "no run") + ".")
    also = []
    if "bracket" in keys:
        lo, hi = info["bracket"]
        also.append(f"the simulated boundary between γ1 = {lo:.4g} and {hi:.4g} (shaded)")
    if "floquet" in keys:
        also.append(f"where the loop linearized about the matched trajectory loses stability, γ1 = "
                    f"{info['floquet']:.4g} (dashed purple)")
    if "frozen" in keys:
        also.append(f"the frozen-signal Routh bound, γ1 = {info['frozen']:.4g} (dashed green)")
    if "spec-gamma" in keys:
        also.append(f"the spec's γ1 = {info['gamma']:.4g} (dotted)")
    if also:
        caption += " Also drawn: " + _sentence(also) + "."
    return Figure("Where the gradient rule loses stability", caption, svg, "fig-mrac-gamma.svg",
                  _present(result, ("adaptive_stability",)))


FIGURES = (outputs_figure, parameters_figure, gamma_figure, regressor_figure)
"""The family's figures, in report order."""
