"""Report figures as deterministic SVG text (matplotlib, imported lazily).

Figures come from two tables, so a new family or check adds its figure without touching the
others:

* :data:`DESIGN_FIGURES` -- drawn from the design and the simulation (pole-zero map, ideal
  linear response, nonlinear simulation per joint);
* :data:`CHECK_FIGURES` -- keyed by check name, drawn from that check's certificate and data
  (the loop margins' Bode plots, the robustness lattice, the intercoupling).

Analysis is never done here: margins, frequency responses, stability over the lattice and the
decoupled predictions are computed by the checks (:mod:`designkit.verification`); figures only
draw them, and every caption is written from what is drawn.  Rendering (rc settings, palette,
byte-for-byte reproducible SVG, decimation) lives in :mod:`designkit.report.svg`.

Any finite value a spec accepts can be drawn: a requirement or element level far from the signals
(more than :data:`OFF_SCALE` times their extent, e.g. a 1e6 N*m saturation on a 30 N*m command) is
named in the legend as "off scale" instead of squashing the signals or overflowing matplotlib's
axis arithmetic, and signal samples beyond :data:`~designkit.report.svg.MAX_DRAWN` are left out.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.report.heatmap import robustness_svg
from designkit.report.svg import (
    BLUE,
    GREEN,
    GREY,
    MAX_DRAWN,
    ORANGE,
    PURPLE,
    RED,
    drawable,
    new_figure,
    plot_decimated,
    render,
)
from designkit.verification.loop import achieved_zeros

__all__ = ["CHECK_FIGURES", "DESIGN_FIGURES", "Figure", "design_figures"]

_JOINT_COLORS = (BLUE, GREEN, PURPLE, ORANGE, RED, GREY)

OFF_SCALE = 3.0
"""A level is drawn when it lies within this many times the extent of the drawn signals beyond them
(for a control limit: at most this many times the peak |u|); otherwise it is only named in the legend,
marked "off scale"."""


def on_scale(levels: Sequence[float], *signals: Any) -> bool:
    """True when every level (same unit as the signals) can be drawn without squashing the ``signals``.

    The signals' finite samples span ``[lo, hi]``; a level is on scale within ``OFF_SCALE * extent`` of
    that span, ``extent`` being ``hi - lo`` or, for a constant signal, its magnitude.  Non-finite levels,
    levels beyond :data:`~designkit.report.svg.MAX_DRAWN` and signals without a finite sample are off scale.

    Examples
    --------
    >>> on_scale([1.1], [0.0, 1.0]), on_scale([1e308], [0.0, 1.0]), on_scale([0.5 + 1e-300], [0.0, 1.0])
    (True, False, True)
    """
    values = np.concatenate([np.ravel(drawable(s)) for s in signals]) if signals else np.array([])
    values = values[np.isfinite(values)]
    levels = np.asarray(levels, dtype=float)
    if values.size == 0 or not np.all(np.abs(levels) <= MAX_DRAWN):
        return False
    lo, hi = float(np.min(values)), float(np.max(values))
    extent = (hi - lo) or abs(hi)
    if extent == 0.0:
        return bool(np.all(levels == 0.0))
    return bool(np.all((levels >= lo - OFF_SCALE * extent) & (levels <= hi + OFF_SCALE * extent)))


def _off_scale(ax: Any, label: str, **style: Any) -> None:
    """A legend entry for a level that is not drawn."""
    ax.plot([], [], label=f"{label} (off scale)", **style)


@dataclass(frozen=True)
class Figure:
    """One report figure.

    Parameters
    ----------
    title : str
        Short title shown above the figure.
    caption : str
        What the figure shows and how to read it (written from what is drawn).
    svg : str
        A standalone SVG document.
    filename : str
        File name used when the figure is written next to the Typst source (``*.svg``).
    """

    title: str
    caption: str
    svg: str
    filename: str


def _joint_label(design: Any, j: int) -> str:
    return "" if len(design.plant.positions) == 1 else f" (joint {j + 1})"


def _pos_name(design: Any, j: int) -> str:
    return design.plant.states[design.plant.positions[j]].name


# ----------------------------------------------------------------------------- pole-zero map


def _requested_poles(design: Any) -> np.ndarray:
    return np.array([*design.poles, *[p for loop in design.loops for p in loop.poles]], dtype=complex)


def _draw_pole_zero(design: Any) -> Any:
    fig, (ax,) = new_figure(6.4, 3.0)
    achieved = np.linalg.eigvals(design.closed_loop.A)
    zeros = achieved_zeros(design)
    req_p = _requested_poles(design)
    req_z = np.array(design.zeros, dtype=complex)
    ax.axvline(0.0, color=GREY, lw=0.8)
    ax.axhline(0.0, color=GREY, lw=0.8)
    per_loop = bool(design.loops)
    if req_p.size:
        ax.plot(req_p.real, req_p.imag, "o", ms=13, mfc="none", mec=ORANGE, mew=1.6, ls="none",
                label="requested poles (per joint loop)" if per_loop else "requested poles")
    ax.plot(achieved.real, achieved.imag, "x", ms=9, color=BLUE, mew=2.0, ls="none",
            label="coupled closed-loop poles" if per_loop else "achieved poles")
    if req_z.size:
        ax.plot(req_z.real, req_z.imag, "s", ms=13, mfc="none", mec=ORANGE, mew=1.6, ls="none",
                label="requested zero")
    if zeros.size:
        ax.plot(zeros.real, zeros.imag, "o", ms=7, mfc="none", mec=BLUE, mew=1.8, ls="none",
                label="achieved zero (xD→x1)")
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


def pole_zero_figure(result: Any) -> Figure | None:
    """Achieved (or coupled) closed-loop poles against the requested ones."""
    design = result.design
    if design.closed_loop is None:
        return None
    n_ach = len(design.closed_loop.A)
    n_req = len(_requested_poles(design))
    if design.loops:
        caption = (f"The {n_ach} poles of the coupled arm's closed loop, linearized at the design configuration (×), "
                   f"against the {n_req} poles each joint loop places on its own simplified link model (○); the "
                   "distance between them is the intercoupling the per-link design ignores.")
    else:
        caption = (f"The {n_ach} achieved closed-loop poles (eigenvalues of the linearized closed loop, ×) against the "
                   f"{n_req} requested poles (○); each × should sit in the centre of a ○.")
    if design.zeros:
        caption += " Zeros of the reference-to-position transfer xD→x1 (small ○) against the requested zero (□)."
    return Figure("Pole-zero map", caption, render(_draw_pole_zero, design), "fig-pole-zero.svg")


# ----------------------------------------------------------------------------- linear response


def _time_grid(design: Any, spec: Any, horizon: float) -> np.ndarray:
    duration = spec.simulation.duration
    if duration is None:
        slowest = min((abs(p.real) for p in np.linalg.eigvals(design.closed_loop.A) if abs(p.real) > 1e-9),
                      default=1.0)
        duration = 8.0 / slowest
        req = spec.requirements
        if req is not None and req.settling_time is not None:
            duration = max(duration, 2.0 * req.settling_time)
        duration += horizon
    return np.linspace(0.0, float(duration), 1500)


def _draw_linear(design: Any, t: np.ndarray, ref: np.ndarray, positions: np.ndarray, u: np.ndarray,
                 limit: float | None) -> Any:
    fig, (ax, ax_u) = new_figure(6.8, 4.6, rows=2)
    fig.get_layout_engine().set(h_pad=0.06)
    n = positions.shape[1]
    for j in range(n):
        color = _JOINT_COLORS[j % len(_JOINT_COLORS)]
        ax.plot(t, drawable(ref[:, j, 0]), color=color, ls="--", lw=1.0,
                label=f"xD{_joint_label(design, j)} (reference)")
        ax.plot(t, drawable(positions[:, j]), color=color, label=f"{_pos_name(design, j)} (linear, nominal)")
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9)
    for k in range(u.shape[1]):
        ax_u.plot(t, drawable(u[:, k]), color=_JOINT_COLORS[k % len(_JOINT_COLORS)], label=design.plant.inputs[k].name)
    if limit is not None:
        _control_limit(ax_u, limit, u)
    ax_u.set_xlabel("time (s)")
    ax_u.set_ylabel("control (N·m)")
    ax_u.legend(loc="best", framealpha=0.9)
    ax_u.set_xlim(t[0], t[-1])
    return fig


def linear_figure(result: Any) -> Figure | None:
    """The nominal linear closed loop driven by the spec's reference (no nonlinearity, delay, noise)."""
    from designkit.families import family
    from designkit.simulation.linear import linear_response
    from designkit.simulation.reference import reference_for

    design, spec = result.design, result.loaded.spec
    if design.closed_loop is None or family(design.kind).motion is not None:
        return None  # a task-space reference does not drive the joint-space linearization
    kind = family(design.kind).reference
    reference = reference_for(kind, spec.simulation, len(design.plant.positions))
    t = _time_grid(design, spec, reference.horizon)
    ref = reference.evaluate(t)
    positions, u = linear_response(design, t, ref)
    req = spec.requirements
    limit = _common_limit(req.max_control) if req is not None else None
    shown = limit is not None and _limit_on_scale(limit, u)
    word = "trajectory" if kind == "trajectory" else "step"
    caption = (f"The nominal closed loop linearized at its operating point, driven by the {word} reference (dashed), "
               "without saturation, delay, noise or perturbation: the response the design predicts. Bottom: the "
               "control it needs")
    caption += (f", with the limit |u| ≤ {limit:g} N·m." if shown else
                f" (the limit |u| ≤ {limit:g} N·m is off scale)." if limit is not None else ".")
    svg = render(_draw_linear, design, t, ref, positions, u, limit)
    return Figure(f"Ideal linear {word} response", caption, svg, "fig-linear-response.svg")


