"""The sliding surface ``sigma = c x`` from requested sliding poles.

The plant's linear model ``x' = A(p) x + B(p) u + D(p) d`` at rest, symbolic in its parameters, and the
controllability of ``(A, B)`` are :mod:`designkit.synthesis.state_space`'s.

**c from the sliding poles** (an Ackermann formula for the sliding surface,
:func:`~designkit.synthesis.pole_placement.ackermann_row`).  Let ``W = [B, AB, ..., A^(n-1) B]``
(controllable: ``W`` invertible), ``e = [0 ... 0 1] W^-1`` (so ``e A^k B = 0`` for ``k < n-1`` and
``e A^(n-1) B = 1``) and ``P(s) = prod (s - p_j)`` the monic polynomial of the ``n - 1`` requested poles.  Then

    c = e P(A)        gives        c B = e A^(n-1) B = 1,

and on ``c x = 0`` the motion under the equivalent control ``u_eq = -(cB)^-1 c A x`` has exactly the poles
``p_j``.  *Proof.*  For any ``lambda`` the state feedback ``u = -(cB)^-1 c (A - lambda I) x`` gives
``sigma' = c A x + c B u = lambda sigma``; it is Ackermann's gain ``e Q(A)`` of the polynomial
``Q(s) = P(s)(s - lambda)`` (``e Q(A) = c (A - lambda I)``), so the closed loop's poles are the roots of ``Q``:
``lambda`` (the motion of ``sigma``) and the ``p_j``.  The subspace ``c x = 0`` is invariant under that loop and
the loop equals ``x' = (I - B c/(cB)) A x`` on it, the sliding motion; so its poles are the ``p_j``.  (The tests
check it independently: the eigenvalues of ``N^+ (I - B c/(cB)) A N`` with ``N`` a basis of ``ker c``, numpy.)

**Normalisation.**  ``c`` is scaled so that its entry on the state the input drives (the single nonzero entry of
``B``: the motor speed ``x2`` of the elastic joint, the link speed ``x2``) is 1; then ``cB > 0``, the orientation
the gain conditions are written for.  Without such an entry (a general ``B``) ``c`` is scaled to ``cB = 1``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from designkit.synthesis.pole_placement import ackermann_row
from designkit.synthesis.state_space import CONTROLLABILITY_TOL, controllability_ratio

__all__ = ["drive_index", "reduced_poles", "sliding_surface"]


def drive_index(B: np.ndarray) -> int | None:
    """The state the input drives, when ``B`` has exactly one nonzero entry; else None."""
    nz = np.flatnonzero(np.asarray(B, float).reshape(-1))
    return int(nz[0]) if nz.size == 1 else None


def sliding_surface(A: np.ndarray, B: np.ndarray, poles: Sequence[complex]) -> np.ndarray:
    """``c`` (row, length ``n``) whose sliding motion on ``c x = 0`` has the ``n - 1`` poles ``poles``.

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (1/s, 1/s^2 by row).
    B : numpy.ndarray
        ``n x 1``.
    poles : sequence of complex
        ``n - 1`` poles (1/s), complex ones in conjugate pairs.

    Returns
    -------
    numpy.ndarray
        ``c`` normalised as the module docstring says (``cB > 0``).

    Raises
    ------
    ValueError
        Wrong number of poles, or ``(A, B)`` uncontrollable
        (:data:`~designkit.synthesis.state_space.CONTROLLABILITY_TOL`).
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    B = np.asarray(B, float).reshape(n)
    if len(poles) != n - 1:
        raise ValueError(f"needs {n - 1} sliding poles for {n} states, got {len(poles)}")
    if controllability_ratio(A, B) < CONTROLLABILITY_TOL:
        raise ValueError("(A, B) is not controllable")
    c = ackermann_row(A, B, poles)
    k = drive_index(B)
    scale = c[k] if k is not None and c[k] != 0 else c @ B
    c = c / scale
    if c @ B < 0:  # cannot happen with a drive index (c_k = 1, B_k > 0 there); kept for a general B
        c = -c
    return c


def reduced_poles(A: np.ndarray, B: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Poles of the sliding motion on ``c x = 0``: eigenvalues of ``N^+ (I - B c/(cB)) A N``, ``N`` an orthonormal
    basis of ``ker c`` (numpy SVD), sorted by real part."""
    A = np.asarray(A, float)
    n = A.shape[0]
    B = np.asarray(B, float).reshape(n, 1)
    c = np.asarray(c, float).reshape(1, n)
    _, _, vt = np.linalg.svd(c)
    N = vt[1:].T
    proj = np.eye(n) - B @ c / float((c @ B)[0, 0])
    eig = np.linalg.eigvals(N.T @ proj @ A @ N)
    return eig[np.lexsort((eig.imag, eig.real))]
