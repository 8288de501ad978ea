"""Report figures as deterministic SVG text (matplotlib, imported lazily).

Every ``*_svg`` function returns the SVG of one figure, or ``None`` when the data it needs is
absent; :func:`design_figures` collects them in report order.  Rendering (rc settings, palette,
byte-for-byte reproducible SVG, decimation of long signals) lives in :mod:`designkit.report.svg`,
the loop transfer and its margins in :mod:`designkit.report.loop` and the robustness heat map in
:mod:`designkit.report.heatmap`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.report.heatmap import robustness_svg
from designkit.report.loop import achieved_zeros, frequency_grid, input_index, loop_frequency_response, loop_margins
from designkit.report.svg import BLUE, GREEN, GREY, ORANGE, PURPLE, RED, column, new_figure, plot_decimated, render


@dataclass(frozen=True)
class Figure:
    """One report figure.

    Parameters
    ----------
    title : str
        Short title shown above the figure.
    caption : str
        What the figure shows and how to read it.
    svg : str
        A standalone SVG document.
    filename : str
        File name used when the figure is written next to the Typst source (``*.svg``).
    """

    title: str
    caption: str
    svg: str
    filename: str


# ----------------------------------------------------------------------------- helpers


def _time_grid(design, requirements, simulation_spec, horizon: float = 0.0) -> np.ndarray:
    duration = getattr(simulation_spec, "duration", None)
    if duration is None:
        slowest = min((abs(p.real) for p in np.linalg.eigvals(design.closed_loop.A) if abs(p.real) > 1e-9),
                      default=1.0)
        duration = 8.0 / slowest
        if requirements is not None and requirements.settling_time is not None:
            duration = max(duration, 2.0 * requirements.settling_time)
        duration += horizon
    return np.linspace(0.0, float(duration), 1500)


def linear_response(design, t: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(x1, u)`` of the nominal linear closed loop driven by ``reference`` (no perturbation)."""
    import control

    cl = design.closed_loop
    names = {"xD": 0, "xDd": 1, "xDdd": 2}
    U = np.zeros((len(cl.inputs), t.size))
    for k, name in enumerate(cl.inputs):
        if name in names:
            U[k] = reference[:, names[name]]
    resp = control.forced_response(control.ss(cl.A, cl.B, cl.C, cl.D), T=t, U=U, X0=np.zeros(cl.A.shape[0]))
    y = np.atleast_2d(resp.outputs)
    return y[cl.outputs.index("x1")], y[cl.outputs.index("u")]


# ----------------------------------------------------------------------------- figures


def pole_zero_svg(design) -> str:
    """Pole-zero map: achieved closed-loop poles and zeros against the requested ones."""
    return render(_draw_pole_zero, design)


def _draw_pole_zero(design):
    fig, (ax,) = new_figure(6.4, 3.0)
    achieved = np.linalg.eigvals(design.closed_loop.A)
    zeros = achieved_zeros(design)
    req_p = np.array(design.poles, dtype=complex)
    req_z = np.array(design.zeros, dtype=complex)
    ax.axvline(0.0, color=GREY, lw=0.8)
    ax.axhline(0.0, color=GREY, lw=0.8)
    if req_p.size:
        ax.plot(req_p.real, req_p.imag, "o", ms=13, mfc="none", mec=ORANGE, mew=1.6, ls="none",
                label="requested poles")
    ax.plot(achieved.real, achieved.imag, "x", ms=9, color=BLUE, mew=2.0, ls="none", label="achieved poles")
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


def step_response_svg(design, requirements=None, simulation_spec=None, simulation=None) -> str:
    """Ideal linear response of ``x1`` (and ``u``) with the requirement envelope.

    Servo designs get a step of ``simulation_spec.step`` rad; tracking designs follow the
    reference of ``simulation`` when given (else the spec's trajectory).
    """
    return render(_draw_step, design, requirements, simulation_spec, simulation)


