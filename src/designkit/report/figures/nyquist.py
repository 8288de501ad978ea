"""The describing-function picture of a loop with a relay or a saturation: the Nyquist curve against ``-1/N(a)``.

For a single-input loop (the link) whose plant input passes through a relay or a saturation
(``simulation.nonlinearity``), the loop broken at the plant input, ``L(jw)`` (as the ``loop_margins``
check computes it, times ``e^(-jw d)`` for the half-step delay of an element evaluated once per step), is drawn
with the locus ``-1/N(a)`` of the element's describing function over its input amplitude ``a``:

* relay with hysteresis (output ``+-M``, hysteresis ``h``): ``-1/N(a) = -(pi/4M)(sqrt(a^2 - h^2) + j h)``,
  a horizontal line at ``Im = -pi h/(4M)`` (:func:`designkit.analysis.elements.relay.relay_describing_function`);
* saturation at ``U``: ``N(a) = (2/pi)(asin(k) + k sqrt(1 - k^2))``, ``k = U/a`` for ``a > U`` (1 below), so
  ``-1/N(a)`` runs along the negative real axis from -1 to ``-inf``.

An intersection predicts a limit cycle (harmonic balance); the figure marks it.  Nothing is drawn for other
loops.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.figure import Figure
from designkit.display.svg import BLUE, GREY, RED, new_figure, render

__all__ = ["nyquist_figure", "saturation_describing_function"]


def saturation_describing_function(a: np.ndarray, limit: float) -> np.ndarray:
    """``N(a)`` of a unit-slope saturation at ``limit`` for an input ``a sin(w t)`` (1 for ``a <= limit``)."""
    a = np.asarray(a, dtype=float)
    k = np.clip(limit / np.maximum(a, 1e-300), 0.0, 1.0)
    return np.where(a <= limit, 1.0, (2.0 / np.pi) * (np.arcsin(k) + k * np.sqrt(1.0 - k**2)))


def _draw(L: np.ndarray, locus: np.ndarray, crossings: list[complex], element: str) -> Any:
    fig, (ax,) = new_figure(6.4, 4.6)
    ax.plot(L.real, L.imag, color=BLUE, lw=1.4, label="L(jω), ω > 0")
    ax.plot(locus.real, locus.imag, color=RED, lw=1.4, ls="--", label=f"−1/N(a) of the {element}")
    ax.plot([-1.0], [0.0], "+", color=GREY, ms=10, label="−1")
    if crossings:
        ax.plot([c.real for c in crossings], [c.imag for c in crossings], "o", color=RED, ms=6, mfc="none",
                label="harmonic balance")
    near = [abs(c) for c in crossings] or [1.0]
    span = max(4.0, 1.6 * min(near))  # around the nearest balance point; farther ones are named in the caption
    ax.set_xlim(-span, 0.5 * span)
    ax.set_ylim(-span, 0.5 * span)
    ax.axhline(0.0, color=GREY, lw=0.6)
    ax.axvline(0.0, color=GREY, lw=0.6)
    ax.set_xlabel("Re")
    ax.set_ylabel("Im")
    ax.legend(loc="lower right", framealpha=0.9)
    return fig


def nyquist_figure(result: Any) -> Figure | None:
    """The Nyquist curve against the element's ``-1/N(a)`` (module docstring), or None."""
    sim = result.simulation
    nl = dict(sim.settings.get("nonlinearity") or {}) if sim is not None else {}
    kind = nl.get("kind")
    check = next((c for c in result.checks if c.name == "loop_margins" and c.data.get("channels")), None)
    if kind not in ("relay", "saturation") or check is None or len(check.data["channels"]) != 1:
        return None
    from designkit.verification.loop import loop_frequency_response

    w = np.logspace(math.log10(min(check.data["frequency"])), math.log10(max(check.data["frequency"])) + 1, 4000)
    L = loop_frequency_response(result.design, w)
    if L is None:
        return None
    per_step = "once per step" in str(sim.settings.get("evaluation", ""))
    delay = 0.5 * float(sim.settings.get("dt", 0.0)) if per_step else 0.0
    L = L * np.exp(-1j * w * delay)
    crossings: list[complex] = []
    if kind == "relay":
        from designkit.analysis.elements.relay import relay_describing_function, relay_harmonic_balance

        M = float(np.min(np.atleast_1d(nl["amplitude"])))
        h = float(np.min(np.atleast_1d(nl["hysteresis"])))
        a = np.linspace(max(h, 1e-12), max(h, 1e-12) + 60 * M, 600)
        locus = -1.0 / relay_describing_function(a, M, h)
        words = f"relay ±{M:g} N·m, hysteresis {h:g} N·m"
        found = relay_harmonic_balance(lambda x: np.interp(x, w, L.real) + 1j * np.interp(x, w, L.imag), M, h, w)
        crossings = [complex(-1.0 / relay_describing_function(a0, M, h)) for a0, _ in found]
        if found:
            pairs = "; ".join(f"ω = {w0:.3g} rad/s with a relay input amplitude a = {a0:.3g} N·m" for a0, w0 in found)
            words_cross = f" They meet at {pairs}: harmonic balance predicts a limit cycle at each such point."
        else:
            words_cross = " They do not meet: harmonic balance predicts no limit cycle."
    else:
        U = float(np.min(np.atleast_1d(nl["limit"])))
        a = np.geomspace(U, 1e4 * U, 600)
        locus = -1.0 / saturation_describing_function(a, U).astype(complex)
        words = f"saturation at ±{U:g} N·m"
        k = np.flatnonzero(np.sign(L.imag[:-1]) * np.sign(L.imag[1:]) < 0)
        re = [L.real[i] - L.imag[i] * (L.real[i + 1] - L.real[i]) / (L.imag[i + 1] - L.imag[i]) for i in k]
        crossings = [complex(r, 0.0) for r in re if r < -1.0]
        if crossings:
            where = ", ".join(f"{c.real:.3g}" for c in crossings)
            words_cross = (f" The curve crosses the locus at {where} on the real axis, where a saturation that lowers "
                           f"the loop gain to 1/{abs(crossings[0].real):.3g} of its design sustains an oscillation "
                           "(harmonic balance); for this conditionally stable loop it marks the gain below which the "
                           "saturated loop is unstable.")
        else:
            words_cross = (" The curve does not cross the negative real axis beyond −1: harmonic balance predicts no "
                           "limit cycle.")
    caption = (f"Nyquist curve of the loop broken at the plant input (solid; times e^(−jω d) with d = {delay:.3g} s, "
               "the mean delay of an element evaluated once per step) and the locus −1/N(a) of the describing function "
               f"of the {words} over its input amplitude a (dashed)." + words_cross)
    return Figure("Describing function against the loop", caption, render(_draw, L, locus, crossings, kind),
                  "fig-describing-function.svg", ("loop_margins",))
