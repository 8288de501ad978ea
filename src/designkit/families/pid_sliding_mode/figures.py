"""The PID/sliding-mode controller's figures, drawn from a run: ``slm(t)`` with its band, the position against the
plant-independent sliding motion, and the command split into its PID and switching parts.

Every artist is tagged with what it shows and the caption is written from the tags drawn
(:func:`designkit.display.svg.render_tagged`), so it names nothing that is not there.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, REFERENCE_STYLE, Figure, plain_ticks
from designkit.display.numbers import sci
from designkit.display.svg import BLUE, GREEN, ORANGE, PURPLE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.pid_sliding_mode.data import LinkSlidingData
from designkit.families.pid_sliding_mode.measure import Run, measure
from designkit.families.pid_sliding_mode.spec import CHATTERING, IN_BAND, PRECISION

__all__ = ["FIGURES"]


def _caption(lead: str, phrases: dict[str, str], keys: Sequence[str]) -> str:
    also = [phrases[k] for k in keys if k in phrases]
    if not also:
        return lead
    text = also[0] if len(also) == 1 else ", ".join(also[:-1]) + " and " + also[-1]
    return f"{lead} Drawn: {text}."


def _present(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


def _events(ax: Any, fig: Any, sim: Any) -> None:
    t = np.asarray(sim.time, float)
    pert = np.asarray(sim.perturbation, float).reshape(len(t), -1)
    idx = np.flatnonzero(np.any(pert != 0.0, axis=1))
    if idx.size and idx[0] > 0:
        tag(fig, "perturbation-onset", ax.axvline(t[idx[0]], color=RED, **EVENT_STYLE, label="perturbation onset"))
    change = sim.settings.get("plant_change") if hasattr(sim.settings, "get") else None
    when = None if not change else change.get("time") if hasattr(change, "get") else None
    if when is not None and float(when) > 0:
        tag(fig, "plant-change", ax.axvline(float(when), color=PURPLE, **EVENT_STYLE, label="plant change"))


def _draw_slm(run: Run, sim: Any) -> tuple[Any, dict[str, Any]]:
    t, s = run.data["time"], run.data["slm"]
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "band", ax.fill_between([t[0], t[-1]], -run.band, run.band, color=GREEN, alpha=0.2, lw=0,
                                     label=f"band |slm| ≤ {sci(run.band)} rad·s"))
    tag(fig, "slm", *plot_decimated(ax, t, s, color=BLUE, lw=1.0, label="slm = a1 x1 + a2 x2 + x3"))
    _events(ax, fig, sim)
    ax.set_yscale("symlog", linthresh=run.band, linscale=1.0)
    plain_ticks(ax.yaxis)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("slm (rad·s)")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


_SLM = {
    "band": "the band (green) the run must stay in",
    "slm": "the sliding variable (blue)",
    "perturbation-onset": "the perturbation's onset (dotted, red)",
    "plant-change": "the plant change (dotted, purple)",
}


def sliding_variable_figure(result: Any) -> Figure | None:
    """``slm(t)`` on a symmetric-log axis linear within the band."""
    sim = result.simulation
    if sim is None or not isinstance(result.design.data, LinkSlidingData):
        return None
    run = measure(result.design, sim)
    svg, keys, _ = render_tagged(_draw_slm, run, sim)
    lead = (f"The sliding variable over the run; the axis is linear within ±{sci(run.band)} rad·s, the band, and "
            "logarithmic beyond.")
    return Figure("PID/sliding mode: the sliding variable", _caption(lead, _SLM, keys), svg,
                  "fig-pid-sm-slm.svg", _present(result, (IN_BAND,)))


def _draw_position(run: Run, sim: Any) -> tuple[Any, dict[str, Any]]:
    t = run.data["time"]
    fig, (ax, bx) = new_figure(6.8, 4.6, rows=2)
    ref = np.asarray(sim.reference[:, 0, 0], float)
    tag(fig, "reference", *plot_decimated(ax, t, ref, color=GREEN, **REFERENCE_STYLE, label="reference xD"))
    tag(fig, "ideal", *plot_decimated(ax, t, run.data["x1_ideal"], color=ORANGE, lw=1.6,
                                      label="sliding motion xD/(1 + a1 s + a2 s²)"))
    tag(fig, "x1", *plot_decimated(ax, t, run.data["x1"], color=BLUE, lw=1.0, label="position x1"))
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9)
    tag(fig, "deviation", *plot_decimated(bx, t, run.data["x1"] - run.data["x1_ideal"], color=BLUE, lw=1.0,
                                          label="x1 − sliding motion"))
    bx.axhline(run.deviation_at_band, color=GREEN, ls="--", lw=0.9)
    tag(fig, "bound", bx.axhline(-run.deviation_at_band, color=GREEN, ls="--", lw=0.9,
                                 label="±‖s/N‖₁ × band"))
    _events(bx, fig, sim)
    bx.set_xlabel("time (s)")
    bx.set_ylabel("deviation (rad)")
    bx.legend(loc="best", framealpha=0.9)
    for a in (ax, bx):
        a.set_xlim(t[0], t[-1])
    return fig, {}


_POS = {
    "reference": "the reference (dash-dot)",
    "ideal": "the plant-independent sliding motion (orange)",
    "x1": "the simulated position (blue)",
    "deviation": "their difference (lower panel)",
    "bound": "the precision the band guarantees, ±‖s/N‖₁ × band (dashed)",
    "perturbation-onset": "the perturbation's onset (dotted, red)",
    "plant-change": "the plant change (dotted, purple)",
}


def position_figure(result: Any) -> Figure | None:
    """The position against the sliding motion, and their difference against the band's precision."""
    sim = result.simulation
    if sim is None or not isinstance(result.design.data, LinkSlidingData):
        return None
    run = measure(result.design, sim)
    svg, keys, _ = render_tagged(_draw_position, run, sim)
    lead = ("The position against the motion the sliding mode imposes whatever Km, τ and the perturbation; the "
            "lower panel shows how far the run is from it.")
    return Figure("PID/sliding mode: the sliding motion", _caption(lead, _POS, keys), svg, "fig-pid-sm-position.svg",
                  _present(result, (PRECISION,)))