def _draw_step(design, requirements, simulation_spec, simulation):
    tracking = input_index(design.closed_loop, "xDd") is not None
    if tracking and simulation is not None and getattr(simulation, "kind", "") == "trajectory":
        t = np.asarray(simulation.time, float)
        ref = np.asarray(simulation.reference, float)
    else:
        from designkit.simulation.reference import reference_for
        from designkit.spec.schema import Simulation

        sim_spec = simulation_spec if simulation_spec is not None else Simulation()
        reference = reference_for("trajectory" if tracking else "step", sim_spec)
        t = _time_grid(design, requirements, simulation_spec, reference.horizon)
        ref = np.asarray(reference.evaluate(t), float)
    amplitude = float(ref[-1, 0])
    x1, u = linear_response(design, t, ref)
    fig, (ax, ax_u) = new_figure(6.8, 4.6, rows=2)
    fig.get_layout_engine().set(h_pad=0.06)
    ax.plot(t, ref[:, 0], color=GREY, ls="--", lw=1.0, label="xD (reference)")
    ax.plot(t, x1, color=BLUE, label="x1 (linear, nominal)")
    if requirements is not None and _at_rest(t, ref[:, 0]):
        _draw_envelope(ax, t, amplitude, requirements)
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9)
    ax_u.plot(t, u, color=PURPLE, label="u (linear)")
    if requirements is not None and requirements.max_control is not None:
        _control_limit(ax_u, requirements.max_control, float(np.max(np.abs(u))))
    ax_u.set_xlabel("time (s)")
    ax_u.set_ylabel("control u (N·m)")
    ax_u.legend(loc="best", framealpha=0.9)
    ax_u.set_xlim(t[0], t[-1])
    return fig


def _control_limit(ax, limit: float, peak: float) -> None:
    """Draw ``|u| <= limit``; when the limit is far beyond the signal (more than 3x its peak) it is
    named in the legend only, so that the signal keeps a readable scale."""
    label = f"|u| ≤ {limit:g} N·m"
    if limit <= 3.0 * peak:
        ax.axhline(limit, color=RED, ls="--", lw=1.0, label=label)
        ax.axhline(-limit, color=RED, ls="--", lw=1.0)
    else:
        ax.plot([], [], color=RED, ls="--", lw=1.0, label=f"{label} (off scale)")


def _at_rest(t: np.ndarray, xd: np.ndarray) -> bool:
    """True when the reference is constant and non-zero over the last 20 % of the time window
    (a step, or a rest-to-rest motion that has ended): only then is there a final value to which
    overshoot, settling and steady-state bounds refer."""
    tail = np.asarray(xd, float)[t >= t[0] + 0.8 * (t[-1] - t[0])]
    final = float(tail[-1]) if tail.size else 0.0
    return final != 0.0 and float(np.ptp(tail)) <= 1e-9 * max(1.0, abs(final))


def _draw_envelope(ax, t, amplitude: float, req) -> None:
    a, mag = amplitude, abs(amplitude)
    t_end = float(t[-1])
    if req.overshoot is not None:
        ax.axhline(a + math.copysign(mag * req.overshoot / 100.0, a), color=RED, ls="--", lw=1.0,
                   label=f"overshoot limit ({req.overshoot:g} %)")
    if req.settling_time is not None and req.settling_time < t_end:
        band = req.settling_band * mag
        ax.fill_between([req.settling_time, t_end], a - band, a + band, color=GREEN, alpha=0.18, lw=0,
                        label=f"settling band ±{100 * req.settling_band:g} % after {req.settling_time:g} s")
        ax.axvline(req.settling_time, color=GREEN, ls=":", lw=1.0)
    if req.rise_time is not None and req.rise_time < t_end:
        ax.plot([req.rise_time], [0.9 * a], marker="^" if a > 0 else "v", ms=8, color=RED, ls="none",
                label=f"rise-time limit: 90 % by {req.rise_time:g} s")
        ax.axvline(req.rise_time, color=RED, ls=":", lw=0.9)
    if req.steady_state_error is not None:
        e = req.steady_state_error
        t0 = t[0] + 0.8 * (t_end - t[0])
        ax.hlines([a - e, a + e], t0, t_end, colors=ORANGE, lw=1.2,
                  label=f"steady-state band ±{e:g} rad")


def bode_svg(design) -> str | None:
    """Bode plot of the loop broken at the plant input, margins annotated (``None`` if undefined)."""
    return render(_draw_bode, design)


