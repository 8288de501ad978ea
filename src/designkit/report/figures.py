"""Report figures as deterministic SVG text (matplotlib, imported lazily).

Figures are built with :class:`matplotlib.figure.Figure` directly, never through ``pyplot``, so
no GUI backend is selected and no global figure registry is touched (the SVG canvas renders
them; the interactive backend setting is irrelevant).  Every ``*_svg`` function returns the SVG
of one figure, or ``None`` when the data it needs is absent.  Output is reproducible byte for
byte: ids are salted with a fixed ``svg.hashsalt``, the date metadata is dropped and text is
drawn as paths (no font is needed to view the SVG).  The options are applied with
:func:`matplotlib.rc_context`, so matplotlib's global state is left as it was.

The loop transfer (:func:`loop_matrices`, :func:`loop_frequency_response`,
:func:`loop_margins`) is the open loop broken at the plant input, where
the input-equivalent perturbation ``xi`` enters (``u + xi``).  With the closed loop
``x' = A x + B r``, ``u = K x + D_u r`` and ``b`` the ``xi`` column of ``B`` (which is the plant
input matrix), the loop before closing is ``A - b K`` and

    L(s) = -K (sI - A + b K)^-1 b,     1 + L(s) = det(sI - A) / det(sI - A + b K).

For the PID servo on the link this is ``L(s) = Km (K2 s^2 + K1 s + K3) / (s^2 (tau s + 1))``,
i.e. ``C(s) P(s)`` with ``C(s) = K1 + K2 s + K3/s`` acting on ``x1`` and
``P(s) = Km / (s (tau s + 1))``; for the tracker the ``x2/Km`` term replaces ``K2`` by
``K2 - 1/Km``.
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

_RC = {
    "svg.hashsalt": "designkit-report",
    "svg.fonttype": "path",
    "font.size": 9.0,
    "axes.titlesize": 10.0,
    "axes.labelsize": 9.0,
    "legend.fontsize": 8.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "lines.linewidth": 1.4,
    "path.simplify": True,
}
_BLUE, _ORANGE, _RED, _GREEN, _GREY, _PURPLE = "#1f5fa8", "#e07b00", "#c0282d", "#2e8b57", "#666666", "#7b3fa0"
_MAX_POINTS = 2000  # per plotted line; longer signals are min/max decimated


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


@dataclass(frozen=True)
class LoopMargins:
    """Classical margins of the loop broken at the plant input.

    Parameters
    ----------
    gain_margin : float
        Gain margin (ratio; ``inf`` when the phase never crosses -180 deg at a finite frequency;
        below 1 for a conditionally stable loop, where the gain may only be *reduced* by that factor).
    phase_margin : float
        Phase margin (deg), ``inf`` when ``|L|`` never crosses 1.
    w_phase_crossover, w_gain_crossover : float
        Frequencies (rad/s) of the phase and gain crossovers (``nan`` when absent).
    modulus_margin : float
        ``inf |1 + L(jw)|`` over the plotted frequency grid and ``w -> inf`` (dimensionless; at
        most 1 because ``L`` is strictly proper).
    """

    gain_margin: float
    phase_margin: float
    w_phase_crossover: float
    w_gain_crossover: float
    modulus_margin: float


# ----------------------------------------------------------------------------- helpers


def _new_figure(width: float, height: float, rows: int = 1, sharex: bool = True):
    from matplotlib.figure import Figure as MplFigure

    fig = MplFigure(figsize=(width, height), layout="constrained")
    axes = fig.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0]
    return fig, axes


def _to_svg(fig) -> str:
    buf = io.StringIO()
    fig.savefig(buf, format="svg", metadata={"Date": None})
    return buf.getvalue()


def _render(draw, *args: Any) -> str | None:
    """Run ``draw(*args) -> figure or None`` under the report's rc settings and return SVG text."""
    import matplotlib

    with matplotlib.rc_context(_RC):
        fig = draw(*args)
        return None if fig is None else _to_svg(fig)