def _common_limit(limit: Any) -> float | None:
    """One control limit to draw: the limit itself, or the common value of per-input limits (None when they
    differ -- they are then only in the max_control check)."""
    if limit is None:
        return None
    arr = np.atleast_1d(np.asarray(limit, dtype=float))
    return float(arr[0]) if np.all(arr == arr[0]) else None


def _limit_on_scale(limit: float, *signals: Any) -> bool:
    """A symmetric limit ``|u| <= limit`` is drawn when it is at most ``OFF_SCALE`` times the signals' peak."""
    values = np.concatenate([np.ravel(drawable(s)) for s in signals])
    values = values[np.isfinite(values)]
    peak = float(np.max(np.abs(values))) if values.size else 0.0
    return bool(peak > 0.0 and limit <= OFF_SCALE * peak)


def _control_limit(ax: Any, limit: float, *signals: Any) -> None:
    """Draw ``|u| <= limit``; a limit far beyond the signals (more than ``OFF_SCALE`` times their peak) is named
    in the legend only."""
    label = f"|u| ≤ {limit:g} N·m"
    if _limit_on_scale(limit, *signals):
        ax.axhline(limit, color=RED, ls="--", lw=1.0, label=label)
        ax.axhline(-limit, color=RED, ls="--", lw=1.0)
    else:
        _off_scale(ax, label, color=RED, ls="--", lw=1.0)


