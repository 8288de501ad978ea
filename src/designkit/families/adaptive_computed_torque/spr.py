"""The SPR condition of the adaptive computed torque: ``H(s) = (1 + psi s)/(s^2 + K2 s + K1)`` per joint.

The update law's Lyapunov argument (notes section 4.4, step ii) needs the map ``u -> e1 = e + psi e'`` of
the error equation ``e'' + K2 e' + K1 e = u`` strictly positive real.  Realisation (``x = (e, e')``)::

    A = [[0, 1], [-K1, -K2]],  B = [0, 1]',  C = [1, psi]          (H = C (sI - A)^-1 B)

**Analytic condition** (docs/families/adaptive_computed_torque.md).  With ``K1, K2 > 0`` (``A`` Hurwitz)::

    Re H(jw) = [K1 + (psi K2 - 1) w^2] / [(K1 - w^2)^2 + K2^2 w^2],
    lim_{w -> inf} w^2 Re H(jw) = psi K2 - 1,   C B = psi,

so ``H`` is SPR (Khalil, Lemma 6.1: ``A`` Hurwitz, ``Re H(jw) > 0`` for all ``w`` and
``lim w^2 Re H(jw) > 0``) if and only if ``psi K2 > 1``, i.e. ``psi > 1/K2``.  At ``psi = 1/K2`` it is
positive real but not strictly (``w^2 Re H -> 0``).  The KYP certificate in closed form:
``P = [[K2 + psi K1, 1], [1, psi]]`` satisfies ``P B = C'`` and
``A'P + PA = -diag(2 K1, 2 (psi K2 - 1))``; conversely every ``P`` with ``P B = C'`` has ``(A'P + PA)_22
= 2 (1 - psi K2)``, so no certificate exists when ``psi K2 <= 1``.  The margin reported is
``psi K2 - 1`` (dimensionless).

The family's check decides by the KYP lemma on the certificate core
(:func:`designkit.verification.kyp.positive_real`: solved with cvxpy + Clarabel, re-checked in NumPy) for
every joint and for the block-diagonal ``2n``-state system, and cross-checks with the frequency sweep of
``Re H(jw)`` and the analytic condition; a disagreement between the three is undecided.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["JointSpr", "analytic_margin", "default_psi", "joint_spr", "lyapunov_matrix", "re_h", "realisation",
           "stacked_realisation"]

PSI_FACTOR = 2.0
"""Without a ``psi`` in the spec: ``psi = PSI_FACTOR / K2`` (the SPR margin ``psi K2 - 1`` is then 1)."""


def realisation(K1: float, K2: float, psi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C)`` of ``H(s) = (1 + psi s)/(s^2 + K2 s + K1)`` with the state ``(e, e')``."""
    return (np.array([[0.0, 1.0], [-K1, -K2]]), np.array([[0.0], [1.0]]), np.array([[1.0, psi]]))


def stacked_realisation(K1: Sequence[float], K2: Sequence[float], psi: Sequence[float]
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The block-diagonal realisation of the ``n x n`` transfer ``diag(H_j)`` (diagonal matrix gains)."""
    n = len(K1)
    A, B, C = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, n)), np.zeros((n, 2 * n))
    for j in range(n):
        a, b, c = realisation(K1[j], K2[j], psi[j])
        A[2 * j:2 * j + 2, 2 * j:2 * j + 2], B[2 * j:2 * j + 2, j:j + 1], C[j:j + 1, 2 * j:2 * j + 2] = a, b, c
    return A, B, C


def re_h(K1: float, K2: float, psi: float, w: np.ndarray) -> np.ndarray:
    """``Re H(jw)`` by complex arithmetic (dimensionless times s^2; the sweep's independent evaluation)."""
    s = 1j * np.asarray(w, dtype=float)
    return np.real((1.0 + psi * s) / (s * s + K2 * s + K1))


def analytic_margin(K2: float, psi: float) -> float:
    """``psi K2 - 1``: positive iff ``H`` is SPR (for ``K1, K2, psi > 0``)."""
    return psi * K2 - 1.0


def default_psi(K2: float) -> float:
    """The ``psi`` (s) chosen when the spec gives none: ``PSI_FACTOR / K2``."""
    return PSI_FACTOR / K2


def lyapunov_matrix(K1: float, K2: float, psi: float) -> np.ndarray:
    """The closed-form KYP matrix ``P = [[K2 + psi K1, 1], [1, psi]]`` (``P B = C'``)."""
    return np.array([[K2 + psi * K1, 1.0], [1.0, psi]])


@dataclass(frozen=True)
class JointSpr:
    """One joint's SPR evidence.

    Parameters
    ----------
    K1, K2, psi : float
        Gains (1/s^2, 1/s) and ``psi`` (s).
    analytic : float
        ``psi K2 - 1`` (dimensionless).
    kyp : bool or None
        The KYP check's verdict (certificate core).
    kyp_margin : float or None
        Its normalised margin.
    sweep_min : float
        Smallest ``Re H(jw)`` over the grid (s^2 ... the unit of H).
    sweep_w : float
        Where (rad/s).
    high_frequency : float
        ``w^2 Re H(jw)`` at the grid's top frequency (approaches ``psi K2 - 1``).
    psi_min : float
        ``1/K2`` (s): SPR for every ``psi`` above it.
    """

    K1: float
    K2: float
    psi: float
    analytic: float
    kyp: bool | None
    kyp_margin: float | None
    sweep_min: float
    sweep_w: float
    high_frequency: float
    psi_min: float

    @property
    def sweep_positive(self) -> bool:
        """The sweep's verdict: ``Re H > 0`` on the grid and the high-frequency limit positive."""
        return self.sweep_min > 0 and self.high_frequency > 0

    @property
    def agree(self) -> bool:
        """KYP, sweep and analytic condition give the same answer."""
        return self.kyp is not None and self.kyp == self.sweep_positive == (self.analytic > 0)


def frequency_grid(K1: float, K2: float) -> np.ndarray:
    """0 and 40 points per decade from ``1e-3 min |p|`` to ``1e5 max |p|`` (rad/s), ``p`` the poles."""
    poles = np.abs(np.roots([1.0, K2, K1]))
    lo, hi = float(np.min(poles)) * 1e-3, float(np.max(poles)) * 1e5
    return np.concatenate([[0.0], np.logspace(np.log10(lo), np.log10(hi), int(40 * np.log10(hi / lo)) + 1)])


def joint_spr(K1: float, K2: float, psi: float, *, solver: str = "CLARABEL") -> JointSpr:
    """The three routes for one joint (module docstring)."""
    from designkit.verification.kyp import positive_real

    check = positive_real(*realisation(K1, K2, psi), solver=solver)
    w = frequency_grid(K1, K2)
    re = re_h(K1, K2, psi, w)
    k = int(np.argmin(re))
    return JointSpr(K1=K1, K2=K2, psi=psi, analytic=analytic_margin(K2, psi), kyp=check.passed,
                    kyp_margin=check.margin, sweep_min=float(re[k]), sweep_w=float(w[k]),
                    high_frequency=float(w[-1] ** 2 * re[-1]), psi_min=1.0 / K2)