def _draw_u(run: Run, sim: Any) -> tuple[Any, dict[str, Any]]:
    t = run.data["time"]
    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "u", *plot_decimated(ax, t, run.data["u"], color=ORANGE, lw=0.9, label="u (commanded)"))
    tag(fig, "u0", *plot_decimated(ax, t, np.asarray(sim.signals["u0"], float), color=BLUE, lw=1.0,
                                   label="u0 (PID part)"))
    tag(fig, "du", *plot_decimated(ax, t, run.data["du"], color=PURPLE, lw=0.9, label="Δu (switching part)"))
    _events(ax, fig, sim)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("control (N·m)")
    ax.legend(loc="best", framealpha=0.9)
    return fig, {}


_U = {
    "u": "the commanded torque (orange; min/max per pixel, so chattering shows as an envelope)",
    "u0": "its PID part (blue)",
    "du": "its switching part (purple)",
    "perturbation-onset": "the perturbation's onset (dotted, red)",
    "plant-change": "the plant change (dotted, purple)",
}


def control_figure(result: Any) -> Figure | None:
    """The command and its PID and switching parts."""
    sim = result.simulation
    if sim is None or not isinstance(result.design.data, LinkSlidingData):
        return None
    run = measure(result.design, sim)
    svg, keys, _ = render_tagged(_draw_u, run, sim)
    freq = run.switching_frequency
    lead = ("The command: the PID part and the switching part that keeps slm in its band"
            + ("." if freq is None else f"; slm changes sign {freq:.4g} times per second after reaching."))
    return Figure("PID/sliding mode: the control", _caption(lead, _U, keys), svg, "fig-pid-sm-control.svg",
                  _present(result, (CHATTERING,)))


FIGURES = (sliding_variable_figure, position_figure, control_figure)
"""The family's figures, in report order."""