# ----------------------------------------------------------------------------- nonlinear simulation


def _at_rest(t: np.ndarray, xd: np.ndarray) -> bool:
    """True when the reference is constant and non-zero over the last 20 % of the window."""
    tail = np.asarray(xd, float)[t >= t[0] + 0.8 * (t[-1] - t[0])]
    final = float(tail[-1]) if tail.size else 0.0
    return final != 0.0 and float(np.ptp(tail)) <= 1e-9 * max(1.0, abs(final))


def _draw_envelope(ax: Any, t: np.ndarray, start: float, target: float, req: Any, signals: Sequence[Any]) -> list[str]:
    """The requirement envelope of a step from ``start`` to ``target`` (rad); a level off the scale of
    ``signals`` (:func:`on_scale`) is only named in the legend.  Returns what the caption should name."""
    a = target - start
    mag = abs(a)
    t_end = float(t[-1])
    drawn = []
    if req.overshoot is not None:
        level = target + math.copysign(mag * req.overshoot / 100.0, a)
        label = f"overshoot limit ({req.overshoot:g} %)"
        if on_scale([level], *signals):
            ax.axhline(level, color=RED, ls="--", lw=1.0, label=label)
            drawn.append("the overshoot limit")
        else:
            _off_scale(ax, label, color=RED, ls="--", lw=1.0)
            drawn.append("the overshoot limit (off scale)")
    if req.settling_time is not None and req.settling_time < t_end:
        band = req.settling_band * mag
        ax.fill_between([req.settling_time, t_end], target - band, target + band, color=GREEN, alpha=0.18, lw=0,
                        label=f"settling band ±{100 * req.settling_band:g} % after {req.settling_time:g} s")
        drawn.append("the settling band")
    if req.steady_state_error is not None:
        e = req.steady_state_error
        from designkit.verification.tolerances import STEADY_STATE_WINDOW

        t0 = t[0] + (1.0 - STEADY_STATE_WINDOW) * (t_end - t[0])
        label = f"steady-state band ±{e:g} rad (last {100 * STEADY_STATE_WINDOW:g} %)"
        if on_scale([target - e, target + e], *signals):
            ax.hlines([target - e, target + e], t0, t_end, colors=ORANGE, lw=1.2, label=label)
            drawn.append("the steady-state band")
        else:
            _off_scale(ax, label, color=ORANGE, lw=1.2)
            drawn.append("the steady-state band (off scale)")
    return drawn


