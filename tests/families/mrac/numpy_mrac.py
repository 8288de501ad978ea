"""The MRAC loop written again in NumPy from the notes (section 4.2) and the link's equations, for the tests.

Independent of the family's code: the sensitivity filters are derived by hand from the reference model
``y1'' + a2 y1' + a1 y1 = a1 r`` (differentiate in ``a1``: ``s1'' + a2 s1' + a1 s1 = r - y1``; in ``a2``:
``s2'' + a2 s2' + a1 s2 = -y1'``), the gains from ``x1'' + ((1 + Km K2)/tau) x1' + (Km K1/tau) x1 =
(Km K1/tau) xD`` and the rule from ``alpha' = -gamma (de/dalpha)' Q e`` with ``de/dalpha ~ -dy/da``.
Integrated by scipy between the reference's jumps and the plant change (no RK4 step straddles them).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.integrate import solve_ivp


def square(amplitude: float, period: float) -> Callable[[float], float]:
    """``+A`` over the first half of every period, ``-A`` over the second."""
    return lambda t: amplitude if (t % period) < 0.5 * period - 1e-12 else -amplitude


def rhs(t: float, s: np.ndarray, *, Km: float, tau: float, nominal: tuple[float, float], a: Sequence[float],
        gamma: Sequence[float], Q: np.ndarray, r: float) -> np.ndarray:
    """``s = (x1, x2, y1, y2, dy1/da1, dy2/da1, dy1/da2, dy2/da2, alpha1, alpha2)``."""
    x1, x2, y1, y2, s11, s21, s12, s22, al1, al2 = s
    a1, a2 = a
    Kmn, taun = nominal
    K1, K2 = taun * al1 / Kmn, (taun * al2 - 1.0) / Kmn
    u = -K1 * (x1 - r) - K2 * x2
    e = np.array([y1 - x1, y2 - x2])
    S = np.array([[s11, s12], [s21, s22]])
    alpha_dot = np.asarray(gamma) * (S.T @ Q @ e)
    return np.array([x2, -x2 / tau + Km / tau * u,
                     y2, -a1 * y1 - a2 * y2 + a1 * r,
                     s21, -a1 * s11 - a2 * s21 + (r - y1),
                     s22, -a1 * s12 - a2 * s22 - y2,
                     alpha_dot[0], alpha_dot[1]])


def simulate(t_eval: np.ndarray, *, Km: float, tau: float, nominal: tuple[float, float], a: Sequence[float],
             gamma: Sequence[float], Q: Sequence[Sequence[float]], initial: Sequence[float], amplitude: float,
             period: float | None, change: tuple[float, float] | None = None, rtol: float = 1e-10,
             atol: float = 1e-12) -> np.ndarray:
    """States at ``t_eval`` ``(N, 10)``: from rest at 0, reference a square wave (``period``) or a step
    (``period=None``), ``change = (time, Km)`` steps the link's gain."""
    Qm = np.asarray(Q, dtype=float)
    t_end = float(t_eval[-1])
    events = {0.0, t_end}
    if period is not None:
        events |= {k * 0.5 * period for k in range(1, int(t_end / (0.5 * period)) + 1)}
    if change is not None:
        events.add(float(change[0]))
    events = sorted(e for e in events if e <= t_end)
    ref = square(amplitude, period) if period is not None else (lambda t: amplitude)
    s = np.array([0, 0, 0, 0, 0, 0, 0, 0, *initial], dtype=float)
    out = np.empty((t_eval.size, 10))
    for lo, hi in zip(events[:-1], events[1:], strict=True):
        mid = 0.5 * (lo + hi)
        gain = change[1] if change is not None and mid >= change[0] else Km
        inside = (t_eval >= lo - 1e-12) & (t_eval <= hi + 1e-12)
        options = {"Km": gain, "tau": tau, "nominal": nominal, "a": a, "gamma": gamma, "Q": Qm, "r": ref(mid)}
        sol = solve_ivp(lambda t, z, o=options: rhs(t, z, **o), (lo, hi), s, method="DOP853", rtol=rtol,
                        atol=atol, dense_output=True)
        out[inside] = sol.sol(t_eval[inside]).T
        s = sol.y[:, -1]
    return out
