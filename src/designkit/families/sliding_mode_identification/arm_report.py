"""The robot form's report: figures (the Lyapunov function and the normalised estimation errors, the observers'
sliding variables, the excitation per window), the section, and the ``synth --json`` fields (the final estimates by
name)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, Figure
from designkit.display.numbers import fmt_number, unit
from designkit.display.section import Question, ReportSection, Table
from designkit.display.svg import BLUE, GREEN, ORANGE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.sliding_mode_identification.arm import base_of, parameter_unit
from designkit.families.sliding_mode_identification.arm_analysis import segments_of, window_rates
from designkit.families.sliding_mode_identification.arm_checks import WINDOW_FACTOR, run_of, tolerances
from designkit.families.sliding_mode_identification.checks import CONVERGED_REL, DET_REL
from designkit.families.sliding_mode_identification.data import ArmIdentifierData
from designkit.families.sliding_mode_identification.laws import KIND

__all__ = ["FIGURES", "arm_json", "arm_section"]


def _f(x: float, digits: int = 4) -> str:
    return fmt_number(x, digits) if math.isfinite(x) else "—"


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _robot(result: Any) -> bool:
    return (result.simulation is not None and isinstance(result.design.data, ArmIdentifierData)
            and result.design.kind == KIND)


def arm_json(result: Any) -> dict[str, Any]:
    """``{"estimates": {name: value}, "identification": {...}}``: the estimates at the end of the run (SI units of
    each), and under ``identification`` the true values at the end, the initial estimates, the units and the known
    base parameters (convention ``u = Wb(q, qd, qdd) beta``, the model layer's base parameters)."""
    x = result.design.data
    names = x.identifier.names
    if result.simulation is None:
        return {"estimates": None}
    run = run_of(result.design, result)
    known = {x.base_names[c]: v for c, v in x.identifier.known}
    return {"estimates": {n: _num(float(v)) for n, v in zip(names, run.estimate[-1], strict=True)},
            "identification": {"convention": "u = Wb(q, qd, qdd) beta, beta the base parameters of the model layer",
                               "units": {n: u for n, u in zip(names, x.units, strict=True)},
                               "initial": dict(zip(names, x.initial, strict=True)),
                               "true_final": {n: float(v) for n, v in zip(names, run.theta[-1], strict=True)},
                               "known": known}}


def _change(result: Any) -> float | None:
    change = result.loaded.spec.simulation.plant_change
    return float(change.time) if change is not None else None


def _mark(fig: Any, axes: Any, onset: float | None) -> None:
    if onset is not None:
        for ax in axes:
            tag(fig, "plant-change", ax.axvline(onset, color=RED, **EVENT_STYLE))


def _step(result: Any) -> str:
    onset = _change(result)
    return f" The dotted red line marks the arm's step change at t = {onset:g} s." if onset is not None else ""


def _scales(result: Any, run: Any) -> np.ndarray:
    spec = result.loaded.spec
    last = segments_of(spec, run.t, run.ident.window, run.ident.Ts)[-1]
    return tolerances(run, last, np.asarray(result.simulation.u_command, dtype=float)[run.rows])


def _draw_errors(result: Any) -> tuple[Any, dict[str, Any]]:
    run = run_of(result.design, result)
    scale = _scales(result, run)
    fig, (top, bottom) = new_figure(6.8, 5.0, rows=2)
    V0 = max(float(run.V[0]), 1e-300)
    tag(fig, "lyapunov", *plot_decimated(top, run.t, np.maximum(run.V / V0, 1e-16), color=BLUE,
                                         label="V(t)/V(0)"))
    top.set_yscale("log")
    top.set_ylabel("V / V(0)")
    top.legend(loc="best", fontsize=7)
    colors = ("C0", "C1", "C2", "C3", "C4", "C5", "C6", "C7", "C8", "C9")
    for i, name in enumerate(run.ident.names):
        err = 100.0 * (run.estimate[:, i] - run.theta[:, i]) / scale[i]
        tag(fig, "error", *plot_decimated(bottom, run.t, err, color=colors[i % len(colors)], lw=0.8, label=name))
    band = 100.0 * CONVERGED_REL
    tag(fig, "band", bottom.axhline(band, color=GREEN, ls=":"), bottom.axhline(-band, color=GREEN, ls=":"))
    bottom.set_yscale("symlog", linthresh=band)
    bottom.set_ylabel("error (% of scale)")
    bottom.set_xlabel("time (s)")
    bottom.legend(loc="upper right", fontsize=6, ncol=5)
    _mark(fig, (top, bottom), _change(result))
    return fig, {}


def _draw_sliding(result: Any) -> tuple[Any, dict[str, Any]]:
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    n = len(result.design.data.identifier.K1)
    fig, axes = new_figure(6.8, 1.0 + 1.4 * n, rows=n)
    for j, ax in enumerate(axes):
        tag(fig, "slm", *plot_decimated(ax, t, np.asarray(sim.signals[f"slm{j + 1}"], dtype=float), color=ORANGE,
                                        label=f"joint {j + 1}: q̂̇{j + 1} − q̇{j + 1}"))
        ax.set_ylabel("rad/s")
        ax.legend(loc="upper right", fontsize=7)
    axes[-1].set_xlabel("time (s)")
    _mark(fig, axes, _change(result))
    return fig, {}


def _windows(result: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    run = run_of(result.design, result)
    length = WINDOW_FACTOR * run.ident.window
    parts = [window_rates(run, m, length) for m in segments_of(result.loaded.spec, run.t, run.ident.window,
                                                               run.ident.Ts)]
    ends, kappa, rate = (np.concatenate([p[k] for p in parts]) for k in range(3))
    return ends, kappa, rate, length


def _draw_excitation(result: Any) -> tuple[Any, dict[str, Any]]:
    ends, kappa, rate, length = _windows(result)
    fig, (top, bottom) = new_figure(6.8, 4.2, rows=2)
    tag(fig, "kappa", *top.plot(ends, kappa, "o-", color=BLUE, ms=3, lw=0.8, label="contraction κ per window"))
    tag(fig, "threshold", top.axhline(1 - DET_REL, color=GREEN, ls=":", label=f"κ = {1 - DET_REL:g}"))
    top.set_ylabel("κ")
    top.legend(loc="best", fontsize=7)
    tag(fig, "rate", *bottom.plot(ends, np.maximum(rate, 0.0), "o-", color=ORANGE, ms=3, lw=0.8,
                                  label="smallest eigenvalue of Γ½ Ḡ Γ½"))
    bottom.set_ylabel("1/s")
    bottom.set_xlabel("end of the window (s)")
    bottom.legend(loc="best", fontsize=7)
    _mark(fig, (top, bottom), _change(result))
    return fig, {}


def _present(result: Any, name: str) -> tuple[str, ...]:
    return (name,) if any(c.name == name for c in result.checks) else ()


def errors_figure(result: Any) -> Figure | None:
    """``V(t)/V(0)`` and each estimate's error in % of its scale."""
    if not _robot(result):
        return None
    svg, _, _ = render_tagged(_draw_errors, result)
    return Figure("Lyapunov function and estimation errors",
                  "Drawn: V = (θ − θ̂)ᵀ Γ⁻¹ (θ − θ̂) relative to its initial value (top, blue, log scale) and the error "
                  "of each identified base parameter in % of max(|θi|, 0.01 rms u / rms Yi) (bottom, one colour per "
                  f"parameter, symmetric log scale) with the ±{100 * CONVERGED_REL:g} % band (dotted green)."
                  + _step(result), svg, "fig-smid-arm-errors.svg",
                  _present(result, "identification_convergence") + _present(result, "identification_lyapunov"))


def sliding_figure(result: Any) -> Figure | None:
    """Each joint's observer sliding variable."""
    if not _robot(result):
        return None
    svg, _, _ = render_tagged(_draw_sliding, result)
    return Figure("The observers' sliding variables",
                  "Drawn: each joint's sliding variable, the observer's speed estimate minus the measured speed "
                  "(orange); on the sliding mode it stays within Ts (kj + the model term's error), below 2 Ts kj."
                  + _step(result),
                  svg, "fig-smid-arm-sliding.svg", _present(result, "switching_condition"))


def excitation_figure(result: Any) -> Figure | None:
    """The contraction and the slowest averaged rate per excitation window."""
    if not _robot(result):
        return None
    svg, _, _ = render_tagged(_draw_excitation, result)
    length = WINDOW_FACTOR * result.design.data.window
    return Figure("Excitation per window",
                  f"Drawn: over each window of {length:g} s, the contraction κ, the largest V(end)/V(start) the "
                  "update can leave whatever the error (top, blue; below the dotted green line every direction is "
                  "excited), and the smallest eigenvalue of Γ½ Ḡ Γ½, Ḡ the window's mean two-point information "
                  "matrix (bottom, orange)." + _step(result), svg, "fig-smid-arm-excitation.svg",
                  _present(result, "determinant_condition"))


FIGURES = (errors_figure, sliding_figure, excitation_figure)
"""The robot form's figures, in report order."""


def _sentence(text: str) -> str:
    return text[0].upper() + text[1:] + "."


def arm_section(result: Any) -> ReportSection | None:
    """Estimates, errors and the conditions in words and tables."""
    if not _robot(result):
        return None
    x = result.design.data
    ident = x.identifier
    run = run_of(result.design, result)
    spec = result.loaded.spec
    scale = _scales(result, run)
    tables = []
    for mask in segments_of(spec, run.t, run.ident.window, run.ident.Ts):
        idx = np.flatnonzero(mask)
        k = idx[-1]
        rows = []
        for i, name in enumerate(run.ident.names):
            rel = np.abs(run.estimate[idx, i] - run.theta[idx, i]) / scale[i]
            inside = np.flatnonzero(rel <= CONVERGED_REL)
            settled = [j for j in inside if np.all(rel[j:] <= CONVERGED_REL)]
            when = f"{run.t[idx[settled[0]]]:.3g} s" if settled else "not within the segment"
            rows.append((name, unit(parameter_unit(name)) or "—", _f(float(run.theta[k, i])),
                         _f(float(run.estimate[k, i])), _f(100 * float(rel[-1]), 3), when))
        tables.append(Table(f"From {run.t[idx[0]]:.3g} s to {run.t[k]:.3g} s: the true and estimated base parameters "
                            f"at the end, the error in % of max(|θi|, 0.01 rms u / rms Yi), and when it entered the "
                            f"{100 * CONVERGED_REL:g} % band for good",
                            ("Parameter", "Unit", "True", "Estimated", "Error (%)", "Within the band from"),
                            tuple(rows)))
    checks = {c.name: c for c in result.checks}
    said = [_sentence(checks[n].detail) for n in
            ("identification_convergence", "switching_condition", "determinant_condition", "identification_lyapunov")
            if n in checks]
    base = base_of(result.design.plant)
    questions = (
        Question("Do the estimates converge to the arm's base parameters?", tuple(said[:1]), tuple(tables)),
        Question("Do the observers' switching condition, the excitation condition and the Lyapunov function hold?",
                 tuple(said[1:])),
        Question("Which parameters are identified, and how are they defined?",
                 (f"The arm's torque is linear in its {len(base.names)} base parameters, u = Wb(q, q̇, q̈) β (the model "
                  "layer's regressor, its dependent columns regrouped): " + "; ".join(base.regrouping) + ".",
                  f"Identified: {', '.join(run.ident.names)}"
                  + (f"; known at the model's values: {', '.join(x.base_names[c] for c, _ in ident.known)}."
                     if ident.known else "."))),
    )
    K1 = ", ".join(_f(v) for v in ident.K1)
    K2 = ", ".join(_f(v) for v in ident.K2)
    intro = (f"A PD servo per joint (K1 = {K1} N·m/rad, K2 = {K2} N·m·s/rad) drives the arm along the reference; every "
             f"{_f(ident.Ts)} s each joint's sliding-mode observer gives its acceleration by the equivalent "
             f"switching term (k = {', '.join(_f(v) for v in ident.switching)} rad/s²), and the gradient rule on "
             f"two time points D = {_f(ident.window)} s apart updates the {len(run.ident.names)} identified base "
             f"parameters, normalised when a sample's step would exceed 1. {x.gains_source}")
    return ReportSection("smid-arm", "Sliding-mode identification of the arm's base parameters (notes §5.5)", intro,
                         questions)
