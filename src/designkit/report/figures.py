"""Report figures as deterministic SVG text (matplotlib, imported lazily).

Figures come from two tables, so a new family or check adds its figure without touching the
others:

* :data:`DESIGN_FIGURES` -- drawn from the design and the simulation (pole-zero map, ideal
  linear response, nonlinear simulation per joint);
* :data:`CHECK_FIGURES` -- keyed by check name, drawn from that check's certificate and data
  (the loop margins' Bode plots, the robustness lattice, the intercoupling), and
  :data:`EXTRA_CHECK_FIGURES` -- further figures of a check (the loop margins' sensitivity |S| and
  complementary sensitivity |T| with the peak Ms).

Captions are written from what is drawn: every artist a caption may name is tagged with a key
(:func:`~designkit.report.svg.tag`, written as the SVG id ``dk-<key>``), and the caption is built from
the keys of the artists actually drawn (plus what the drawing measured, e.g. a symmetric-log control
axis), so no envelope, limit or marker is named when it is absent.  Line styles are distinct:
references dash-dot, limits dashed, events (a perturbation's onset, crossovers) dotted verticals.
Every :class:`Figure` names the checks it is evidence for (``evidence``), and the windows and levels
drawn are the checks' own (the steady-state window is the last
:data:`~designkit.verification.tolerances.STEADY_STATE_WINDOW` of the run, the rise-time markers the
:data:`~designkit.verification.tolerances.RISE_LIMITS` crossings).

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
    EVENT_STYLE,
    GREEN,
    GREY,
    LIMIT_STYLE,
    MAX_DRAWN,
    ORANGE,
    PURPLE,
    RED,
    REFERENCE_STYLE,
    drawable,
    new_figure,
    plot_decimated,
    render,
    render_tagged,
    svg_keys,
    tag,
)
from designkit.verification.loop import achieved_zeros
from designkit.verification.tolerances import RISE_LIMITS, STEADY_STATE_WINDOW

__all__ = ["CHECK_FIGURES", "DESIGN_FIGURES", "EXTRA_CHECK_FIGURES", "Figure", "design_figures"]

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


def _off_scale(ax: Any, label: str, **style: Any) -> list[Any]:
    """A legend entry for a level that is not drawn (returns the empty line carrying it)."""
    return ax.plot([], [], label=f"{label} (off scale)", **style)


@dataclass(frozen=True)
class Figure:
    """One report figure.

    Parameters
    ----------
    title : str
        Short title shown above the figure.
    caption : str
        What the figure shows and how to read it, written from what is drawn (the keys of the tagged
        artists, :func:`designkit.report.svg.tag`): nothing absent from the drawing is named.
    svg : str
        A standalone SVG document (text as ``<text>`` in DejaVu Sans).
    filename : str
        File name used when the figure is written next to the Typst source (``*.svg``).  Unique among
        a report's figures: it also names the figure's HTML anchor, :attr:`anchor`.
    evidence : tuple of str
        Names of the checks whose evidence the figure shows (e.g. the simulation figure for
        ``overshoot``, ``settling_time``, ...; the Bode and sensitivity figures for ``loop_margins``),
        only checks present in the run.  A report links each requirement to the first figure whose
        ``evidence`` names its check.
    """

    title: str
    caption: str
    svg: str
    filename: str
    evidence: tuple[str, ...] = ()

    @property
    def anchor(self) -> str:
        """The figure's HTML anchor id: its file name's stem, ``fig-`` prefixed when it is not already
        (``fig-simulation.svg`` -> ``fig-simulation``)."""
        stem = self.filename.rsplit(".", 1)[0]
        return stem if stem.startswith("fig-") else "fig-" + stem


def _joint_label(design: Any, j: int) -> str:
    return "" if len(design.plant.positions) == 1 else f" (joint {j + 1})"


def _pos_name(design: Any, j: int) -> str:
    return design.plant.states[design.plant.positions[j]].name


def _present(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    """The names among ``names`` of checks the run has, in ``names`` order."""
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def sci(x: float, digits: int = 3) -> str:
    """``x`` to ``digits`` significant figures, large or small magnitudes as ``m × 10ⁿ`` (never ``1e+04``).

    Examples
    --------
    >>> sci(13390.2), sci(0.5), sci(2.5e-7), sci(-1e300)
    ('1.34 × 10⁴', '0.5', '2.5 × 10⁻⁷', '−1 × 10³⁰⁰')
    """
    text = f"{x:.{digits}g}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa} × 10{str(int(exponent)).translate(_SUPERSCRIPT)}"
    return text.replace("-", "−", 1) if text.startswith("-") else text


def _sentence(parts: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    parts = list(parts)
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


# ----------------------------------------------------------------------------- pole-zero map


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
                  _present(result, ("pole_placement", "error_poles")))


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
    n = positions.shape[1]
    for j in range(n):
        color = _JOINT_COLORS[j % len(_JOINT_COLORS)]
        tag(fig, "reference", *ax.plot(t, drawable(ref[:, j, 0]), color=color, **REFERENCE_STYLE,
                                       label=f"xD{_joint_label(design, j)} (reference)"))
        tag(fig, "position", *ax.plot(t, drawable(positions[:, j]), color=color,
                                      label=f"{_pos_name(design, j)} (linear, nominal)"))
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9)
    for k in range(u.shape[1]):
        tag(fig, "control", *ax_u.plot(t, drawable(u[:, k]), color=_JOINT_COLORS[k % len(_JOINT_COLORS)],
                                       label=design.plant.inputs[k].name))
    info = {}
    if limit is not None:
        _control_limit(fig, ax_u, limit, u)
        info["limit"] = limit
    ax_u.set_xlabel("time (s)")
    ax_u.set_ylabel("control (N·m)")
    ax_u.legend(loc="best", framealpha=0.9)
    ax_u.set_xlim(t[0], t[-1])
    return fig, info


def _linear_caption(keys: Sequence[str], word: str, info: Mapping[str, Any]) -> str:
    text = "The nominal closed loop linearized at its operating point"
    if "reference" in keys:
        text += f", driven by the {word} reference (dash-dot)"
    text += ", without saturation, delay, noise or perturbation: the response the design predicts."
    if "control" in keys:
        text += " Bottom: the control it needs"
        if "control-limit" in keys:
            text += f", with the limit |u| ≤ {info['limit']:g} N·m (dashed)."
        elif "control-limit-offscale" in keys:
            text += f" (the limit |u| ≤ {info['limit']:g} N·m is off scale, named in the legend only)."
        else:
            text += "."
    return text


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
    word = "trajectory" if kind == "trajectory" else "step"
    svg, keys, info = render_tagged(_draw_linear, design, t, ref, positions, u, limit)
    return Figure(f"Ideal linear {word} response", _linear_caption(keys, word, info), svg,
                  "fig-linear-response.svg")


def _common_limit(limit: Any) -> float | None:
    """One control limit to draw: the limit itself, or the common value of per-input limits (None when they
    differ -- they are then only in the max_control check)."""
    if limit is None:
        return None
    arr = np.atleast_1d(np.asarray(limit, dtype=float))
    return float(arr[0]) if np.all(arr == arr[0]) else None


def _limit_on_scale(limit: float, *signals: Any) -> bool:
    """A symmetric limit ``|u| <= limit`` is drawn when it is at most ``OFF_SCALE`` times the signals' peak."""
    peak = _peak(*signals)
    return bool(peak > 0.0 and limit <= OFF_SCALE * peak)


