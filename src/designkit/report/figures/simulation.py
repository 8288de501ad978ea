"""The nonlinear closed-loop simulation: positions against references, errors, controls, and what the
requirements and the nonlinear element draw on them (envelope, levels, perturbation)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from designkit.display.figure import (
    EVENT_STYLE,
    JOINT_COLORS,
    LIMIT_STYLE,
    REFERENCE_STYLE,
    Figure,
    joint_units,
    off_scale_entry,
    on_scale,
    plain_ticks,
)
from designkit.display.numbers import sci
from designkit.display.svg import GREEN, GREY, ORANGE, PURPLE, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.report.figures.control import common_limit, control_limit, control_linthresh, limit_on_scale, signal_peak
from designkit.report.figures.naming import joint_label, present_checks
from designkit.verification.tolerances import RISE_LIMITS, STEADY_STATE_WINDOW

__all__ = ["rise_crossings", "simulation_figure", "steady_state_interval"]


def _sentence(parts: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    parts = list(parts)
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _at_rest(t: np.ndarray, xd: np.ndarray) -> bool:
    """True when the reference is constant and non-zero over the last 20 % of the window."""
    tail = np.asarray(xd, float)[t >= t[0] + 0.8 * (t[-1] - t[0])]
    final = float(tail[-1]) if tail.size else 0.0
    return final != 0.0 and float(np.ptp(tail)) <= 1e-9 * max(1.0, abs(final))


def steady_state_interval(t: np.ndarray) -> tuple[float, float]:
    """The window ``[t0, t_end]`` (s) over which the ``steady_state_error`` check averages ``|x1 - xD|``: the
    last :data:`~designkit.verification.tolerances.STEADY_STATE_WINDOW` of the run, as in
    :mod:`designkit.verification.time_domain` (samples with ``t >= t0``).

    Examples
    --------
    >>> steady_state_interval(np.linspace(0.0, 2.0, 201))
    (1.9, 2.0)
    """
    t = np.asarray(t, dtype=float)
    duration = float(t[-1] - t[0])
    return float(t[-1] - STEADY_STATE_WINDOW * duration), float(t[-1])


def rise_crossings(t: np.ndarray, y: np.ndarray, target: float) -> tuple[float, float] | None:
    """The instants (s) the step response ``y`` from ``y[0]`` to ``target`` first crosses the rise-time levels
    (:data:`~designkit.verification.tolerances.RISE_LIMITS`, 10 % and 90 %), interpolated as the
    ``rise_time`` check does; None when a level is never reached or the step is zero."""
    from designkit.verification.time_domain import _first_crossing

    y = np.asarray(y, dtype=float)
    amp = target - float(y[0])
    if amp == 0.0 or not np.all(np.isfinite(y)):
        return None
    yn = (y - y[0]) / amp
    lo, hi = (_first_crossing(np.asarray(t, float), yn, level) for level in RISE_LIMITS)
    return None if lo is None or hi is None else (lo, hi)


def _draw_envelope(fig: Any, ax: Any, t: np.ndarray, y: np.ndarray, target: float, req: Any,
                   signals: Sequence[Any]) -> None:
    """The requirement envelope of the step response ``y`` to ``target`` (rad); a level off the scale of
    ``signals`` (:func:`on_scale`) is only named in the legend."""
    start = float(y[0])
    a = target - start
    mag = abs(a)
    t_end = float(t[-1])
    if req.overshoot is not None:
        level = target + math.copysign(mag * req.overshoot / 100.0, a)
        label = f"overshoot limit ({req.overshoot:g} %)"
        if on_scale([level], *signals):
            tag(fig, "overshoot-limit", ax.axhline(level, color=RED, **LIMIT_STYLE, label=label))
        else:
            tag(fig, "overshoot-limit-offscale", *off_scale_entry(ax, label, color=RED, **LIMIT_STYLE))
    if req.settling_time is not None and req.settling_time < t_end:
        band = req.settling_band * mag
        tag(fig, "settling-band", ax.fill_between(
            [req.settling_time, t_end], target - band, target + band, color=GREEN, alpha=0.18, lw=0,
            label=f"settling band ±{100 * req.settling_band:g} % after {req.settling_time:g} s"))
    if getattr(req, "rise_time", None) is not None:
        cross = rise_crossings(t, y, target)
        if cross is not None:
            levels = [start + f * a for f in RISE_LIMITS]
            tag(fig, "rise-time", *ax.plot(cross, levels, ls="none", marker="D", ms=5, color=PURPLE,
                                           label=f"10 %/90 % crossings: rise {cross[1] - cross[0]:.3g} s "
                                                 f"(≤ {req.rise_time:g} s)"))
    if req.steady_state_error is not None:
        e = req.steady_state_error
        t0, t1 = steady_state_interval(t)
        label = f"steady-state band ±{e:g} rad (last {100 * STEADY_STATE_WINDOW:g} %)"
        if on_scale([target - e, target + e], *signals):
            tag(fig, "steady-state-band", ax.hlines([target - e, target + e], t0, t1, colors=ORANGE, lw=1.6,
                                                    label=label))
        else:
            tag(fig, "steady-state-band-offscale", *off_scale_entry(ax, label, color=ORANGE, lw=1.6))


_ELEMENT_LEVELS = {"saturation": ("limit", "saturation ±limit"), "relay": ("amplitude", "relay ±amplitude")}


def _element_level_values(element: Any) -> list[float]:
    """The finite output levels (N·m) of a saturation or relay element (empty for other elements)."""
    if not hasattr(element, "get") or element.get("kind") not in _ELEMENT_LEVELS:
        return []
    level = element.get(_ELEMENT_LEVELS[element["kind"]][0])
    levels = [level] if isinstance(level, int | float) else list(level or [])
    return [float(lv) for lv in levels if isinstance(lv, int | float) and math.isfinite(lv)]


def _element_levels(fig: Any, ax: Any, element: Any, *signals: Any) -> None:
    """Draw the element's output levels ``±level`` (N*m, dashed); levels off the scale of the control
    ``signals`` (more than ``OFF_SCALE`` times their peak) are only named in the legend."""
    levels = _element_level_values(element)
    if not levels:
        return
    label = _ELEMENT_LEVELS[element["kind"]][1]
    shown = [lv for lv in levels if limit_on_scale(abs(lv), *signals)]
    for k, lv in enumerate(shown):
        tag(fig, "element-levels", ax.axhline(lv, color=ORANGE, **LIMIT_STYLE, zorder=1.5,
                                              label=label if k == 0 else None),
            ax.axhline(-lv, color=ORANGE, **LIMIT_STYLE, zorder=1.5))
    if len(shown) < len(levels):
        off = ", ".join(f"{lv:g}" for lv in levels if lv not in shown)
        tag(fig, "element-levels-offscale", *off_scale_entry(ax, f"{label} = {off} N·m", color=ORANGE, **LIMIT_STYLE))


def _onset(t: np.ndarray, pert: np.ndarray) -> float | None:
    """First instant (s) a perturbation is non-zero, None when it never is."""
    pert = np.asarray(pert, float).reshape(len(t), -1) if np.size(pert) else np.zeros((len(t), 0))
    idx = np.flatnonzero(np.any(pert != 0.0, axis=1))
    return float(t[idx[0]]) if idx.size else None


def _error_bands(fig: Any, ax: Any, t: np.ndarray, err: np.ndarray, req: Any, info: dict[str, Any]) -> None:
    """The error requirements on the error panel, and a zoom that shows them: the ``tracking_error`` band over the
    run, the ``steady_state_error`` band over the steady-state window; the axis spans the bands and the error over
    the window they judge (an early transient many times larger is clipped, and the caption says so)."""
    if req is None:
        return
    spans = []
    if req.tracking_error is not None:
        e = float(req.tracking_error)
        tag(fig, "tracking-band", ax.axhline(e, color=RED, **LIMIT_STYLE, label=f"tracking requirement ±{e:g}"),
            ax.axhline(-e, color=RED, **LIMIT_STYLE))
        spans.append(max(e, float(np.nanmax(np.abs(err))) if np.isfinite(err).any() else e))
        info["tracking_band"] = e
    if req.steady_state_error is not None and t.size > 1:
        e = float(req.steady_state_error)
        t0, t1 = steady_state_interval(t)
        tag(fig, "error-steady-band", ax.fill_between([t0, t1], -e, e, color=ORANGE, alpha=0.25, lw=0,
                                                      label=f"steady-state requirement ±{e:g}"))
        window = (t >= t0) & (t <= t1)
        late = float(np.nanmax(np.abs(err[window]))) if np.isfinite(err[window]).any() else e
        spans.append(max(e, late))
        info["steady_band"] = e
    finite = err[np.isfinite(err)]
    if spans and finite.size:
        span = 1.3 * max(spans)
        if float(np.max(np.abs(finite))) > span:
            ax.set_ylim(-span, span)
            info["zoomed"] = span


def _draw_simulation(design: Any, sim: Any, req: Any, torque_limits: Sequence[float] | None = None
                     ) -> tuple[Any, dict[str, Any]]:
    t = np.asarray(sim.time, float)
    n = sim.n_joints
    steady_req = req is not None and req.steady_state_error is not None
    rows = 3 if (sim.kind == "trajectory" or n > 1 or steady_req) else 2
    fig, axes = new_figure(6.8, 6.2 if rows == 3 else 4.6, rows=rows)
    ax, ax_u = axes[0], axes[-1]
    info: dict[str, Any] = {}
    task = getattr(sim, "task_space", False)
    names = sim.coordinate_names
    unit = ", ".join(dict.fromkeys(sim.coordinate_units)) if task else joint_units(design.plant, "positions")
    n = len(names)
    for j in range(n):
        color = JOINT_COLORS[j % len(JOINT_COLORS)]
        if n > 2:  # one legend entry for all references: a long legend hides the lines
            ref_label = "references (dash-dot, each joint's colour)" if j == 0 else None
        else:
            ref_label = f"{names[j]}D (reference)" if task else f"xD{joint_label(design, j)} (reference)"
        tag(fig, "reference", *plot_decimated(ax, t, sim.desired[:, j], color=color, **REFERENCE_STYLE,
                                              label=ref_label))
        tag(fig, "position", *plot_decimated(ax, t, sim.tracked_positions[:, j], color=color, label=names[j]))
    if req is not None and t.size > 1 and n == 1 and _at_rest(t, sim.desired[:, 0]):
        _draw_envelope(fig, ax, t, sim.tracked_positions[:, 0], float(sim.desired[-1, 0]), req,
                       (sim.desired[:, 0], sim.tracked_positions[:, 0]))
    ax.set_ylabel(f"{'end effector' if task else 'position'} ({unit})")
    ax.legend(loc="best", framealpha=0.9, ncols=2 if n > 1 else 1)
    if rows == 3:
        ax_e = axes[1]
        for j in range(n):
            tag(fig, "tracking-error", *plot_decimated(
                ax_e, t, sim.tracking_errors[:, j], color=JOINT_COLORS[j % len(JOINT_COLORS)],
                label=f"{names[j]} − {names[j]}D" if task else f"{names[j]} − xD{joint_label(design, j)}"))
        ax_e.axhline(0.0, color=GREY, lw=0.8)
        _error_bands(fig, ax_e, t, np.asarray(sim.tracking_errors, float), req, info)
        ax_e.set_ylabel(f"error ({unit})")
        ax_e.legend(loc="best", framealpha=0.9, ncols=2 if n > 2 else 1)
        info["task"] = task
    limit = common_limit(req.max_control) if req is not None else None
    element = sim.settings.get("nonlinearity")
    if limit is not None:
        control_limit(fig, ax_u, limit, sim.u_command, sim.u_applied)
        info["limit"] = limit
    _element_levels(fig, ax_u, element, sim.u_command, sim.u_applied)
    if _element_level_values(element):
        info["element"] = str(element["kind"])
    same = np.array_equal(np.asarray(sim.u_applied), np.asarray(sim.u_command))  # no element between them
    for k in range(sim.u_applied.shape[1]):
        color = JOINT_COLORS[k % len(JOINT_COLORS)]
        name = sim.input_names[k]
        if same:  # one line per input: the legend stays short enough to read
            tag(fig, "u-command", *plot_decimated(ax_u, t, sim.u_command[:, k], color=PURPLE if n == 1 else color,
                                                  lw=1.2, ls="-", label=name))
            continue
        tag(fig, "u-applied", *plot_decimated(ax_u, t, sim.u_applied[:, k], color=ORANGE if n == 1 else color,
                                              lw=1.3, alpha=0.8, zorder=2.5, label=f"{name} applied"))
        tag(fig, "u-command", *plot_decimated(ax_u, t, sim.u_command[:, k], color=PURPLE if n == 1 else color,
                                              lw=1.2, ls="-", label=f"{name} command"))
    if torque_limits is not None:
        for k, lim in enumerate(torque_limits):
            color = ORANGE if n == 1 else JOINT_COLORS[k % len(JOINT_COLORS)]
            tag(fig, "torque-limits", ax_u.axhline(lim, color=color, ls=":", lw=1.0,
                                                   label="actuator torque limits" if k == 0 else None),
                ax_u.axhline(-lim, color=color, ls=":", lw=1.0))
        levels_extra = [float(v) for v in torque_limits]
    else:
        levels_extra = []
    pert = np.asarray(sim.perturbation, float)
    onset = _onset(t, pert)
    if onset is not None:
        pert = pert.reshape(len(t), -1)
        for k in range(pert.shape[1]):
            if np.any(pert[:, k] != 0):
                tag(fig, "perturbation", *plot_decimated(ax_u, t, pert[:, k], color=RED, ls="-", lw=0.9,
                                                         label=f"perturbation {sim.disturbance_names[k]}"))
        if onset > t[0]:
            for a in axes:
                tag(fig, "perturbation-onset", a.axvline(onset, color=RED, **EVENT_STYLE))
            info["onset"] = onset
    levels = [lv for lv in [limit, *_element_level_values(element), *levels_extra] if lv is not None]
    linthresh = control_linthresh(levels, sim.u_command, sim.u_applied)
    if linthresh is not None:
        ax_u.set_yscale("symlog", linthresh=linthresh, linscale=1.0)
        plain_ticks(ax_u.yaxis)
        info.update(linthresh=linthresh, peak=signal_peak(sim.u_command), levels=sorted({abs(lv) for lv in levels}))
    ax_u.set_ylabel(f"control ({joint_units(design.plant, 'inputs')})")
    ax_u.set_xlabel("time (s)")
    ax_u.set_xlim(t[0], t[-1])
    ax_u.legend(loc="best", framealpha=0.9, ncols=2 if n > 1 else 1)
    return fig, info


def _conditions(settings: Mapping[str, Any]) -> list[str]:
    """The simulation conditions that depart from the ideal loop, from the run's settings (present ones only)."""
    out = []
    element = settings.get("nonlinearity")
    if hasattr(element, "get") and element.get("kind") not in (None, "none"):
        out.append(f"a {str(element['kind']).replace('_', ' ')} at the plant input")
    if float(settings.get("delay") or 0.0) > 0.0:
        out.append(f"a {float(settings['delay']):g} s delay")
    if float(settings.get("sampling_period") or 0.0) > 0.0:
        out.append(f"a controller sampled every {float(settings['sampling_period']):g} s")
    noise = settings.get("noise")
    if hasattr(noise, "get") and float(noise.get("std") or 0.0) > 0.0:
        out.append(f"measurement noise (σ = {float(noise['std']):g} rad)")
    controller = settings.get("controller")
    aw = controller.get("anti_windup") if hasattr(controller, "get") else None
    if hasattr(aw, "get") and aw.get("kind") not in (None, "none"):
        out.append(f"anti-windup ({str(aw['kind']).replace('_', ' ')})")
    return out