def _draw_bode(design):
    w = frequency_grid(design)
    resp = loop_frequency_response(design, w)
    margins = loop_margins(design)
    if resp is None or margins is None:
        return None
    mag_db = 20.0 * np.log10(np.abs(resp))
    phase = np.degrees(np.unwrap(np.angle(resp)))
    # unwrap keeps continuity; shift by whole turns so the low-frequency phase lies in (-360, 0]
    phase -= 360.0 * math.ceil(phase[0] / 360.0)
    fig, (ax_m, ax_p) = new_figure(6.8, 4.6, rows=2)
    ax_m.semilogx(w, mag_db, color=BLUE)
    ax_m.axhline(0.0, color=GREY, lw=0.8)
    ax_m.set_ylabel("|L(jω)| (dB)")
    ax_p.semilogx(w, phase, color=BLUE)
    ax_p.axhline(-180.0, color=GREY, lw=0.8)
    ax_p.set_ylabel("∠L(jω) (deg)")
    ax_p.set_xlabel("ω (rad/s)")
    ax_p.set_xlim(w[0], w[-1])
    text = []
    if math.isfinite(margins.w_gain_crossover):
        wgc = margins.w_gain_crossover
        for a in (ax_m, ax_p):
            a.axvline(wgc, color=GREEN, ls=":", lw=1.0)
        ax_p.annotate("", xy=(wgc, -180.0 + margins.phase_margin), xytext=(wgc, -180.0),
                      arrowprops={"arrowstyle": "<->", "color": GREEN, "lw": 1.4})
        text.append(f"PM = {margins.phase_margin:.1f}° at ω = {wgc:.3g} rad/s")
    else:
        text.append("PM: no gain crossover")
    if math.isfinite(margins.w_phase_crossover) and math.isfinite(margins.gain_margin):
        wpc = margins.w_phase_crossover
        for a in (ax_m, ax_p):
            a.axvline(wpc, color=RED, ls=":", lw=1.0)
        gm_db = 20.0 * math.log10(margins.gain_margin)
        ax_m.annotate("", xy=(wpc, 0.0), xytext=(wpc, -gm_db),
                      arrowprops={"arrowstyle": "<->", "color": RED, "lw": 1.4})
        text.append(f"GM = {margins.gain_margin:.3g} ({gm_db:+.1f} dB) at ω = {wpc:.3g} rad/s")
    else:
        text.append("GM = ∞ (phase never crosses -180° at finite ω)")
    text.append(f"min |1 + L| = {margins.modulus_margin:.3g}")
    ax_m.text(0.99, 0.96, "\n".join(text), transform=ax_m.transAxes, ha="right", va="top", fontsize=8,
              bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": GREY, "alpha": 0.9}, zorder=5)
    lo, hi = float(np.min(phase)), float(np.max(phase))
    ax_p.set_ylim(min(lo, -180.0) - 15.0, max(hi, -180.0) + 15.0)
    return fig


def simulation_svg(simulation, requirements=None) -> str | None:
    """Nonlinear simulation: ``x1`` and ``xD`` (with the requirement envelope when the reference
    comes to rest); ``u_command``, ``u_applied``, the perturbation and the control limit."""
    if simulation is None:
        return None
    return render(_draw_simulation, simulation, requirements)


def _draw_simulation(sim, requirements):
    t = np.asarray(sim.time, float)
    xd = column(sim.reference)
    fig, (ax, ax_u) = new_figure(6.8, 4.6, rows=2)
    plot_decimated(ax, t, xd, color=GREY, ls="--", lw=1.0, label="xD (reference)")
    plot_decimated(ax, t, column(sim.state), color=BLUE, label="x1")
    if requirements is not None and t.size > 1 and _at_rest(t, xd):
        _draw_envelope(ax, t, float(xd[-1]), requirements)
    if requirements is not None and requirements.max_control is not None:
        peak = max(float(np.max(np.abs(column(sim.u_command)))), float(np.max(np.abs(column(sim.u_applied)))))
        _control_limit(ax_u, requirements.max_control, peak)
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9)
    _element_levels(ax_u, (sim.settings or {}).get("nonlinearity"))
    # applied first, so that a chattering applied control (relay, quantiser) does not hide the command
    plot_decimated(ax_u, t, column(sim.u_applied), color=ORANGE, lw=1.0, alpha=0.75, label="u applied")
    plot_decimated(ax_u, t, column(sim.u_command), color=PURPLE, lw=1.2, label="u command")
    pert = column(sim.perturbation) if np.size(sim.perturbation) else np.zeros(0)
    if pert.size == t.size and np.any(pert != 0.0):
        plot_decimated(ax_u, t, pert, color=RED, ls="--", lw=1.0, label="perturbation ξ")
    ax_u.set_ylabel("control (N·m)")
    ax_u.set_xlabel("time (s)")
    ax_u.set_xlim(t[0], t[-1])
    ax_u.legend(loc="best", framealpha=0.9)
    return fig


