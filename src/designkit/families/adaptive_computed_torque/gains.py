"""The adaptation gain ``K`` as a matrix, and the tracking-convergence settings of the spec section.

``K`` is symmetric positive definite on the adapted parameters ``p`` (``controller.adapt``), three ways:

* ``gain``: diagonal, one number or one per adapted parameter (the default, ``K = diag(gain)``);
* ``gain_matrix``: the full ``m x m`` matrix, refused unless symmetric (to 1e-12 of its largest entry) and positive
  definite (its Cholesky factorisation exists);
* ``combination`` (``T``, ``m x m``, invertible) with ``gain`` the diagonal ``G`` on the combinations ``a = T p``:
  an update diagonal on ``a``, ``a' = G Y_a' s`` with ``Y_p = Y_a T``, is ``p' = T^-1 G T^-T Y_p' s``, so
  ``K = T^-1 G T^-T`` and ``p' K^-1 p = a' G^-1 a`` (the Lyapunov function written in the combinations).

``convergence`` (:class:`ConvergenceSpec`): how ``tracking_convergence`` judges that the error goes to zero
(:mod:`.checks`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.spec.fields import Finite, Section
from designkit.spec.ranges import Ranged

__all__ = ["ConvergenceSpec", "SYMMETRY", "check_matrix", "gain_parts"]

SYMMETRY = 1e-12
"""``gain_matrix`` is symmetric when ``|K - K'|`` is at most this share of its largest entry."""
CONDITION = 1e12
"""Largest condition number of ``combination`` (and of ``K``) accepted."""


class ConvergenceSpec(Section):
    """How the tracking error's convergence is judged (``controller.convergence``).

    ``window`` (s, 1e-6 to 1e9): the trailing window of the running maximum of ``|e_j|`` (default: the reference's
    period when it is a sine and the run holds two periods, else a tenth of the run); ``tolerance`` (0 to 1,
    default 0): the relative rise allowed from one window's maximum to the next; ``floor`` (rad, 1e-15 to 1,
    default 1e-6): an error whose running maximum is below it counts as converged.
    """

    window: Ranged(1e-6, 1e9, "s") | None = None
    tolerance: Ranged(0.0, 1.0, "") = 0.0
    floor: Ranged(1e-15, 1.0, "rad") = 1e-6


def check_matrix(value: Any, m: int, key: str) -> np.ndarray:
    """``value`` as an ``m x m`` float matrix (``ValueError`` naming ``key[i]`` when it is not one)."""
    if not isinstance(value, list | tuple) or len(value) != m:
        raise ValueError(f"{key}: must be {m} rows of {m} numbers (one per adapted parameter), got "
                         f"{len(value) if isinstance(value, list | tuple) else type(value).__name__}")
    for i, row in enumerate(value):
        if not isinstance(row, list | tuple) or len(row) != m:
            raise ValueError(f"{key}[{i}]: must be a row of {m} numbers, got "
                             f"{len(row) if isinstance(row, list | tuple) else type(row).__name__}")
    return np.asarray(value, dtype=float)


def _spd(K: np.ndarray, key: str) -> None:
    scale = float(np.max(np.abs(K))) if K.size else 0.0
    asym = float(np.max(np.abs(K - K.T))) if K.size else 0.0
    if asym > SYMMETRY * max(scale, 1e-300):
        i, j = np.unravel_index(int(np.argmax(np.abs(K - K.T))), K.shape)
        raise ValueError(f"{key}: must be symmetric, but [{i}][{j}] = {K[i, j]:g} and [{j}][{i}] = {K[j, i]:g}")
    try:
        np.linalg.cholesky((K + K.T) / 2)
    except np.linalg.LinAlgError:
        eig = np.linalg.eigvalsh((K + K.T) / 2)
        raise ValueError(f"{key}: must be positive definite (its Cholesky factorisation fails; smallest eigenvalue "
                         f"{eig[0]:.4g})") from None
    eig = np.linalg.eigvalsh((K + K.T) / 2)
    if eig[-1] > CONDITION * eig[0]:
        raise ValueError(f"{key}: condition number {eig[-1] / eig[0]:.3g} is above {CONDITION:g}")


def gain_parts(gain: Any, gain_matrix: Any, combination: Any, m: int, gain_given: bool
               ) -> tuple[tuple[float, ...], tuple[tuple[float, ...], ...] | None, tuple[tuple[float, ...], ...] | None,
                          tuple[float, ...]]:
    """``(diag K, K or None, T or None, G on a)`` from the section's ``gain``, ``gain_matrix`` and ``combination``
    (module docstring); ``ValueError`` naming the key on a bad entry."""
    gains = [float(g) for g in gain] if isinstance(gain, list | tuple) else [float(gain)]
    if len(gains) not in (1, m):
        raise ValueError(f"gain: must be one number or {m} (one per adapted parameter), got {len(gains)}")
    diagonal = tuple(gains * m if len(gains) == 1 else gains)
    if gain_matrix is not None:
        if gain_given:
            raise ValueError("gain_matrix: give either gain (diagonal) or gain_matrix, not both")
        if combination is not None:
            raise ValueError("combination: takes the diagonal gain on the combinations (gain), not gain_matrix")
        K = check_matrix(gain_matrix, m, "gain_matrix")
        _spd(K, "gain_matrix")
        K = (K + K.T) / 2
        return tuple(float(x) for x in np.diag(K)), tuple(tuple(float(x) for x in r) for r in K), None, ()
    if combination is None:
        return diagonal, None, None, ()
    T = check_matrix(combination, m, "combination")
    sv = np.linalg.svd(T, compute_uv=False)
    if not sv[-1] > 0 or sv[0] > CONDITION * sv[-1]:
        raise ValueError("combination: must be invertible (the combinations a = T p must determine the adapted "
                         f"parameters), its condition number is {sv[0] / sv[-1] if sv[-1] > 0 else float('inf'):.3g}")
    Tinv = np.linalg.inv(T)
    K = Tinv @ np.diag(diagonal) @ Tinv.T
    K = (K + K.T) / 2
    _spd(K, "combination")
    return (tuple(float(x) for x in np.diag(K)), tuple(tuple(float(x) for x in r) for r in K),
            tuple(tuple(float(x) for x in r) for r in T), diagonal)


Matrix = list[list[Finite]]
"""The YAML form of ``gain_matrix`` and ``combination``: rows of numbers."""