_SIM_PHRASES = {
    "overshoot-limit": "the overshoot limit (dashed)",
    "overshoot-limit-offscale": "the overshoot limit (off scale, in the legend only)",
    "settling-band": "the settling band (green) from the required settling time on",
    "rise-time": "the 10 % and 90 % crossings the rise time is measured between (◆)",
    "steady-state-band": "the steady-state band over the last {window:g} % of the run, the window the "
                         "steady-state error is averaged over",
    "steady-state-band-offscale": "the steady-state band (off scale, in the legend only)",
    "control-limit": "the control limit |u| ≤ {limit:g} N·m (dashed)",
    "control-limit-offscale": "the control limit |u| ≤ {limit:g} N·m (off scale, in the legend only)",
    "element-levels": "the {element}'s output levels (dashed, orange)",
    "element-levels-offscale": "the {element}'s output levels (off scale, in the legend only)",
    "perturbation": "the perturbation torque (red)",
    "tracking-band": "the tracking-error requirement ±{tracking_band:g} on the error panel (dashed)",
    "error-steady-band": "the steady-state requirement ±{steady_band:g} on the error panel over the window it is "
                         "judged on (orange)",
    "torque-limits": "the actuator torque limits of the plant (dotted)",
    "perturbation-onset": "its onset at t = {onset:.3g} s (dotted vertical line)",
}
"""Caption phrase of each optional key a simulation figure may draw (formatted with the drawing's info)."""


