"""The sliding variable of the PID/sliding-mode link controller and the §5.4 input-equivalent perturbation.

Derivations (package docstring; checked by SymPy, python-control and simulation in the tests):

* ``slm = a1 x1 + a2 x2 + x3`` (servo) or ``a1 dx1 + a2 dx2 + x3`` (tracking), ``a1 = -(1/p1 + 1/p2)`` (s),
  ``a2 = 1/(p1 p2)`` (s^2), obeys ``slm' = p3 slm + g (du + xi)`` with ``g = a2 Km/tau = Km/(tau p1 p2)``
  ((rad*s)/(N*m*s), i.e. rad/(N*m*s)), for the PID whose zero is on ``p3``;
* a true plant ``(Km, tau)`` under gains designed for ``(Km0, tau0)`` is the nominal one with the
  input-equivalent perturbation (referred to the true input gain ``b = Km/tau``)
  ``xi_p = (tau/Km) [(1/tau0 - 1/tau) x2 + (Km/tau - Km0/tau0) u0]``, ``u0`` the PID part of the command.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

__all__ = ["Surface", "impulse", "l1_norm", "perturbation_of_change", "split_poles", "surface", "ideal_motion"]


def split_poles(poles: Sequence[complex]) -> tuple[complex, complex, float]:
    """``(p1, p2, p3)``: the pair the sliding motion keeps and the real pole ``p3`` the zero cancels (the real
    pole when the others are a complex pair, else the third pole as given)."""
    ps = [complex(p) for p in poles]
    real = [p for p in ps if p.imag == 0]
    if len(real) == 1:
        pair = [p for p in ps if p.imag != 0]
        return pair[0], pair[1], real[0].real
    return ps[0], ps[1], ps[2].real


@dataclass(frozen=True)
class Surface:
    """The sliding variable's coefficients: ``a1`` (s), ``a2`` (s^2), ``p3`` (1/s) and the poles."""

    a1: float
    a2: float
    p3: float
    p1: complex
    p2: complex

    def gain(self, Km: float | np.ndarray, tau: float | np.ndarray) -> float | np.ndarray:
        """``g = a2 Km/tau`` (rad/(N*m*s)): ``slm' = p3 slm + g (du + xi)``."""
        return self.a2 * np.asarray(Km, float) / np.asarray(tau, float)


def surface(poles: Sequence[complex]) -> Surface:
    """The :class:`Surface` of three closed-loop poles (1/s)."""
    p1, p2, p3 = split_poles(poles)
    return Surface(a1=float((-(1 / p1 + 1 / p2)).real), a2=float((1 / (p1 * p2)).real), p3=p3, p1=p1, p2=p2)


def impulse(sf: Surface, t: np.ndarray) -> np.ndarray:
    """Impulse response (1/s^2 per unit slm, i.e. of ``s/N(s)`` with ``N = 1 + a1 s + a2 s^2``) at ``t`` (s):
    ``p1 p2 (p1 e^(p1 t) - p2 e^(p2 t))/(p1 - p2)``, or ``p^2 (1 + p t) e^(p t)`` for a double pole."""
    p1, p2 = sf.p1, sf.p2
    t = np.asarray(t, float)
    if abs(p1 - p2) <= 1e-9 * abs(p1):
        p = (p1 + p2) / 2
        return (p * p * (1 + p * t) * np.exp(p * t)).real
    return (p1 * p2 * (p1 * np.exp(p1 * t) - p2 * np.exp(p2 * t)) / (p1 - p2)).real


def l1_norm(sf: Surface) -> float:
    """``||h||_1`` (1/s) of the impulse response of ``s/N(s)``: ``|x1 - x1_ideal| <= ||h||_1 sup|slm|``
    (trapezoids on 400 000 points up to 40 time constants of the slower pole)."""
    slow = min(abs(sf.p1.real), abs(sf.p2.real))
    t = np.linspace(0.0, 40.0 / slow, 400001)
    return float(np.trapezoid(np.abs(impulse(sf, t)), t))


def ideal_motion(sf: Surface, t: np.ndarray, ref: np.ndarray, form: str, start: float | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(x1, x2, x3)`` on ``slm = 0`` from rest at the reference's start (rad, rad/s, rad*s).

    ``ref`` has shape ``(N, 3)`` (position, velocity, acceleration).  Servo: ``x1 = xD/N(s)``, held-input exact
    discretisation of ``a2 x1'' + a1 x1' + x1 = xD`` (the servo's references are piecewise constant), and
    ``x3 = -a1 x1 - a2 x2``, from ``x1 = start`` (default: the reference's value before its first sample,
    ``ref[0, 0]`` held before ``t[0]``).  Tracking: ``x1 = xD``, ``x2 = xD'``, ``x3 = 0``.
    """
    if form == "tracking":
        return ref[:, 0].copy(), ref[:, 1].copy(), np.zeros(len(t))
    A = np.array([[0.0, 1.0], [-1.0 / sf.a2, -sf.a1 / sf.a2]])
    Bm = np.array([0.0, 1.0 / sf.a2])
    z = np.array([ref[0, 0] if start is None else float(start), 0.0])
    out = np.empty((len(t), 2))
    out[0] = z
    cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
    for k in range(1, len(t)):
        h = float(t[k] - t[k - 1])
        if h not in cache:
            E = expm(np.block([[A, Bm[:, None]], [np.zeros((1, 3))]]) * h)
            cache[h] = (E[:2, :2], E[:2, 2])
        Ad, Bd = cache[h]
        z = Ad @ z + Bd * ref[k - 1, 0]
        out[k] = z
    x1, x2 = out[:, 0], out[:, 1]
    return x1, x2, -sf.a1 * x1 - sf.a2 * x2


def perturbation_of_change(x2: np.ndarray, u0: np.ndarray, Km: float, tau: float, Km0: float, tau0: float
                           ) -> np.ndarray:
    """§5.4: ``xi_p = (tau/Km) [(1/tau0 - 1/tau) x2 + (Km/tau - Km0/tau0) u0]`` (N*m).

    The true link ``x2' = -x2/tau + (Km/tau)(u0 + du)`` equals the nominal one written with the true input gain,
    ``x2' = -x2/tau0 + (Km0/tau0) u0 + (Km/tau)(du + xi_p)``.
    """
    return (tau / Km) * ((1.0 / tau0 - 1.0 / tau) * np.asarray(x2, float) + (Km / tau - Km0 / tau0)
                         * np.asarray(u0, float))
