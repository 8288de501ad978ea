"""The variable structure regulator's figures, drawn from a run: ``sigma(t)`` with the reaching time, the error
state against time, ``u(t)`` with the equivalent control, and the ranges of ``l_i`` over the box against
``alpha_i`` and ``beta_i``.  Every artist is tagged and the caption is written from the tags drawn."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, Figure, plain_ticks
from designkit.display.numbers import fmt_number
from designkit.display.svg import BLUE, GREEN, GREY, ORANGE, PURPLE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.vsc.data import VscData
from designkit.families.vsc.measure import VscRun, measure

__all__ = ["FIGURES"]

COLORS = (BLUE, ORANGE, GREEN, PURPLE)
SUB = dict(enumerate("₀₁₂₃₄₅₆₇₈₉"))


def _sentence(parts: Sequence[str]) -> str:
    parts = list(parts)
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _caption(lead: str, phrases: dict[str, str], keys: Sequence[str]) -> str:
    also = [phrases[k] for k in keys if k in phrases]
    return lead + (" Drawn: " + _sentence(also) + "." if also else "")


def _present(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


def _ok(result: Any) -> bool:
    return result.simulation is not None and isinstance(result.design.data, VscData)


def _draw_sigma(run: VscRun, unit: str) -> tuple[Any, dict[str, Any]]:
    d = run.data
    t, s, band = d["time"], d["sigma"], d["band"]
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "band", ax.fill_between(t, -band, band, color=GREEN, alpha=0.2, lw=0, label="hold band"))
    tag(fig, "sigma", *plot_decimated(ax, t, s, color=BLUE, lw=1.0, label="σ = c x̃"))
    if run.reaching_time is not None:
        tag(fig, "reaching", ax.axvline(t[0] + run.reaching_time, color=PURPLE, **EVENT_STYLE, label="reaching time"))
    lin = float(np.median(band[band > 0])) if np.any(band > 0) else 1e-6
    ax.set_yscale("symlog", linthresh=lin, linscale=1.0)
    plain_ticks(ax.yaxis)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"σ ({unit})")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


def sigma_figure(result: Any) -> Figure | None:
    """``sigma(t)`` on a symmetric-log axis with the hold band and the reaching time."""
    if not _ok(result):
        return None
    run = measure(result.design, result.simulation)
    k = result.design.data.drive_index
    unit = result.design.plant.states[k].unit if k is not None else ""
    svg, keys, _ = render_tagged(_draw_sigma, run, unit)
    phrases = {"band": "the band one held step can move σ by (green)", "sigma": "the switching function σ (blue)",
               "reaching": "the reaching time (dotted)"}
    when = "" if run.reaching_time is None else f" It reaches the band after {fmt_number(run.reaching_time, 4)} s."
    lead = ("The switching function over the run, on an axis linear near zero and logarithmic beyond." + when)
    return Figure("Variable structure control: the switching function", _caption(lead, phrases, keys), svg,
                  "fig-vsc-sigma.svg", _present(result, ("vsc_reaching_time", "vsc_band")))


def _draw_states(run: VscRun, names: Sequence[str]) -> tuple[Any, dict[str, Any]]:
    d = run.data
    t, x = d["time"], d["xt"]
    fig, (ax,) = new_figure(6.8, 3.6)
    for i in range(x.shape[1]):
        tag(fig, "states", *plot_decimated(ax, t, x[:, i], color=COLORS[i % 4], lw=1.0, label=f"{names[i]} − x*"))
    if run.reaching_time is not None:
        tag(fig, "reaching", ax.axvline(t[0] + run.reaching_time, color=PURPLE, **EVENT_STYLE, label="reaching time"))
    ax.axhline(0.0, color=GREY, lw=0.6)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("error state x̃")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


def states_figure(result: Any) -> Figure | None:
    """The error state against time."""
    if not _ok(result):
        return None
    run = measure(result.design, result.simulation)
    names = [f"{s.name} ({s.unit})" for s in result.design.plant.states]
    svg, keys, _ = render_tagged(_draw_states, run, names)
    phrases = {"states": "each state's deviation from the rest state at the reference", "reaching": "the reaching "
               "time (dotted)"}
    return Figure("Variable structure control: the error state", _caption(
        "The state's deviation from the rest state at the reference: after reaching it decays along σ = 0 at the "
        "sliding poles.", phrases, keys), svg, "fig-vsc-states.svg", _present(result, ("vsc_sliding_poles",)))


def _draw_u(run: VscRun, unit: str) -> tuple[Any, dict[str, Any]]:
    d = run.data
    t = d["time"]
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "u", *plot_decimated(ax, t, d["u"], color=ORANGE, lw=0.9, alpha=0.8, label="u (held per step)"))
    tag(fig, "u-eq", *plot_decimated(ax, t, d["u_eq"], color=PURPLE, lw=1.3, label="equivalent control u_eq"))
    if run.reaching_time is not None:
        tag(fig, "reaching", ax.axvline(t[0] + run.reaching_time, color=RED, **EVENT_STYLE, label="reaching time"))
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"control ({unit})")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


def control_figure(result: Any) -> Figure | None:
    """The command with the equivalent control of the run's plant."""
    if not _ok(result):
        return None
    run = measure(result.design, result.simulation)
    unit = result.design.plant.inputs[0].unit
    svg, keys, _ = render_tagged(_draw_u, run, unit)
    phrases = {"u": "the commanded input (orange, its envelope where it chatters)",
               "u-eq": "the equivalent control −(cB)⁻¹(cA x̃ + cD d) of the run's plant (purple), which the "
                       "switching averages to while sliding", "reaching": "the reaching time (dotted)"}
    frac = "" if run.ueq_fraction is None else (f" While sliding the equivalent control lies between the two "
                                                 f"switched controls on {fmt_number(100 * run.ueq_fraction, 4)} % "
                                                 "of the samples.")
    return Figure("Variable structure control: the control", _caption(
        "The control the switching law commands." + frac, phrases, keys), svg, "fig-vsc-control.svg",
        _present(result, ("vsc_equivalent_control", "vsc_chattering")))