def _column(values: np.ndarray, index: int = 0) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    return arr[:, index] if arr.ndim == 2 else arr


def minmax_decimate(t: np.ndarray, y: np.ndarray, max_points: int = _MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Reduce a signal to at most ``max_points`` samples keeping each bucket's min and max.

    Chattering signals (relays, quantisers) keep their envelope, unlike plain subsampling.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    n = t.size
    if n <= max_points:
        return t, y
    buckets = max_points // 2
    edges = np.linspace(0, n, buckets + 1).astype(int)
    idx = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        if hi <= lo:
            continue
        seg = y[lo:hi]
        i_min, i_max = lo + int(np.argmin(seg)), lo + int(np.argmax(seg))
        idx.extend(sorted({i_min, i_max}))
    sel = np.asarray(idx, dtype=int)
    return t[sel], y[sel]


def _plot(ax, t, y, **kwargs):
    td, yd = minmax_decimate(t, y)
    return ax.plot(td, yd, **kwargs)


def _input_index(system, name: str) -> int | None:
    return system.inputs.index(name) if name in system.inputs else None


def siso_zeros(A: np.ndarray, b: np.ndarray, c: np.ndarray, d: float) -> np.ndarray:
    """Finite transmission zeros of a SISO state-space system (generalised eigenvalues of the
    Rosenbrock pencil)."""
    from scipy.linalg import eigvals

    n = A.shape[0]
    M = np.block([[A, b.reshape(n, 1)], [c.reshape(1, n), np.array([[d]])]])
    N = np.zeros((n + 1, n + 1))
    N[:n, :n] = np.eye(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = eigvals(M, N)
    return np.sort_complex(z[np.isfinite(z)])


def achieved_zeros(design) -> np.ndarray:
    """Zeros of the ``xD -> x1`` channel of the closed loop (empty when the design has none)."""
    cl = design.closed_loop
    i_in = _input_index(cl, "xD")
    if not design.zeros or i_in is None or "x1" not in cl.outputs:
        return np.array([], dtype=complex)
    i_out = cl.outputs.index("x1")
    return siso_zeros(cl.A, cl.B[:, i_in], cl.C[i_out], float(cl.D[i_out, i_in]))


def loop_matrices(design) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(A_open, b, -K)`` of the loop broken at the plant input (see the module docstring),
    or ``None`` when the closed loop has no ``xi`` input or no ``u`` output."""
    cl = design.closed_loop
    i_xi = _input_index(cl, "xi")
    if i_xi is None or "u" not in cl.outputs:
        return None
    b = cl.B[:, [i_xi]]
    K = cl.C[[cl.outputs.index("u")], :]
    return cl.A - b @ K, b, -K


def loop_frequency_response(design, w: np.ndarray) -> np.ndarray | None:
    """``L(jw)`` at the frequencies ``w`` (rad/s)."""
    mats = loop_matrices(design)
    if mats is None:
        return None
    A, b, c = mats
    eye = np.eye(A.shape[0])
    return np.array([(c @ np.linalg.solve(1j * wk * eye - A, b))[0, 0] for wk in w])


def _frequency_grid(design) -> np.ndarray:
    mags = [abs(p) for p in np.linalg.eigvals(design.closed_loop.A) if abs(p) > 1e-9]
    mags += [abs(p) for p in design.poles if abs(p) > 1e-9]
    lo, hi = (min(mags), max(mags)) if mags else (1.0, 1.0)
    return np.logspace(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 1, 600)


def loop_margins(design) -> LoopMargins | None:
    """Gain and phase margins of the loop broken at the plant input (python-control
    ``stability_margins``) and the modulus margin ``inf |1 + L(jw)|``."""
    import control

    mats = loop_matrices(design)
    if mats is None:
        return None
    A, b, c = mats
    gm, pm, _sm, wpc, wgc, _wms = control.stability_margins(control.ss(A, b, c, 0.0))
    resp = loop_frequency_response(design, _frequency_grid(design))
    return LoopMargins(
        gain_margin=float(gm), phase_margin=float(pm), w_phase_crossover=float(wpc),
        # L is strictly proper, so |1 + L(jw)| -> 1 as w -> inf: the infimum is at most 1
        w_gain_crossover=float(wgc), modulus_margin=min(float(np.min(np.abs(1.0 + resp))), 1.0),
    )


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
    return _render(_draw_pole_zero, design)


def _draw_pole_zero(design):
    fig, (ax,) = _new_figure(6.4, 3.0)
    achieved = np.linalg.eigvals(design.closed_loop.A)
    zeros = achieved_zeros(design)
    req_p = np.array(design.poles, dtype=complex)
    req_z = np.array(design.zeros, dtype=complex)
    ax.axvline(0.0, color=_GREY, lw=0.8)
    ax.axhline(0.0, color=_GREY, lw=0.8)
    if req_p.size:
        ax.plot(req_p.real, req_p.imag, "o", ms=13, mfc="none", mec=_ORANGE, mew=1.6, ls="none",
                label="requested poles")
    ax.plot(achieved.real, achieved.imag, "x", ms=9, color=_BLUE, mew=2.0, ls="none", label="achieved poles")
    if req_z.size:
        ax.plot(req_z.real, req_z.imag, "s", ms=13, mfc="none", mec=_ORANGE, mew=1.6, ls="none",
                label="requested zero")
    if zeros.size:
        ax.plot(zeros.real, zeros.imag, "o", ms=7, mfc="none", mec=_BLUE, mew=1.8, ls="none",
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
    return _render(_draw_step, design, requirements, simulation_spec, simulation)


def _draw_step(design, requirements, simulation_spec, simulation):
    tracking = _input_index(design.closed_loop, "xDd") is not None
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
    fig, (ax, ax_u) = _new_figure(6.8, 4.6, rows=2)
    fig.get_layout_engine().set(h_pad=0.06)
    ax.plot(t, ref[:, 0], color=_GREY, ls="--", lw=1.0, label="xD (reference)")
    ax.plot(t, x1, color=_BLUE, label="x1 (linear, nominal)")
    if requirements is not None and _at_rest(t, ref[:, 0]):
        _draw_envelope(ax, t, amplitude, requirements)
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9)
    ax_u.plot(t, u, color=_PURPLE, label="u (linear)")
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
        ax.axhline(limit, color=_RED, ls="--", lw=1.0, label=label)
        ax.axhline(-limit, color=_RED, ls="--", lw=1.0)
    else:
        ax.plot([], [], color=_RED, ls="--", lw=1.0, label=f"{label} (off scale)")


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
        ax.axhline(a + math.copysign(mag * req.overshoot / 100.0, a), color=_RED, ls="--", lw=1.0,
                   label=f"overshoot limit ({req.overshoot:g} %)")
    if req.settling_time is not None and req.settling_time < t_end:
        band = req.settling_band * mag
        ax.fill_between([req.settling_time, t_end], a - band, a + band, color=_GREEN, alpha=0.18, lw=0,
                        label=f"settling band ±{100 * req.settling_band:g} % after {req.settling_time:g} s")
        ax.axvline(req.settling_time, color=_GREEN, ls=":", lw=1.0)
    if req.rise_time is not None and req.rise_time < t_end:
        ax.plot([req.rise_time], [0.9 * a], marker="^" if a > 0 else "v", ms=8, color=_RED, ls="none",
                label=f"rise-time limit: 90 % by {req.rise_time:g} s")
        ax.axvline(req.rise_time, color=_RED, ls=":", lw=0.9)
    if req.steady_state_error is not None:
        e = req.steady_state_error
        t0 = t[0] + 0.8 * (t_end - t[0])
        ax.hlines([a - e, a + e], t0, t_end, colors=_ORANGE, lw=1.2,
                  label=f"steady-state band ±{e:g} rad")


def bode_svg(design) -> str | None:
    """Bode plot of the loop broken at the plant input, margins annotated (``None`` if undefined)."""
    return _render(_draw_bode, design)


def _draw_bode(design):
    w = _frequency_grid(design)
    resp = loop_frequency_response(design, w)
    margins = loop_margins(design)
    if resp is None or margins is None:
        return None
    mag_db = 20.0 * np.log10(np.abs(resp))
    phase = np.degrees(np.unwrap(np.angle(resp)))
    # unwrap keeps continuity; shift by whole turns so the low-frequency phase lies in (-360, 0]
    phase -= 360.0 * math.ceil(phase[0] / 360.0)
    fig, (ax_m, ax_p) = _new_figure(6.8, 4.6, rows=2)
    ax_m.semilogx(w, mag_db, color=_BLUE)
    ax_m.axhline(0.0, color=_GREY, lw=0.8)
    ax_m.set_ylabel("|L(jω)| (dB)")
    ax_p.semilogx(w, phase, color=_BLUE)
    ax_p.axhline(-180.0, color=_GREY, lw=0.8)
    ax_p.set_ylabel("∠L(jω) (deg)")
    ax_p.set_xlabel("ω (rad/s)")
    ax_p.set_xlim(w[0], w[-1])
    text = []
    if math.isfinite(margins.w_gain_crossover):
        wgc = margins.w_gain_crossover
        for a in (ax_m, ax_p):
            a.axvline(wgc, color=_GREEN, ls=":", lw=1.0)
        ax_p.annotate("", xy=(wgc, -180.0 + margins.phase_margin), xytext=(wgc, -180.0),
                      arrowprops={"arrowstyle": "<->", "color": _GREEN, "lw": 1.4})
        text.append(f"PM = {margins.phase_margin:.1f}° at ω = {wgc:.3g} rad/s")
    else:
        text.append("PM: no gain crossover")
    if math.isfinite(margins.w_phase_crossover) and math.isfinite(margins.gain_margin):
        wpc = margins.w_phase_crossover
        for a in (ax_m, ax_p):
            a.axvline(wpc, color=_RED, ls=":", lw=1.0)
        gm_db = 20.0 * math.log10(margins.gain_margin)
        ax_m.annotate("", xy=(wpc, 0.0), xytext=(wpc, -gm_db),
                      arrowprops={"arrowstyle": "<->", "color": _RED, "lw": 1.4})
        text.append(f"GM = {margins.gain_margin:.3g} ({gm_db:+.1f} dB) at ω = {wpc:.3g} rad/s")
    else:
        text.append("GM = ∞ (phase never crosses -180° at finite ω)")
    text.append(f"min |1 + L| = {margins.modulus_margin:.3g}")
    ax_m.text(0.99, 0.96, "\n".join(text), transform=ax_m.transAxes, ha="right", va="top", fontsize=8,
              bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": _GREY, "alpha": 0.9}, zorder=5)
    lo, hi = float(np.min(phase)), float(np.max(phase))
    ax_p.set_ylim(min(lo, -180.0) - 15.0, max(hi, -180.0) + 15.0)
    return fig


def simulation_svg(simulation, requirements=None) -> str | None:
    """Nonlinear simulation: ``x1`` and ``xD`` (with the requirement envelope when the reference
    comes to rest); ``u_command``, ``u_applied``, the perturbation and the control limit."""
    if simulation is None:
        return None
    return _render(_draw_simulation, simulation, requirements)


def _draw_simulation(sim, requirements):
    t = np.asarray(sim.time, float)
    xd = _column(sim.reference)
    fig, (ax, ax_u) = _new_figure(6.8, 4.6, rows=2)
    _plot(ax, t, xd, color=_GREY, ls="--", lw=1.0, label="xD (reference)")
    _plot(ax, t, _column(sim.state), color=_BLUE, label="x1")
    if requirements is not None and t.size > 1 and _at_rest(t, xd):
        _draw_envelope(ax, t, float(xd[-1]), requirements)
    if requirements is not None and requirements.max_control is not None:
        peak = max(float(np.max(np.abs(_column(sim.u_command)))), float(np.max(np.abs(_column(sim.u_applied)))))
        _control_limit(ax_u, requirements.max_control, peak)
    ax.set_ylabel("position (rad)")
    ax.legend(loc="best", framealpha=0.9)
    # applied first, so that a chattering applied control (relay, quantiser) does not hide the command
    _plot(ax_u, t, _column(sim.u_applied), color=_ORANGE, lw=1.0, alpha=0.75, label="u applied")
    _plot(ax_u, t, _column(sim.u_command), color=_PURPLE, lw=1.2, label="u command")
    pert = _column(sim.perturbation) if np.size(sim.perturbation) else np.zeros(0)
    if pert.size == t.size and np.any(pert != 0.0):
        _plot(ax_u, t, pert, color=_RED, ls="--", lw=1.0, label="perturbation ξ")
    ax_u.set_ylabel("control (N·m)")
    ax_u.set_xlabel("time (s)")
    ax_u.set_xlim(t[0], t[-1])
    ax_u.legend(loc="best", framealpha=0.9)
    return fig


_GRID_VALUE_KEYS = ("values", "margin", "margins", "value", "z")


def robustness_grid(certificate: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray, str] | None:
    """``(Km, tau, values[tau, Km], label)`` from a certificate's ``"grid"`` entry, else ``None``.

    Accepted form: ``certificate["grid"] = {"Km": [...], "tau": [...], "values": [[...]],
    "label": "..."}`` where ``values`` has shape ``(len(tau), len(Km))`` or ``(len(Km), len(tau))``
    (the key may also be ``margin``/``margins``/``value``/``z``).
    """
    grid = certificate.get("grid") if isinstance(certificate, Mapping) else None
    if not isinstance(grid, Mapping) or "Km" not in grid or "tau" not in grid:
        return None
    key = next((k for k in _GRID_VALUE_KEYS if k in grid), None)
    if key is None:
        return None
    try:
        km = np.asarray(grid["Km"], float).ravel()
        tau = np.asarray(grid["tau"], float).ravel()
        values = np.asarray(grid[key], float)
    except (TypeError, ValueError):
        return None
    if values.shape == (km.size, tau.size) and km.size != tau.size:
        values = values.T
    if values.shape != (tau.size, km.size) or km.size < 2 or tau.size < 2:
        return None
    return km, tau, values, str(grid.get("label", key))


def robustness_svg(name: str, certificate: Mapping[str, Any]) -> str | None:
    """Heat map of a robustness margin over the ``(Km, tau)`` box (``None`` without grid data)."""
    data = robustness_grid(certificate)
    if data is None:
        return None
    return _render(_draw_robustness, name, data)


def _draw_robustness(name: str, data):
    km, tau, values, label = data
    fig, (ax,) = _new_figure(6.4, 4.0)
    finite = values[np.isfinite(values)]
    vmax = float(np.max(np.abs(finite))) if finite.size else 1.0
    vmax = vmax if vmax > 0 else 1.0
    mesh = ax.pcolormesh(km, tau, values, shading="nearest", cmap="RdYlGn", vmin=-vmax, vmax=vmax)
    if finite.size and np.min(finite) < 0 < np.max(finite):
        ax.contour(km, tau, values, levels=[0.0], colors="black", linewidths=1.2)
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel("Km ((rad/s)/(N·m))")
    ax.set_ylabel("τ (s)")
    ax.set_title(f"{name}: {label}")
    return fig


def design_figures(
    design, *, requirements=None, simulation_spec=None, simulation=None,
    checks: Sequence[Any] = (),
) -> tuple[Figure, ...]:
    """Every figure of a report, in report order (figures without data are left out)."""
    tracking = _input_index(design.closed_loop, "xDd") is not None
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
