"""Frequency responses of the loop broken at the plant input (data of the ``loop_margins`` check): the Bode
plot with its margins, and the sensitivity |S| and complementary sensitivity |T| with their peaks."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from designkit.display.figure import EVENT_STYLE, JOINT_COLORS, Figure, few_log_ticks
from designkit.display.numbers import sci
from designkit.display.svg import GREY, new_figure, render_tagged, tag

__all__ = ["bode_figure", "sensitivities", "sensitivity_figure", "sensitivity_peaks"]


def _draw_bode(data: Any) -> Any:
    w = np.asarray(data["frequency"], float)
    fig, (ax_m, ax_p) = new_figure(6.8, 4.6, rows=2)
    text = []
    for k, ch in enumerate(data["channels"]):
        resp, m = np.asarray(ch["response"]), ch["margins"]
        color = JOINT_COLORS[k % len(JOINT_COLORS)]
        phase = np.degrees(np.unwrap(np.angle(resp)))
        phase -= 360.0 * math.ceil(phase[0] / 360.0)
        mag = np.abs(resp)
        db = 20.0 * np.log10(np.where(mag > 0, mag, np.nan))  # a zero loop gain (a loop frozen at zero) is not drawn
        tag(fig, "loop-gain", *ax_m.semilogx(w, db, color=color,
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
    few_log_ticks(ax_p)
    if len(data["channels"]) > 1:
        ax_m.legend(loc="lower left", framealpha=0.9)
    if text:
        tag(fig, "margin-box", ax_m.text(0.99, 0.96, "\n".join(text), transform=ax_m.transAxes, ha="right", va="top",
                                         fontsize=8, zorder=5,
                                         bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": GREY, "alpha": 0.9}))
    return fig



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
    display = getattr(result, "display", None)  # the family's Display (PipelineResult.display)
    transfer = display.loop_line(getattr(result, "design", None)) if display is not None else ""
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
        color = JOINT_COLORS[k % len(JOINT_COLORS)]
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
    few_log_ticks(ax_t)
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
    if any(math.isfinite(p["w_Ms"]) for p in peaks):
        text += " |S| above 0 dB amplifies output disturbances at those frequencies."
    else:
        text += " |S| stays below 0 dB: no output disturbance is amplified at any frequency of the grid."
    return text + " |T| is the response to measurement noise and to the reference."


def sensitivity_figure(result: Any, check: Any) -> Figure | None:
    """|S| and |T| of the loop broken at each plant input, peaks marked (data of the ``loop_margins`` check)."""
    if not check.data.get("channels"):
        return None
    svg, keys, _ = render_tagged(_draw_sensitivity, check.data)
    caption = _sensitivity_caption(keys, sensitivity_peaks(check.data))
    return Figure("Sensitivity and complementary sensitivity", caption, svg, "fig-loop-sensitivity.svg",
                  (check.name,))
