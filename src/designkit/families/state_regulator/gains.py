"""Pole placement for the state regulator: ``K`` by Ackermann's formula, the reference gain ``N``.

**K.**  With ``W = [B, AB, ..., A^(n-1) B]`` invertible (controllable), ``e = [0 ... 0 1] W^-1`` and
``P(s) = prod (s - p_j)`` the monic polynomial of the ``n`` requested poles, ``K = e P(A)`` gives
``det(sI - (A - B K)) = P(s)``.  *Proof* (Cayley-Hamilton in the controllable canonical basis): ``e A^k B = 0`` for
``k < n - 1`` and ``e A^(n-1) B = 1``, so ``T = [e; e A; ...; e A^(n-1)]`` is invertible and puts ``(A, B)`` in
companion form with ``B -> [0 ... 0 1]^T``; there ``K T^-1`` is the row of differences between ``P``'s and ``A``'s
characteristic coefficients, which is what ``e P(A) T^-1`` reads.  Ackermann's formula handles repeated poles
(``scipy.signal.place_poles`` does not for a single input); the tests pin ``K`` against python-control's
``acker`` and ``place`` and the poles against ``numpy.linalg.eigvals``.

**N.**  ``u = -K x + N xD`` at rest at ``x*``: ``0 = (A - B K) x* + B N xD``, so the controlled position's static
gain is ``-C (A - B K)^-1 B N`` and ``N = -1 / (C (A - B K)^-1 B)`` makes it 1 (zero steady-state position error
without load).  On the elastic joint without gravity the rest state ``[xD, 0, xD, 0]`` has ``A x* = 0``, so
``N = K1 + K3`` (``u = -K (x - x*)``): the tests check both routes agree.  A load torque ``w`` on the link leaves
``x3 - xD = -C (A - B K)^-1 D w`` (no integral action: the regulator is a proportional state feedback).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from designkit.errors import SpecError
from designkit.families.vsc.surface import CONTROLLABILITY_TOL, controllability_matrix, controllability_ratio

__all__ = ["COUPLING", "ackermann", "check_controllable", "load_offset", "reference_gain"]

COUPLING = ("KR", "J2", "R2")
"""Elastic-joint parameters of the coupling ``k2 = KR R2^2/J2`` through which the motor reaches the link."""


def ackermann(A: np.ndarray, B: np.ndarray, poles: Sequence[complex]) -> np.ndarray:
    """``K`` (length ``n``) with ``eig(A - B K) = poles`` (module docstring).

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (state units per state unit per second).
    B : numpy.ndarray
        ``n x 1`` (state units per second per input unit).
    poles : sequence of complex
        ``n`` poles (1/s), complex ones in conjugate pairs.

    Returns
    -------
    numpy.ndarray
        ``K`` (input units per state unit).
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    if len(poles) != n:
        raise ValueError(f"needs {n} poles for {n} states, got {len(poles)}")
    W = controllability_matrix(A, B)
    e = np.linalg.solve(W.T, np.eye(n)[n - 1])
    P = np.zeros((n, n))
    for k in np.poly(np.asarray(poles, complex)).real:  # Horner: P(A) = (...(A + a1 I) A + a2 I ...) + an I
        P = P @ A + k * np.eye(n)
    return e @ P


def reference_gain(A: np.ndarray, B: np.ndarray, K: np.ndarray, position: int) -> float:
    """``N = -1/(C (A - B K)^-1 B)``, ``C`` selecting state ``position``: unit static gain from ``xD``."""
    Acl = np.asarray(A, float) - np.outer(np.asarray(B, float).reshape(-1), K)
    return float(-1.0 / np.linalg.solve(Acl, np.asarray(B, float).reshape(-1))[position])


def load_offset(A: np.ndarray, B: np.ndarray, D: np.ndarray, K: np.ndarray, position: int) -> float:
    """Steady-state position error per unit of constant disturbance: ``-C (A - B K)^-1 D`` (state unit per
    disturbance unit)."""
    Acl = np.asarray(A, float) - np.outer(np.asarray(B, float).reshape(-1), K)
    return float(-np.linalg.solve(Acl, np.asarray(D, float)[:, 0])[position])


def check_controllable(spec: object, model: object, box: dict[str, tuple[float, float]],
                       consequence: str = "no state feedback places the poles") -> None:
    """Refuse a plant (nominal, or a vertex of the box) whose ``(A, B)`` is not controllable (``consequence``: what
    that means for the controller, ending the message).

    Raises
    ------
    SpecError
        At ``plant.<name>``: on the elastic joint, the coupling parameter given (``KR``, else ``J2`` or ``R2``)
        that makes the motor unable to move the link; at ``plant.uncertainty.<name>`` for a vertex.
    """
    A, B, _ = model.at()  # type: ignore[attr-defined]
    ratio = controllability_ratio(A, B)
    if ratio < CONTROLLABILITY_TOL:
        plant = spec.plant  # type: ignore[attr-defined]
        if A.shape[0] != 4:
            raise SpecError("plant", f"the plant is not controllable (Hadamard ratio {ratio:.3g})")
        given = [k for k in COUPLING if getattr(plant, k, None) is not None] or ["KR"]
        raise SpecError(f"plant.{given[0]}", f"makes the plant uncontrollable: the motor reaches the link only "
                        f"through the coupling k2 = KR R2²/J2 = {-A[3, 2]:.3g} 1/s², and the controllability "
                        f"matrix [B, AB, A²B, A³B] is singular to {ratio:.3g} (Hadamard ratio, below "
                        f"{CONTROLLABILITY_TOL:g}): {consequence}")
    for name, (lo, hi) in box.items():
        for v in (lo, hi):
            Ab, Bb, _ = model.at({name: v})  # type: ignore[attr-defined]
            if controllability_ratio(Ab, Bb) < CONTROLLABILITY_TOL:
                raise SpecError(f"plant.uncertainty.{name}", f"{name} = {v:g} makes the plant uncontrollable")
