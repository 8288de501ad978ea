"""Why the adaptive computed torque failed, from its SPR condition (``Family.diagnoses``).

Per joint the error filter ``H(s) = (1 + psi s)/(s^2 + K2 s + K1)`` (:mod:`.spr`) has::

    Re H(jw) = [K1 + (psi K2 - 1) w^2] / |K1 - w^2 + j K2 w|^2,      lim w^2 Re H(jw) = psi K2 - 1,

so for ``K1, K2 > 0`` it is strictly positive real exactly when ``psi K2 > 1``; with ``psi K2 < 1``,
``Re H(jw) < 0`` for every ``w > w0 = sqrt(K1/(1 - psi K2))`` (:func:`crossing`).  The update law's Lyapunov
function ``V = sum_j x_j' P_j x_j + phi' K^-1 phi`` (``P_j = [[K2 + psi K1, 1], [1, psi]]``, ``P_j B = C'``)
then has, along the error equation, ``V' = -sum_j [2 K1 e_j^2 + 2 (psi K2 - 1) e_j'^2]``: positive wherever
``|e_j'| > w0 |e_j|`` on a joint whose ``psi K2 < 1``.

* ``spr_certificate`` failed: which joints, ``psi K2``, the frequency above which ``Re H`` is negative (and the
  sweep's least value), and the fix ``psi > 1/K2`` -- declared as the spec change ``psi = 2/K2`` on those joints
  (the value the family chooses when the spec gives none: margin ``psi K2 - 1 = 1``).
* ``adaptive_lyapunov`` failed while some ``psi K2 < 1``: the same condition, with the rise of ``V`` the run shows
  against the integral of ``V'`` over the rise computed from the run's errors (:func:`predicted_rise`), and the
  same fix.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, quantity
from designkit.families.adaptive_computed_torque.spr import PSI_FACTOR, default_psi, frequency_grid, re_h
from designkit.synthesis.spec_change import SpecChange

__all__ = ["crossing", "diagnose", "predicted_rise", "psi_fix"]


def crossing(K1: float, K2: float, psi: float) -> float | None:
    """``w0 = sqrt(K1/(1 - psi K2))`` (rad/s), above which ``Re H(jw) < 0``; None when ``psi K2 >= 1``."""
    return math.sqrt(K1 / (1.0 - psi * K2)) if psi * K2 < 1.0 else None


def predicted_rise(t: np.ndarray, e: np.ndarray, edot: np.ndarray, K1: Sequence[float], K2: Sequence[float],
                   psi: Sequence[float], start: int, end: int) -> float:
    """``int V' dt`` from sample ``start`` to ``end`` with ``V' = -sum_j [2 K1 e_j^2 + 2 (psi K2 - 1) e_j'^2]``
    (trapezoids; ``e``, ``edot`` of shape (N, n) in rad and rad/s): what the error equation says ``V`` gains there."""
    K1, K2, psi = (np.asarray(v, dtype=float) for v in (K1, K2, psi))
    vdot = -np.sum(2.0 * K1 * e**2 + 2.0 * (psi * K2 - 1.0) * edot**2, axis=1)
    v, tt = vdot[start:end + 1], t[start:end + 1]
    return float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(tt)))


def psi_fix(a: Any) -> tuple[list[float], list[int]]:
    """``psi`` per joint of the adaptation ``a`` (its ``K2``, ``psi``) with :func:`~.spr.default_psi` (``2/K2``,
    s) on the joints whose ``psi K2 <= 1``, and those joints (1-based)."""
    psi, bad = [], []
    for j, (k2, p) in enumerate(zip(a.K2, a.psi, strict=True)):
        if p * k2 <= 1.0:
            bad.append(j + 1)
            psi.append(float(f"{default_psi(k2):.6g}"))
        else:
            psi.append(float(p))
    return psi, bad


def _joints(numbers: Sequence[int]) -> str:
    words = [str(j) for j in numbers]
    text = ", ".join(words[:-1]) + f" and {words[-1]}" if len(words) > 1 else words[0]
    return ("joint " if len(words) == 1 else "joints ") + text


def _groups(a: dict[str, Any], joints: Sequence[int]) -> list[tuple[list[int], float, float, float]]:
    """The joints grouped by equal ``(K1, K2, psi)``."""
    groups: dict[tuple[float, float, float], list[int]] = {}
    for j in joints:
        key = (float(a.K1[j - 1]), float(a.K2[j - 1]), float(a.psi[j - 1]))
        groups.setdefault(key, []).append(j)
    return [(js, *key) for key, js in groups.items()]


def _condition(a: dict[str, Any], bad: Sequence[int]) -> str:
    parts = []
    for js, K1, K2, psi in _groups(a, bad):
        w = frequency_grid(K1, K2)
        re = re_h(K1, K2, psi, w)
        k = int(np.argmin(re))
        w0 = crossing(K1, K2, psi)
        s = (f"on {_joints(js)} ψ K2 = {quantity(psi, 's')} × {quantity(K2, '1/s')} = {fmt_number(psi * K2)}"
             + (", below 1" if psi * K2 < 1 else ", not above 1")
             + f", so ω² Re H(jω) tends to ψ K2 − 1 = {fmt_number(psi * K2 - 1)}")
        if w0 is not None:
            s += (f" and Re H(jω) = [K1 + (ψ K2 − 1) ω²]/|K1 − ω² + j K2 ω|² is negative above ω = √(K1/(1 − ψ K2)) = "
                  f"{quantity(w0, 'rad/s')} (least value {quantity(float(re[k]), 's^2')} at "
                  f"{quantity(float(w[k]), 'rad/s')})")
        parts.append(s)
    return "; ".join(parts)


def _fix(a: dict[str, Any]) -> tuple[str, tuple[SpecChange, ...]]:
    psi, bad = psi_fix(a)
    by_k2: dict[float, list[int]] = {}
    for j in bad:
        by_k2.setdefault(float(a.K2[j - 1]), []).append(j)
    bounds = "; ".join(f"{quantity(1.0 / k2, 's')} on {_joints(js)}" for k2, js in by_k2.items())
    chosen = "; ".join(f"{quantity(float(f'{default_psi(k2):.6g}'), 's')} on {_joints(js)}" for k2, js in by_k2.items())
    text = (f"Choose ψ above 1/K2 ({bounds}): ψ K2 > 1 makes H strictly positive real and V' ≤ 0; "
            f"ψ = {fmt_number(PSI_FACTOR)}/K2 ({chosen}), the value this family chooses when the spec gives none, "
            "leaves the margin ψ K2 − 1 = 1.")
    change = SpecChange(f"ψ = {fmt_number(PSI_FACTOR)}/K2 ({chosen})", (("controller.psi", psi),))
    return text, (change,)


def _spr(result: Any, check: Any, a: dict[str, Any]) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    _, bad = psi_fix(a)
    if not bad:
        return None
    cause = ("The error filter H(s) = (1 + ψ s)/(s² + K2 s + K1) is not strictly positive real: " + _condition(a, bad)
             + ". The update law's Lyapunov argument needs it: with P B = Cᵀ, V' = −Σ [2 K1 e² + 2 (ψ K2 − 1) ė²], "
             "whose second term is then positive.")
    return (cause, *_fix(a))


def _errors(sim: Any) -> tuple[np.ndarray, np.ndarray]:
    ref = np.asarray(sim.reference, dtype=float)
    x = np.asarray(sim.state, dtype=float)
    return ref[:, :, 0] - x[:, list(sim.positions)], ref[:, :, 1] - x[:, list(sim.velocities)]


def _lyapunov(result: Any, check: Any, a: dict[str, Any]) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    from designkit.families.adaptive_computed_torque.checks import lyapunov_rise

    _, bad = psi_fix(a)
    sim = result.simulation
    if not bad or sim is None or "V" not in sim.signals:
        return None
    t = np.asarray(sim.time, dtype=float)
    V = np.asarray(sim.signals["V"], dtype=float)
    if not np.all(np.isfinite(V)) or not V[0] > 0:
        return None
    rise, k = lyapunov_rise(V)
    start = int(np.argmin(V[:k + 1]))
    e, edot = _errors(sim)
    gained = predicted_rise(t, e, edot, a.K1, a.K2, a.psi, start, k)
    words = []
    for js, K1, K2, psi in _groups(a, bad):
        w0 = crossing(K1, K2, psi)
        words.append(f"on {_joints(js)} ψ K2 = {fmt_number(psi * K2)}" + (
            f", so V' > 0 wherever |ė| > √(K1/(1 − ψ K2)) |e| = {quantity(w0, '1/s')} × |e|" if w0 is not None else ""))
    cause = ("V is not a Lyapunov function of this loop, because the error filter is not strictly positive real: "
             "along the error equation V' = −Σ [2 K1 e² + 2 (ψ K2 − 1) ė²], and " + "; ".join(words)
             + f". In this run V rises by {fmt_number(100 * rise / V[0])} % of V(0) from t = {quantity(t[start], 's')} "
               f"to {quantity(t[k], 's')}; the integral of that V' over the rise, from the run's errors, is "
               f"{fmt_number(100 * gained / V[0])} % of V(0).")
    return (cause, *_fix(a))


def diagnose(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    """``(cause, fix, changes)`` for a failed ``spr_certificate``, or a failed ``adaptive_lyapunov`` of a design whose
    filter is not SPR (module docstring); else None."""
    data = result.design.data
    a = getattr(data, "adaptation", None)
    if check.passed is not False or a is None or a.scheme != "craig":
        return None
    if check.name == "spr_certificate":
        return _spr(result, check, a)
    if check.name == "adaptive_lyapunov":
        return _lyapunov(result, check, a)
    return None