def _peak(*signals: Any) -> float:
    """Largest drawable magnitude of the ``signals`` (0 without a finite sample)."""
    values = np.concatenate([np.ravel(drawable(s)) for s in signals])
    values = values[np.isfinite(values)]
    return float(np.max(np.abs(values))) if values.size else 0.0


def _control_limit(fig: Any, ax: Any, limit: float, *signals: Any) -> None:
    """Draw ``|u| <= limit`` (dashed); a limit far beyond the signals (more than ``OFF_SCALE`` times their peak)
    is named in the legend only."""
    label = f"|u| ≤ {limit:g} N·m"
    if _limit_on_scale(limit, *signals):
        tag(fig, "control-limit", ax.axhline(limit, color=RED, **LIMIT_STYLE, zorder=1.5, label=label),
            ax.axhline(-limit, color=RED, **LIMIT_STYLE, zorder=1.5))
    else:
        tag(fig, "control-limit-offscale", *_off_scale(ax, label, color=RED, **LIMIT_STYLE))


SYMLOG_RATIO = 20.0
"""The control axis becomes symmetric-logarithmic when the peak |u| exceeds this many times the smallest
level drawn on it (a limit would otherwise be a hairline on the zero line)."""


def control_linthresh(levels: Sequence[float], *signals: Any) -> float | None:
    """The linear range ``±linthresh`` (N·m) of a symmetric-log control axis, or None for a linear axis.

    A symlog axis is used when the signals' peak |u| exceeds :data:`SYMLOG_RATIO` times the smallest
    positive finite level: the range is then twice that level, so the levels sit in the linear part.

    Examples
    --------
    >>> control_linthresh([5.0], [0.0, 1.3e4]), control_linthresh([5.0], [0.0, 30.0]), control_linthresh([], [1e4])
    (10.0, None, None)
    """
    lv = [abs(float(x)) for x in levels if math.isfinite(x) and x != 0.0]
    if not lv:
        return None
    smallest = min(lv)
    return 2.0 * smallest if _peak(*signals) > SYMLOG_RATIO * smallest else None


