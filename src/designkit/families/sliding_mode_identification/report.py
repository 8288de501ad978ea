"""The identification's report section (estimates against the true values, the observer's sliding variable, the
determinant monitor) and its top-level JSON fields ``a_hat``, ``b_hat`` (and ``identification``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, Figure
from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table
from designkit.display.svg import BLUE, GREEN, ORANGE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.sliding_mode_identification import arm_report
from designkit.families.sliding_mode_identification.checks import (
    CONVERGED_REL,
    DET_REL,
    segments,
    true_parameters,
)
from designkit.families.sliding_mode_identification.data import ArmIdentifierData

__all__ = ["FIGURES", "determinant_figure", "estimates_figure", "json", "section", "sliding_figure"]



def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def json(result: Any) -> dict[str, Any]:
    """``{"a_hat": ..., "b_hat": ..., "identification": {...}}``: the estimates at the end of the run (1/s,
    (rad/s^2)/(N*m)), and, under ``identification``, the true values at the end and the units (convention
    ``x2' = -a x2 + b u``, ``a = 1/tau``, ``b = Km/tau``)."""
    if isinstance(result.design.data, ArmIdentifierData):
        return arm_report.arm_json(result)
    sim = result.simulation
    if sim is None:
        return {"a_hat": None, "b_hat": None}
    ah, bh = float(sim.signals["a_hat"][-1]), float(sim.signals["b_hat"][-1])
    plant = result.plant if result.plant is not None else result.design.plant
    t = np.asarray(sim.time, dtype=float)
    a, b = true_parameters(result.loaded.spec, plant, t)
    return {"a_hat": _num(ah), "b_hat": _num(bh),
            "identification": {"convention": "x2' = -a x2 + b u, a = 1/tau, b = Km/tau", "units": ["1/s",
                               "rad/(s^2*N*m)"], "initial": list(result.design.data.initial),
                               "true_final": [float(a[-1]), float(b[-1])]}}


def _change(result: Any) -> float | None:
    change = result.loaded.spec.simulation.plant_change
    return float(change.time) if change is not None else None


def _mark(fig: Any, axes: Any, onset: float | None) -> None:
    if onset is not None:
        for ax in axes:
            tag(fig, "plant-change", ax.axvline(onset, color=RED, **EVENT_STYLE))


def _draw_estimates(result: Any) -> tuple[Any, dict[str, Any]]:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    plant = result.plant if result.plant is not None else result.design.plant
    a, b = true_parameters(result.loaded.spec, plant, t)
    fig, axes = new_figure(6.8, 4.4, rows=2)
    for ax, name, true, label, unit in ((axes[0], "a_hat", a, "a", "1/s"),
                                        (axes[1], "b_hat", b, "b", "rad/(s²·N·m)")):
        tag(fig, "estimate", *plot_decimated(ax, t, np.asarray(sim.signals[name], dtype=float), color=BLUE,
                                             label=f"estimate of {label}"))
        tag(fig, "true", *ax.plot(t, true, ls="--", color=GREEN, label=f"true {label}"))
        ax.set_ylabel(f"{label} ({unit})")
        ax.legend(loc="best", fontsize=7)
    axes[1].set_xlabel("time (s)")
    _mark(fig, axes, _change(result))
    return fig, {}


def _draw_sliding(result: Any) -> tuple[Any, dict[str, Any]]:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    fig, (ax,) = new_figure(6.8, 3.0, rows=1)
    tag(fig, "slm", *plot_decimated(ax, t, np.asarray(sim.signals["slm"], dtype=float), color=ORANGE,
                                    label="sliding variable x̂2 − x2"))
    ax.set_ylabel("x̂2 − x2 (rad/s)")
    ax.set_xlabel("time (s)")
    _mark(fig, [ax], _change(result))
    return fig, {}


def _draw_determinant(result: Any) -> tuple[Any, dict[str, Any]]:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    det = np.asarray(sim.signals["det"], dtype=float)
    fig, (ax,) = new_figure(6.8, 3.0, rows=1)
    tag(fig, "det", *plot_decimated(ax, t, det, color=BLUE, label="determinant of the two time points"))
    peak = float(np.max(np.abs(det))) if det.size else 0.0
    if peak > 0:
        tag(fig, "threshold", ax.axhline(DET_REL * peak, color=GREEN, ls=":"), ax.axhline(-DET_REL * peak,
                                                                                          color=GREEN, ls=":"))
    ax.set_ylabel("det (rad·N·m/s)")
    ax.set_xlabel("time (s)")
    _mark(fig, [ax], _change(result))
    return fig, {}


def _step(result: Any) -> str:
    onset = _change(result)
    return f" The dotted red line marks the link's step change at t = {onset:g} s." if onset is not None else ""


def estimates_figure(result: Any) -> Figure | None:
    """The estimates of a and b against the true values over time."""
    if result.simulation is None or "a_hat" not in result.simulation.signals:
        return None
    svg, _, _ = render_tagged(_draw_estimates, result)
    return Figure("Estimates against the true values",
                  "Drawn: the estimates of a = 1/τ (top) and b = Km/τ (bottom) (blue) and the true values "
                  "(dashed green)." + _step(result), svg, "fig-smid-estimates.svg", _present(result,
                                                                                            "identification_convergence"))


def sliding_figure(result: Any) -> Figure | None:
    """The observer's sliding variable over time."""
    if result.simulation is None or "slm" not in result.simulation.signals:
        return None
    svg, _, _ = render_tagged(_draw_sliding, result)
    return Figure("The observer's sliding variable",
                  "Drawn: the sliding variable of the observer, its speed estimate minus the measured speed "
                  "(orange); on the sliding mode it stays within one sample's switching step." + _step(result),
                  svg, "fig-smid-sliding.svg", _present(result, "switching_condition"))


def determinant_figure(result: Any) -> Figure | None:
    """The determinant of the two time points over time, with the band counted as zero."""
    if result.simulation is None or "det" not in result.simulation.signals:
        return None
    svg, _, _ = render_tagged(_draw_determinant, result)
    return Figure("Determinant monitor",
                  "Drawn: the determinant of the speed and the command at the two time points D apart (blue) "
                  f"and the band of {DET_REL:g} times its largest magnitude counted as zero (dotted green)."
                  + _step(result), svg, "fig-smid-determinant.svg", _present(result, "determinant_condition"))


def _present(result: Any, name: str) -> tuple[str, ...]:
    return (name,) if any(c.name == name for c in result.checks) else ()


FIGURES = (estimates_figure, sliding_figure, determinant_figure)
"""The link's figures, in report order (the family's are these and the robot form's,
:data:`~designkit.families.sliding_mode_identification.arm_report.FIGURES`: each draws for its own form only)."""


def _f(x: float, digits: int = 4) -> str:
    return fmt_number(x, digits) if math.isfinite(x) else "—"


def _sentence(text: str) -> str:
    first = text.split(" ", 1)[0]
    return (text if any(ch in first for ch in "âb̂[|") else text[0].upper() + text[1:]) + "."


def section(result: Any) -> ReportSection | None:
    """Estimates, errors and the conditions, in words and a table, with the three figures."""
    sim = result.simulation
    if sim is None:
        return None
    if isinstance(result.design.data, ArmIdentifierData):
        return arm_report.arm_section(result)
    x = result.design.data
    t = np.asarray(sim.time, dtype=float)
    plant = result.plant if result.plant is not None else result.design.plant
    spec = result.loaded.spec
    a, b = true_parameters(spec, plant, t)
    ah, bh = (np.asarray(sim.signals[n], dtype=float) for n in ("a_hat", "b_hat"))
    rows = []
    for mask in segments(spec, t, x.window, x.Ts):
        idx = np.flatnonzero(mask)
        k = idx[-1]
        rel = np.maximum(np.abs(ah - a) / np.abs(a), np.abs(bh - b) / np.abs(b))
        inside = idx[rel[idx] <= CONVERGED_REL]
        settled = [i for i in inside if np.all(rel[i:k + 1] <= CONVERGED_REL)]
        when = f"{t[settled[0]]:.3g} s" if settled else "not within the segment"
        rows.append((f"{t[idx[0]]:.3g} s to {t[k]:.3g} s", f"{_f(a[k])} 1/s, {_f(b[k])} rad/(s²·N·m)",
                     f"{_f(ah[k])} 1/s, {_f(bh[k])} rad/(s²·N·m)", when))
    table = Table("Estimates at the end of each segment with a fixed link, and when they entered the "
                  f"{100 * CONVERGED_REL:g} % band for good",
                  ("Segment", "True a, b", "Estimated a, b", "Within the band from"), tuple(rows))
    checks = {c.name: c for c in result.checks}
    said = [_sentence(checks[n].detail) for n in
            ("identification_convergence", "switching_condition", "determinant_condition", "identification_lyapunov")
            if n in checks]
    questions = (
        Question("Do the estimates converge to the link's a = 1/τ and b = Km/τ?", tuple(said[:1]), (table,)),
        Question("Do the observer's switching condition, the Lyapunov function and the determinant condition hold?",
                 tuple(said[1:])),
    )
    intro = (f"A PD servo (K1 = {_f(x.K1)} N·m/rad, K2 = {_f(x.K2)} N·m·s/rad) drives the link; every "
             f"{_f(x.Ts)} s the sliding-mode observer's equivalent switching term gives the acceleration, and "
             f"the gradient rule on two time points D = {_f(x.window)} s apart updates the estimates "
             f"(γa = {_f(x.gamma[0])} s/rad², γb = {_f(x.gamma[1])} 1/(s·N²·m²)), from a = "
             f"{_f(x.initial[0])} 1/s, b = {_f(x.initial[1])} rad/(s²·N·m). Sign convention: "
             "x2' = −a x2 + b u (that of §5.1; §5.5 writes +a x2).")
    return ReportSection("smid", "Sliding-mode parameter identification (notes §5.5)", intro, questions)