def _simulation_caption(keys: Sequence[str], info: Mapping[str, Any], plant_kind: str, what: str,
                        conditions: Sequence[str], checked: bool) -> str:
    text = f"Simulation of the full nonlinear {plant_kind} plant"
    text += (" with " + _sentence(conditions) + "." if conditions else
             " (no saturation, delay, sampling, noise or other element in the spec).")
    if checked:
        text += " The time-domain checks are measured on it."
    text += f" Top: {what}" + (" (solid) and their references (dash-dot)." if "reference" in keys else ".")
    if "tracking-error" in keys:
        text += (" Middle: the tracking error, position minus reference, of every "
                 + ("end-effector coordinate." if info.get("task") else "joint."))
    if "tracking-error" in keys and "zoomed" in info:
        text += (f" The error axis is zoomed to ±{info['zoomed']:.3g} so that the requirement is visible; the larger "
                 "early transient runs off it.")
    if "u-applied" in keys:
        text += " Bottom: the control as commanded by the controller and as applied to the plant."
    elif "u-command" in keys:
        text += " Bottom: the control, commanded and applied alike (no element between them)."
    fmt = {"window": 100 * STEADY_STATE_WINDOW, **info}
    also = [_SIM_PHRASES[k].format(**fmt) for k in keys if k in _SIM_PHRASES]
    if also:
        text += " Also drawn: " + _sentence(also) + "."
    if "linthresh" in info:
        lv = ", ".join(f"±{v:g}" for v in info["levels"])
        text += (f" The control axis is symmetric-logarithmic: linear within ±{info['linthresh']:g} N·m, where the "
                 f"{lv} N·m levels lie, and logarithmic beyond, so that they stay visible next to the peak command "
                 f"of {sci(info['peak'])} N·m.")
    return text