# ----------------------------------------------------------------------------- nonlinear simulation


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
            tag(fig, "overshoot-limit-offscale", *_off_scale(ax, label, color=RED, **LIMIT_STYLE))
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
            tag(fig, "steady-state-band-offscale", *_off_scale(ax, label, color=ORANGE, lw=1.6))


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
    shown = [lv for lv in levels if _limit_on_scale(abs(lv), *signals)]
    for k, lv in enumerate(shown):
        tag(fig, "element-levels", ax.axhline(lv, color=ORANGE, **LIMIT_STYLE, zorder=1.5,
                                              label=label if k == 0 else None),
            ax.axhline(-lv, color=ORANGE, **LIMIT_STYLE, zorder=1.5))
    if len(shown) < len(levels):
        off = ", ".join(f"{lv:g}" for lv in levels if lv not in shown)
        tag(fig, "element-levels-offscale", *_off_scale(ax, f"{label} = {off} N·m", color=ORANGE, **LIMIT_STYLE))


def _onset(t: np.ndarray, pert: np.ndarray) -> float | None:
    """First instant (s) a perturbation is non-zero, None when it never is."""
    pert = np.asarray(pert, float).reshape(len(t), -1) if np.size(pert) else np.zeros((len(t), 0))
    idx = np.flatnonzero(np.any(pert != 0.0, axis=1))
    return float(t[idx[0]]) if idx.size else None