_ELEMENT_LEVELS = {"saturation": ("limit", "saturation ±limit"), "relay": ("amplitude", "relay ±amplitude")}


def _element_levels(ax: Any, element: Any, *signals: Any) -> str | None:
    """Draw the element's output levels ``±level`` (N*m); levels off the scale of the control ``signals``
    (more than ``OFF_SCALE`` times their peak) are only named in the legend.  Returns what the caption
    should name (None: no levels)."""
    if not hasattr(element, "get") or element.get("kind") not in _ELEMENT_LEVELS:
        return None
    key, label = _ELEMENT_LEVELS[element["kind"]]
    level = element.get(key)
    levels = [level] if isinstance(level, int | float) else list(level or [])
    levels = [float(lv) for lv in levels if isinstance(lv, int | float) and math.isfinite(lv)]
    if not levels:
        return None
    shown = [lv for lv in levels if _limit_on_scale(abs(lv), *signals)]
    for k, lv in enumerate(shown):
        ax.axhline(lv, color=ORANGE, ls=":", lw=1.0, label=label if k == 0 else None)
        ax.axhline(-lv, color=ORANGE, ls=":", lw=1.0)
    if len(shown) < len(levels):
        off = ", ".join(f"{lv:g}" for lv in levels if lv not in shown)
        _off_scale(ax, f"{label} = {off} N·m", color=ORANGE, ls=":", lw=1.0)
        return f"the element's output levels ({'some ' if shown else ''}off scale)"
    return "the element's output levels"