_SIM_EVIDENCE = ("overshoot", "settling_time", "rise_time", "steady_state_error", "tracking_error", "max_control")
"""Checks measured on the nonlinear simulation (the simulation figure is their evidence)."""


def simulation_figure(result: Any) -> Figure | None:
    """The nonlinear closed-loop simulation: positions against references, errors, controls."""
    sim = result.simulation
    if sim is None:
        return None
    plant_spec = result.loaded.spec.plant
    limits = getattr(getattr(plant_spec, "limits", None), "torque", None)
    torque = None
    if limits is not None:
        width = sim.u_command.shape[1]
        torque = [float(v) for v in np.broadcast_to(np.atleast_1d(np.asarray(limits, float)), (width,))]
    svg, keys, info = render_tagged(_draw_simulation, result.design, sim, result.loaded.spec.requirements, torque)
    what = ("the end effector's coordinates (" + ", ".join(sim.coordinate_names) + "; orientation as the rotation "
            "from the held orientation)" if getattr(sim, "task_space", False) else "joint positions")
    evidence = present_checks(result, _SIM_EVIDENCE)
    caption = _simulation_caption(keys, info, result.design.plant.kind, what, _conditions(sim.settings),
                                  bool(evidence))
    return Figure("Nonlinear closed-loop simulation", caption, svg, "fig-simulation.svg", evidence)