def _draw_simulation(design: Any, sim: Any, req: Any) -> tuple[Any, dict[str, Any]]:
    t = np.asarray(sim.time, float)
    n = sim.n_joints
    rows = 3 if (sim.kind == "trajectory" or n > 1) else 2
    fig, axes = new_figure(6.8, 6.2 if rows == 3 else 4.6, rows=rows)
    ax, ax_u = axes[0], axes[-1]
    info: dict[str, Any] = {}
    task = getattr(sim, "task_space", False)
    names = sim.coordinate_names
    unit = ", ".join(dict.fromkeys(sim.coordinate_units))
    n = len(names)
    for j in range(n):
        color = _JOINT_COLORS[j % len(_JOINT_COLORS)]
        tag(fig, "reference", *plot_decimated(
            ax, t, sim.desired[:, j], color=color, **REFERENCE_STYLE,
            label=f"{names[j]}D (reference)" if task else f"xD{_joint_label(design, j)} (reference)"))
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
                ax_e, t, sim.tracking_errors[:, j], color=_JOINT_COLORS[j % len(_JOINT_COLORS)],
                label=f"{names[j]} − {names[j]}D" if task else f"{names[j]} − xD{_joint_label(design, j)}"))
        ax_e.axhline(0.0, color=GREY, lw=0.8)
        ax_e.set_ylabel(f"error ({unit})")
        ax_e.legend(loc="best", framealpha=0.9)
        info["task"] = task
    limit = _common_limit(req.max_control) if req is not None else None
    element = sim.settings.get("nonlinearity")
    if limit is not None:
        _control_limit(fig, ax_u, limit, sim.u_command, sim.u_applied)
        info["limit"] = limit
    _element_levels(fig, ax_u, element, sim.u_command, sim.u_applied)
    if _element_level_values(element):
        info["element"] = str(element["kind"])
    for k in range(sim.u_applied.shape[1]):
        color = _JOINT_COLORS[k % len(_JOINT_COLORS)]
        name = sim.input_names[k]
        tag(fig, "u-applied", *plot_decimated(ax_u, t, sim.u_applied[:, k], color=ORANGE if n == 1 else color,
                                              lw=1.3, alpha=0.8, zorder=2.5, label=f"{name} applied"))
        tag(fig, "u-command", *plot_decimated(ax_u, t, sim.u_command[:, k], color=PURPLE if n == 1 else color,
                                              lw=1.2, ls="-", label=f"{name} command"))
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
    levels = [lv for lv in [limit, *_element_level_values(element)] if lv is not None]
    linthresh = control_linthresh(levels, sim.u_command, sim.u_applied)
    if linthresh is not None:
        ax_u.set_yscale("symlog", linthresh=linthresh, linscale=1.0)
        plain_ticks(ax_u.yaxis)
        info.update(linthresh=linthresh, peak=_peak(sim.u_command), levels=sorted({abs(lv) for lv in levels}))
    ax_u.set_ylabel("control (N·m)")
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
    if "u-command" in keys:
        text += " Bottom: the control as commanded by the controller and as applied to the plant."
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
    svg, keys, info = render_tagged(_draw_simulation, result.design, sim, result.loaded.spec.requirements)
    what = ("the end effector's coordinates (" + ", ".join(sim.coordinate_names) + "; orientation as the rotation "
            "from the held orientation)" if getattr(sim, "task_space", False) else "joint positions")
    evidence = _present(result, _SIM_EVIDENCE)
    caption = _simulation_caption(keys, info, result.design.plant.kind, what, _conditions(sim.settings),
                                  bool(evidence))
    return Figure("Nonlinear closed-loop simulation", caption, svg, "fig-simulation.svg", evidence)


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
        tag(fig, "loop-gain", *ax_m.semilogx(w, 20.0 * np.log10(np.abs(resp)), color=color,
                                             label=f"L at {ch['input']}"))
        tag(fig, "loop-phase", *ax_p.semilogx(w, phase, color=color))
        if math.isfinite(m.w_gain_crossover):
            for a in (ax_m, ax_p):
                tag(fig, "gain-crossover", a.axvline(m.w_gain_crossover, color=color, **EVENT_STYLE))
            text.append(f"{ch['input']}: PM = {m.phase_margin:.1f}° at ω = {sci(m.w_gain_crossover)} rad/s")
        if math.isfinite(m.w_phase_crossover) and math.isfinite(m.gain_margin):
            text.append(f"{ch['input']}: GM = {m.gain_margin:.3g} at ω = {sci(m.w_phase_crossover)} rad/s")
    ax_m.axhline(0.0, color=GREY, lw=0.8)
    ax_p.axhline(-180.0, color=GREY, lw=0.8)
    ax_m.set_ylabel("|L(jω)| (dB)")
    ax_p.set_ylabel("∠L(jω) (deg)")
    ax_p.set_xlabel("ω (rad/s)")
    ax_p.set_xlim(w[0], w[-1])
    _few_log_ticks(ax_p)
    if len(data["channels"]) > 1:
        ax_m.legend(loc="lower left", framealpha=0.9)
    if text:
        tag(fig, "margin-box", ax_m.text(0.99, 0.96, "\n".join(text), transform=ax_m.transAxes, ha="right", va="top",
                                         fontsize=8, zorder=5,
                                         bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": GREY, "alpha": 0.9}))
    return fig


def _few_log_ticks(ax: Any) -> None:
    """Minor ticks of a log x axis at 2 and 5 times each decade only (readable, and fewer tick artists to lay
    out), and plain tick labels (:func:`plain_ticks`)."""
    from matplotlib.ticker import LogLocator, NullFormatter

    ax.xaxis.set_minor_locator(LogLocator(base=10.0, subs=(2.0, 5.0)))
    ax.xaxis.set_minor_formatter(NullFormatter())
    plain_ticks(ax.xaxis)


def plain_ticks(axis: Any) -> None:
    """Label a log or symlog ``axis`` with plain numbers (``0.1``, ``100``, ``1e+04``) instead of matplotlib's
    mathtext powers of ten: the labels stay searchable text, and parsing mathtext is the costliest step of
    drawing a log axis."""
    from matplotlib.ticker import FuncFormatter

    axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}".replace("-", "−")))


def _loop_caption(keys: Sequence[str], n_channels: int, transfer: str) -> str:
    caption = ("The loop broken where the control enters the plant" + (" (each input in turn, the other loops closed)"
                                                                      if n_channels > 1 else "")
               + ": L(s) = C (sI − A − B C)⁻¹ B from the linearized closed loop, closed by negative feedback "
               "(the closed loop is A = A_i − B_i C_i). ")
    if transfer:
        caption += f"In closed form: {transfer}. "
    if "gain-crossover" in keys:
        caption += "Dotted vertical lines: gain crossovers. "
    if "margin-box" in keys:
        caption += "The box gives the phase and gain margins measured there."
    return caption.rstrip()


def bode_figure(result: Any, check: Any) -> Figure | None:
    """Bode plots of the loop broken at each plant input (data of the ``loop_margins`` check)."""
    if not check.data.get("channels"):
        return None
    from designkit.families import family

    transfer = family(result.design.kind).display.loop_transfer
    svg, keys, _ = render_tagged(_draw_bode, check.data)
    return Figure("Loop Bode plot at the plant input", _loop_caption(keys, len(check.data["channels"]), transfer),
                  svg, "fig-loop-bode.svg", (check.name,))


def sensitivities(response: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sensitivity ``S = 1/(1 + L)`` and complementary sensitivity ``T = L/(1 + L)`` from the loop's frequency
    response ``L(jw)`` (negative feedback, the sign convention of :mod:`designkit.verification.loop`).

    Examples
    --------
    >>> S, T = sensitivities(np.array([1.0 + 0j, -0.5 + 0j]))
    >>> S.tolist(), T.tolist()
    ([(0.5+0j), (2+0j)], [(0.5+0j), (-1+0j)])
    """
    L = np.asarray(response, dtype=complex)
    S = 1.0 / (1.0 + L)
    return S, L * S


def sensitivity_peaks(data: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Per channel of the ``loop_margins`` data: the peaks ``Ms = sup |S|`` and ``Mt = max |T|`` (dimensionless)
    and where they occur (rad/s).

    ``L`` is strictly proper, so ``S -> 1`` as ``w -> inf``: when ``|S| < 1`` over the whole grid, ``Ms = 1`` is
    approached there and ``w_Ms`` is ``inf`` (then ``1/Ms`` equals the check's modulus margin, which is
    clamped to 1 the same way).  ``Mt`` is the largest ``|T|`` on the grid.
    """
    w = np.asarray(data["frequency"], float)
    out = []
    for ch in data["channels"]:
        S, T = sensitivities(np.asarray(ch["response"]))
        i, k = int(np.argmax(np.abs(S))), int(np.argmax(np.abs(T)))
        ms, w_ms = (float(np.abs(S[i])), float(w[i])) if np.abs(S[i]) > 1.0 else (1.0, math.inf)
        out.append({"input": ch["input"], "Ms": ms, "w_Ms": w_ms, "Mt": float(np.abs(T[k])), "w_Mt": float(w[k])})
    return out


def _db(x: Any) -> float | np.ndarray:
    return 20.0 * np.log10(np.maximum(np.abs(x), 1e-300))


def _draw_sensitivity(data: Any) -> Any:
    w = np.asarray(data["frequency"], float)
    fig, (ax_s, ax_t) = new_figure(6.8, 4.6, rows=2)
    several = len(data["channels"]) > 1
    for k, (ch, pk) in enumerate(zip(data["channels"], sensitivity_peaks(data), strict=True)):
        color = _JOINT_COLORS[k % len(_JOINT_COLORS)]
        S, T = sensitivities(np.asarray(ch["response"]))
        suffix = f" at {ch['input']}" if several else ""
        tag(fig, "sensitivity", *ax_s.semilogx(w, _db(S), color=color, label=f"|S|{suffix}"))
        tag(fig, "complementary-sensitivity", *ax_t.semilogx(w, _db(T), color=color, label=f"|T|{suffix}"))
        if math.isfinite(pk["w_Ms"]):
            tag(fig, "ms-peak", *ax_s.plot([pk["w_Ms"]], [_db(pk["Ms"])], "o", color=color, mfc="none", mew=1.6,
                                           ms=7, label=f"Ms = {pk['Ms']:.3g} at {sci(pk['w_Ms'])} rad/s"))
        tag(fig, "mt-peak", *ax_t.plot([pk["w_Mt"]], [_db(pk["Mt"])], "o", color=color, mfc="none", mew=1.6, ms=7,
                                       label=f"Mt = {pk['Mt']:.3g} at {sci(pk['w_Mt'])} rad/s"))
    for a in (ax_s, ax_t):
        a.axhline(0.0, color=GREY, lw=0.8)
        a.legend(loc="best", framealpha=0.9)
    ax_s.set_ylabel("|S(jω)| (dB)")
    ax_t.set_ylabel("|T(jω)| (dB)")
    ax_t.set_xlabel("ω (rad/s)")
    ax_t.set_xlim(w[0], w[-1])
    _few_log_ticks(ax_t)
    return fig


def _sensitivity_caption(keys: Sequence[str], peaks: Sequence[Mapping[str, Any]]) -> str:
    several = len(peaks) > 1
    text = ("Sensitivity S = 1/(1 + L) (top) and complementary sensitivity T = L/(1 + L) (bottom), in dB, of the "
            "loop of the Bode plot broken at the plant input" + ("s" if several else "") + ".")
    ms = []
    for p in peaks:
        who = f"{p['input']}: " if several else ""
        if math.isfinite(p["w_Ms"]):
            ms.append(f"{who}Ms = {p['Ms']:.3g} ({_db(p['Ms']):.2g} dB) at ω = {sci(p['w_Ms'])} rad/s, so the Nyquist "
                      f"curve comes within 1/Ms = {1.0 / p['Ms']:.3g} of −1")
        else:
            ms.append(f"{who}|S| < 1 at every frequency of the grid, so Ms = 1, approached as ω → ∞, and the Nyquist "
                      "curve stays at least 1 from −1")
    text += " " + "; ".join(ms) + ("" if "ms-peak" not in keys else " (○ marks the peak)") + "."
    if "mt-peak" in keys:
        text += " " + "; ".join(f"{p['input'] + ': ' if several else ''}Mt = {p['Mt']:.3g} at ω = {sci(p['w_Mt'])} "
                                "rad/s" for p in peaks) + " (○)."
    return text + " |S| above 0 dB amplifies output disturbances at those frequencies; |T| is the response to " \
                  "measurement noise and to the reference."


def sensitivity_figure(result: Any, check: Any) -> Figure | None:
    """|S| and |T| of the loop broken at each plant input, peaks marked (data of the ``loop_margins`` check)."""
    if not check.data.get("channels"):
        return None
    svg, keys, _ = render_tagged(_draw_sensitivity, check.data)
    caption = _sensitivity_caption(keys, sensitivity_peaks(check.data))
    return Figure("Sensitivity and complementary sensitivity", caption, svg, "fig-loop-sensitivity.svg",
                  (check.name,))


def robustness_figure(result: Any, check: Any) -> Figure | None:
    """The robust_grid check's margin over its parameter lattice (axes from the certificate)."""
    svg = robustness_svg(check.name, check.certificate)
    if svg is None:
        return None
    keys = svg_keys(svg)
    axes = check.certificate["grid"]["axes"]
    names = " and ".join(a["name"] for a in axes)
    label = str(check.certificate["grid"].get("label", "margin")).split(";", 1)[0].strip()
    caption = f"{label[:1].upper()}{label[1:]} of the closed loop over the lattice of {names}"
    if len(axes) == 2:
        caption += "; green where it is above zero, red below"
        caption += (", and the black line is where the value is zero." if "zero-contour" in keys else
                    "; the value does not change sign over the lattice.")
    else:
        caption += "; above zero (the grey line) is robust."
    return Figure(f"Robustness over {names}", caption, svg, f"fig-robustness-{_slug(check.name)}.svg", (check.name,))


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
                  "fig-coupling.svg", (check.name,))


def _draw_singularity(data: Any) -> Any:
    t = np.asarray(data["time"], float)
    fig, (ax_c, ax_w) = new_figure(6.8, 4.6, rows=2)
    ax_c.semilogy(t, np.asarray(data["condition"], float), color=BLUE, label="condition number of J")
    plain_ticks(ax_c.yaxis)
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
                  render(_draw_singularity, check.data), "fig-singularity.svg", (check.name,))