def _draw_simulation(design: Any, sim: Any, req: Any) -> tuple[Any, list[str]]:
    t = np.asarray(sim.time, float)
    n = sim.n_joints
    rows = 3 if (sim.kind == "trajectory" or n > 1) else 2
    fig, axes = new_figure(6.8, 6.2 if rows == 3 else 4.6, rows=rows)
    ax, ax_u = axes[0], axes[-1]
    drawn = []
    task = getattr(sim, "task_space", False)
    names = sim.coordinate_names
    unit = ", ".join(dict.fromkeys(sim.coordinate_units))
    n = len(names)
    for j in range(n):
        color = _JOINT_COLORS[j % len(_JOINT_COLORS)]
        plot_decimated(ax, t, sim.desired[:, j], color=color, ls="--", lw=1.0,
                       label=f"{names[j]}D (reference)" if task else f"xD{_joint_label(design, j)} (reference)")
        plot_decimated(ax, t, sim.tracked_positions[:, j], color=color, label=names[j])
    if req is not None and t.size > 1 and n == 1 and _at_rest(t, sim.desired[:, 0]):
        drawn += _draw_envelope(ax, t, float(sim.tracked_positions[0, 0]), float(sim.desired[-1, 0]), req,
                                (sim.desired[:, 0], sim.tracked_positions[:, 0]))
    ax.set_ylabel(f"{'end effector' if task else 'position'} ({unit})")
    ax.legend(loc="best", framealpha=0.9, ncols=2 if n > 1 else 1)
    if rows == 3:
        ax_e = axes[1]
        for j in range(n):
            plot_decimated(ax_e, t, sim.tracking_errors[:, j], color=_JOINT_COLORS[j % len(_JOINT_COLORS)],
                           label=f"{names[j]} − {names[j]}D" if task else f"{names[j]} − xD")
        ax_e.axhline(0.0, color=GREY, lw=0.8)
        ax_e.set_ylabel(f"error ({unit})")
        ax_e.legend(loc="best", framealpha=0.9)
        drawn.append("the tracking error of every end-effector coordinate" if task else
                     "the tracking error of every joint")
    limit = _common_limit(req.max_control) if req is not None else None
    if limit is not None:
        _control_limit(ax_u, limit, sim.u_command, sim.u_applied)
        drawn.append("the control limit" if _limit_on_scale(limit, sim.u_command, sim.u_applied) else
                     "the control limit (off scale)")
    levels = _element_levels(ax_u, sim.settings.get("nonlinearity"), sim.u_command, sim.u_applied)
    if levels is not None:
        drawn.append(levels)
    for k in range(sim.u_applied.shape[1]):
        color = _JOINT_COLORS[k % len(_JOINT_COLORS)]
        name = sim.input_names[k]
        plot_decimated(ax_u, t, sim.u_applied[:, k], color=ORANGE if n == 1 else color, lw=1.0, alpha=0.75,
                       label=f"{name} applied")
        plot_decimated(ax_u, t, sim.u_command[:, k], color=PURPLE if n == 1 else color, lw=1.2, ls="-",
                       label=f"{name} command")
    pert = np.asarray(sim.perturbation, float)
    if pert.size and np.any(pert != 0.0):
        for k in range(pert.shape[1]):
            if np.any(pert[:, k] != 0):
                plot_decimated(ax_u, t, pert[:, k], color=RED, ls="-.", lw=1.0,
                               label=f"perturbation {sim.disturbance_names[k]}")
        drawn.append("the perturbation")
    ax_u.set_ylabel("control (N·m)")
    ax_u.set_xlabel("time (s)")
    ax_u.set_xlim(t[0], t[-1])
    ax_u.legend(loc="best", framealpha=0.9, ncols=2 if n > 1 else 1)
    return fig, drawn


def simulation_figure(result: Any) -> Figure | None:
    """The nonlinear closed-loop simulation: positions against references, errors, controls."""
    sim = result.simulation
    if sim is None:
        return None
    spec = result.loaded.spec
    drawn: list[str] = []

    def draw(design: Any, sim: Any, req: Any) -> Any:
        fig, what = _draw_simulation(design, sim, req)
        drawn.extend(what)
        return fig

    svg = render(draw, result.design, sim, spec.requirements)
    plant = result.design.plant
    what = ("the end effector's coordinates (" + ", ".join(sim.coordinate_names) + "; orientation as the rotation "
            "from the held orientation) and their references" if getattr(sim, "task_space", False)
            else "joint positions and their references")
    caption = (f"Simulation of the full nonlinear {plant.kind} plant with the spec's nonlinearity, delay, sampling, "
               f"noise and perturbation; the time-domain checks are measured on it. Top: {what} (dashed). Bottom: "
               "the control each input receives as commanded by the controller and as applied to the plant")
    caption += ("; also drawn: " + ", ".join(drawn) + ".") if drawn else "."
    return Figure("Nonlinear closed-loop simulation", caption, svg, "fig-simulation.svg")