def _draw_l(info: VscData) -> tuple[Any, dict[str, Any]]:
    n = len(info.c)
    fig, axes = new_figure(6.8, 0.8 + 1.1 * n, rows=n, sharex=False, layout="constrained")
    axes = list(axes)
    for i, ax in enumerate(axes):
        b = info.bounds[f"l_{i + 1}"]
        al, be = info.alpha[i], info.beta[i]
        tag(fig, "range", *ax.barh([0], [b.upper - b.lower], left=[b.lower], height=0.5, color=BLUE,
                                  alpha=0.5, label="range of lᵢ over the box" if i == 0 else None))
        tag(fig, "alpha", ax.axvline(al, color=ORANGE, lw=2, label="αᵢ" if i == 0 else None))
        tag(fig, "beta", ax.axvline(be, color=GREEN, lw=2, label="βᵢ" if i == 0 else None))
        lo, hi = min(al, b.lower), max(be, b.upper)
        pad = 0.1 * (hi - lo) if hi > lo else 1.0
        ax.set_xlim(lo - pad, hi + pad)
        ax.set_yticks([0])
        ax.set_yticklabels([f"l{SUB[i + 1]}"])
    axes[0].legend(loc="best", framealpha=0.9, fontsize=7)
    axes[-1].set_xlabel("gain (input per state unit)")
    return fig, {}


def gains_figure(result: Any) -> Figure | None:
    """The range of each ``l_i`` over the box against ``alpha_i`` and ``beta_i``."""
    info = result.design.data
    if not isinstance(info, VscData):
        return None
    svg, keys, _ = render_tagged(_draw_l, info)
    phrases = {"range": "the range of each equivalent-control gain lᵢ over the parameter box (blue bar)",
               "alpha": "αᵢ (orange)", "beta": "βᵢ (green)"}
    return Figure("Variable structure control: the gains against the equivalent-control gains", _caption(
        f"Theorem 3 asks αᵢ < lᵢ < βᵢ for every plant of the box ({len(info.box)} uncertain "
        "parameters); each row is one state.", phrases, keys), svg, "fig-vsc-gains.svg",
        _present(result, ("vsc_gains", "vsc_gains_enclosed")))


FIGURES = (sigma_figure, states_figure, control_figure, gains_figure)
"""The family's figures, in report order."""