def _draw_workspace(data: Any) -> Any:
    joints = [j for j in data["joints"] if math.isfinite(j["tau_stable"][1]) and j["tau_stable"][1] > 0]
    if not joints:
        return None
    fig, (ax,) = new_figure(6.8, 1.5 + 0.4 * len(joints), layout="constrained")  # outside legend
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
        plain_ticks(ax.xaxis)
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
    return Figure("Joint loops over the workspace", caption, svg, "fig-workspace.svg", (check.name,))


DESIGN_FIGURES: tuple[Callable[[Any], Figure | None], ...] = (pole_zero_figure, linear_figure, simulation_figure)
"""Figures drawn from the design and the simulation, in report order."""

CHECK_FIGURES: dict[str, Callable[[Any, Any], Figure | None]] = {
    "loop_margins": bode_figure,
    "coupling": coupling_figure,
    "workspace": workspace_figure,
    "singularity": singularity_figure,
}
"""Check name -> figure drawn from that check's certificate and data."""

EXTRA_CHECK_FIGURES: dict[str, tuple[Callable[[Any, Any], Figure | None], ...]] = {
    "loop_margins": (sensitivity_figure,),
}
"""Check name -> further figures drawn from that check, after its :data:`CHECK_FIGURES` one."""


def design_figures(result: Any, *, processes: int = 1) -> tuple[Figure, ...]:
    """Every figure of a report, in report order (figures without data are left out).

    A check gets the figure :data:`CHECK_FIGURES` names for it, or, when its certificate holds a
    parameter lattice (``"grid"``), the robustness figure; then those of :data:`EXTRA_CHECK_FIGURES`.
    File names are unique (a later figure with a taken name is left out).  With ``processes=2`` the
    figures are drawn on two cores (:func:`designkit.report.parallel.run_tasks`; same figures).
    """
    from functools import partial

    from designkit.report.parallel import run_tasks

    tasks: list[Callable[[], Figure | None]] = [partial(draw, result) for draw in DESIGN_FIGURES]
    for check in result.checks:
        draw = CHECK_FIGURES.get(check.name)
        if draw is None and isinstance(check.certificate, dict | Mapping) and "grid" in check.certificate:
            draw = robustness_figure
        draws = ((draw,) if draw is not None else ()) + EXTRA_CHECK_FIGURES.get(check.name, ())
        tasks.extend(partial(d, result, check) for d in draws)
    out = [f for f in run_tasks(tasks, processes=processes) if f is not None]
    seen: set[str] = set()
    return tuple(f for f in out if not (f.filename in seen or seen.add(f.filename)))


def _slug(text: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in text)[:60] or "check"