# nonlinear element kind -> (key of its level in the settings, legend label)
_ELEMENT_LEVELS = {"saturation": ("limit", "saturation ±limit"), "relay": ("amplitude", "relay ±amplitude")}


def _element_levels(ax, element) -> None:
    """Dotted lines at the output levels of a saturating element (saturation, relay)."""
    if not isinstance(element, dict) or element.get("kind") not in _ELEMENT_LEVELS:
        return
    key, label = _ELEMENT_LEVELS[element["kind"]]
    level = element.get(key)
    if isinstance(level, int | float) and math.isfinite(level):
        ax.axhline(level, color=ORANGE, ls=":", lw=1.0, label=label)
        ax.axhline(-level, color=ORANGE, ls=":", lw=1.0)


def design_figures(
    design, *, requirements=None, simulation_spec=None, simulation=None,
    checks: Sequence[Any] = (),
) -> tuple[Figure, ...]:
    """Every figure of a report, in report order (figures without data are left out)."""
    tracking = input_index(design.closed_loop, "xDd") is not None
    kind_word = "trajectory" if tracking else "step"
    pz_caption = ("Achieved closed-loop poles (eigenvalues of the nominal closed-loop A, ×) against the requested "
                  "poles (○); each × should sit in the centre of a ○.")
    if design.zeros:
        pz_caption += (" Zeros of the reference-to-position transfer xD→x1 (small ○) against the requested "
                       "zero (□).")
    loop_formula = {
        "pid_servo": " For the PID servo L(s) = Km (K2 s² + K1 s + K3) / (s² (τ s + 1)).",
        "pid_tracking": " For the PID tracker L(s) = ((Km K2 − 1) s² + Km K1 s + Km K3) / (s² (τ s + 1)) "
                        "(the x2/Km term cancels the plant damping).",
    }.get(design.kind, "")
    out = [
        Figure("Pole-zero map", pz_caption, pole_zero_svg(design), "fig-pole-zero.svg"),
        Figure(
            f"Ideal linear {kind_word} response",
            f"Nominal linear closed loop (no saturation, delay, noise or perturbation) driven by the {kind_word} "
            "reference, with the requirement envelope where the spec has requirements: the response must "
            "stay under the overshoot limit, pass the rise-time marker in time and stay in the settling "
            "band; the lower plot is the control it needs against the control limit.",
            step_response_svg(design, requirements, simulation_spec, simulation), "fig-linear-response.svg",
        ),
    ]
    bode = bode_svg(design)
    if bode is not None:
        out.append(Figure(
            "Loop Bode plot at the plant input",
            "L(s) = −K (sI − A + bK)⁻¹ b: the loop broken where the control (and the perturbation ξ) enters "
            f"the plant.{loop_formula} Green: gain crossover and phase margin; red: phase crossover and gain "
            "margin (a gain margin below 1 means the loop becomes unstable if the gain is reduced by that "
            "factor).",
            bode, "fig-loop-bode.svg",
        ))
    sim = simulation_svg(simulation, requirements)
    if sim is not None:
        out.append(Figure(
            "Nonlinear closed-loop simulation",
            "Simulation on the link model with the spec's nonlinearity, delay, sampling, noise and "
            "perturbation; the time-domain checks are measured on it. Top: position x1 and reference xD "
            "with the requirement envelope. Bottom: control computed by the controller (u command), "
            "control reaching the plant (u applied), the perturbation ξ and the control limit.",
            sim, "fig-simulation.svg",
        ))
    for check in checks:
        svg = robustness_svg(check.name, check.certificate)
        if svg is not None:
            out.append(Figure(
                f"Robustness over the parameter box ({check.name})",
                "The check's margin over the grid of plant parameters (Km, τ); green is robust, red is not, "
                "and the black line is where the margin is zero.",
                svg, f"fig-robustness-{_slug(check.name)}.svg",
            ))
    return tuple(out)


def _slug(text: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in text)[:60] or "check"