# ----------------------------------------------------------------------------- check figures


def _draw_bode(data: Any) -> Any:
    w = np.asarray(data["frequency"], float)
    fig, (ax_m, ax_p) = new_figure(6.8, 4.6, rows=2)
    text = []
    for k, ch in enumerate(data["channels"]):
        resp, m = np.asarray(ch["response"]), ch["margins"]
        color = _JOINT_COLORS[k % len(_JOINT_COLORS)]
        phase = np.degrees(np.unwrap(np.angle(resp)))
        phase -= 360.0 * math.ceil(phase[0] / 360.0)
        ax_m.semilogx(w, 20.0 * np.log10(np.abs(resp)), color=color, label=f"L at {ch['input']}")
        ax_p.semilogx(w, phase, color=color)
        if math.isfinite(m.w_gain_crossover):
            for a in (ax_m, ax_p):
                a.axvline(m.w_gain_crossover, color=color, ls=":", lw=1.0)
            text.append(f"{ch['input']}: PM = {m.phase_margin:.1f}° at ω = {m.w_gain_crossover:.3g} rad/s")
        if math.isfinite(m.w_phase_crossover) and math.isfinite(m.gain_margin):
            text.append(f"{ch['input']}: GM = {m.gain_margin:.3g} at ω = {m.w_phase_crossover:.3g} rad/s")
    ax_m.axhline(0.0, color=GREY, lw=0.8)
    ax_p.axhline(-180.0, color=GREY, lw=0.8)
    ax_m.set_ylabel("|L(jω)| (dB)")
    ax_p.set_ylabel("∠L(jω) (deg)")
    ax_p.set_xlabel("ω (rad/s)")
    ax_p.set_xlim(w[0], w[-1])
    if len(data["channels"]) > 1:
        ax_m.legend(loc="lower left", framealpha=0.9)
    if text:
        ax_m.text(0.99, 0.96, "\n".join(text), transform=ax_m.transAxes, ha="right", va="top", fontsize=8,
                  bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": GREY, "alpha": 0.9}, zorder=5)
    return fig


def bode_figure(result: Any, check: Any) -> Figure | None:
    """Bode plots of the loop broken at each plant input (data of the ``loop_margins`` check)."""
    if not check.data.get("channels"):
        return None
    from designkit.families import family

    transfer = family(result.design.kind).display.loop_transfer
    chans = [c["input"] for c in check.data["channels"]]
    caption = ("The loop broken where the control enters the plant" + (" (each input in turn, the other loops closed)"
                                                                      if len(chans) > 1 else "")
               + ": L(s) = C (sI − A − B C)⁻¹ B from the linearized closed loop. ")
    if transfer:
        caption += f"In closed form: {transfer}. "
    caption += "Dotted lines: gain crossovers; the box gives the phase and gain margins measured there."
    return Figure("Loop Bode plot at the plant input", caption, render(_draw_bode, check.data), "fig-loop-bode.svg")


def robustness_figure(result: Any, check: Any) -> Figure | None:
    """The robust_grid check's margin over its parameter lattice (axes from the certificate)."""
    svg = robustness_svg(check.name, check.certificate)
    if svg is None:
        return None
    axes = check.certificate["grid"]["axes"]
    names = " and ".join(a["name"] for a in axes)
    caption = (f"Stability margin −max Re(pole) (1/s) of the closed loop over the lattice of {names}; "
               + ("green is stable, red unstable, and the black line is where the margin is zero."
                  if len(axes) == 2 else "above zero is stable."))
    return Figure(f"Robustness over {names}", caption, svg, f"fig-robustness-{_slug(check.name)}.svg")


def _draw_coupling(data: Any, names: Sequence[str]) -> Any:
    t = np.asarray(data["time"], float)
    coupled, decoupled = np.asarray(data["coupled"]), np.asarray(data["decoupled"])
    fig, (ax, ax_e) = new_figure(6.8, 4.6, rows=2)
    for j in range(coupled.shape[1]):
        color = _JOINT_COLORS[j % len(_JOINT_COLORS)]
        plot_decimated(ax, t, decoupled[:, j], color=color, ls="--", lw=1.0, label=f"{names[j]} own loop alone")
        plot_decimated(ax, t, coupled[:, j], color=color, label=f"{names[j]} coupled arm")
        plot_decimated(ax_e, t, coupled[:, j] - decoupled[:, j], color=color, label=f"{names[j]}")
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9, ncols=2)
    ax_e.axhline(0.0, color=GREY, lw=0.8)
    ax_e.set_ylabel("intercoupling error (rad)")
    ax_e.set_xlabel("time (s)")
    ax_e.set_xlim(t[0], t[-1])
    ax_e.legend(loc="best", framealpha=0.9)
    return fig


def coupling_figure(result: Any, check: Any) -> Figure | None:
    """Each joint on the coupled arm against its own loop on its simplified model (coupling check data)."""
    if not check.data:
        return None
    plant = result.design.plant
    names = [plant.states[i].name for i in plant.positions]
    rows = check.certificate.get("intercoupling_error", [])
    worst = max(rows, key=lambda r: r["max_abs_rad"]) if rows else None
    caption = ("Top: each joint on the full nonlinear coupled arm (solid) and as its own loop predicts on its "
               "simplified link model, alone (dashed). Bottom: their difference, the intercoupling error the "
               "per-joint PIDs leave")
    if worst is not None:
        caption += f" (largest {worst['max_abs_rad']:.3g} rad, joint {worst['joint']}, t = {worst['at_s']:.3g} s)."
    return Figure("Intercoupling between the joint loops", caption, render(_draw_coupling, check.data, names),
                  "fig-coupling.svg")


def _draw_singularity(data: Any) -> Any:
    t = np.asarray(data["time"], float)
    fig, (ax_c, ax_w) = new_figure(6.8, 4.6, rows=2)
    ax_c.semilogy(t, np.asarray(data["condition"], float), color=BLUE, label="condition number of J")
    ax_c.axhline(float(data["limit"]), color=RED, ls="--", lw=1.0, label=f"near-singular above {data['limit']:g}")
    ax_c.set_ylabel("κ(J)")
    ax_c.legend(loc="best", framealpha=0.9)
    ax_w.plot(t, np.asarray(data["manipulability"], float), color=GREEN, label="manipulability √det(J Jᵀ)")
    ax_w.set_ylabel("manipulability")
    ax_w.set_xlabel("time (s)")
    ax_w.set_xlim(t[0], t[-1])
    ax_w.legend(loc="best", framealpha=0.9)
    return fig


def singularity_figure(result: Any, check: Any) -> Figure | None:
    """Conditioning of the task Jacobian along the exact joint path (singularity check data)."""
    if not check.data:
        return None
    cert = check.certificate
    caption = (f"Conditioning of the task Jacobian J along the joint path that tracks the reference exactly "
               f"({cert['samples']} instants of inverse kinematics): its condition number (top, the limit "
               f"{cert['max_condition_allowed']:g} dashed) peaks at {cert['worst_condition']:.4g} at "
               f"t = {cert['worst_at_s']:.3g} s; manipulability (bottom) down to "
               f"{cert['smallest_manipulability']:.3g}.")
    if cert.get("damping"):
        caption += (f" Damped least squares (λ = {cert['damping']:g}) keeps the resolution bounded; the task gain "
                    f"along the weakest direction at the worst point is {cert['task_gain_at_worst']:.3g}.")
    return Figure("Distance to singular configurations along the path", caption,
                  render(_draw_singularity, check.data), "fig-singularity.svg")


def _draw_workspace(data: Any) -> Any:
    joints = [j for j in data["joints"] if math.isfinite(j["tau_stable"][1]) and j["tau_stable"][1] > 0]
    if not joints:
        return None
    fig, (ax,) = new_figure(6.8, 1.5 + 0.4 * len(joints))
    ratios = [1.0]
    for k, j in enumerate(joints):
        crit, y = j["tau_stable"][1], len(joints) - 1 - k
        lo, hi, nominal = j["tau"][0] / crit, j["tau"][1] / crit, j["tau_nominal"] / crit
        ratios += [lo, hi, nominal]
        ax.plot([lo, hi], [y, y], color=GREEN if hi < 1.0 else RED, lw=7, solid_capstyle="butt", marker="|",
                ms=14, label="τ_i over the workspace" if k == 0 else None)
        ax.plot(nominal, y, "o", color=GREY, ms=5, label="τ_i at q*" if k == 0 else None)
    ax.axvline(1.0, color=RED, ls="--", lw=1.0, label="stability limit")
    if max(ratios) / min(ratios) > 10.0:
        ax.set_xscale("log")
    ax.set_yticks(range(len(joints)), [f"joint {j['joint']}" for j in reversed(joints)])
    ax.set_ylim(-0.7, len(joints) - 0.3)
    ax.set_xlabel("τ_i / τ_crit,i  =  D_ii(q) / D_crit,i")
    fig.legend(loc="outside lower center", ncols=3, framealpha=0.9)
    return fig


def workspace_figure(result: Any, check: Any) -> Figure | None:
    """Each joint's range of tau over the workspace against its stability limit (workspace check data)."""
    if not check.data.get("joints"):
        return None
    svg = render(_draw_workspace, check.data)
    if svg is None:
        return None
    worst = check.certificate["smallest_margin"]
    at = ", ".join(f"{v:.3g}" for v in worst["configuration"])
    caption = ("Each joint's time constant τ_i = D_ii(q)/f_i over the workspace box (bar, from the smallest to the "
               "largest D_ii found; green when stable throughout, red when not) and at the design configuration "
               "(dot), divided by the largest τ_i its PID loop tolerates, τ_crit,i = K1 (1 + Km K2)/K3: the loop is "
               f"stable left of the dashed line. Smallest margin 1 − τ/τ_crit = {worst['margin']:.3g} on joint "
               f"{worst['joint']} at q = [{at}].")
    return Figure("Joint loops over the workspace", caption, svg, "fig-workspace.svg")


DESIGN_FIGURES: tuple[Callable[[Any], Figure | None], ...] = (pole_zero_figure, linear_figure, simulation_figure)
"""Figures drawn from the design and the simulation, in report order."""

CHECK_FIGURES: dict[str, Callable[[Any, Any], Figure | None]] = {
    "loop_margins": bode_figure,
    "coupling": coupling_figure,
    "workspace": workspace_figure,
    "singularity": singularity_figure,
}
"""Check name -> figure drawn from that check's certificate and data."""


def design_figures(result: Any) -> tuple[Figure, ...]:
    """Every figure of a report, in report order (figures without data are left out).

    A check gets the figure :data:`CHECK_FIGURES` names for it, or, when its certificate holds a
    parameter lattice (``"grid"``), the robustness figure.
    """
    out = [f for draw in DESIGN_FIGURES if (f := draw(result)) is not None]
    for check in result.checks:
        draw = CHECK_FIGURES.get(check.name)
        if draw is None and isinstance(check.certificate, dict | Mapping) and "grid" in check.certificate:
            draw = robustness_figure
        if draw is not None and (f := draw(result, check)) is not None:
            out.append(f)
    return tuple(out)


def _slug(text: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in text)[:60] or "check"
