"""The state regulator's reference gain ``N`` and its offset under a constant load.

**K** is placed by Ackermann's formula (:func:`designkit.synthesis.pole_placement.ackermann`, derivation there);
the tests pin it against python-control's ``acker`` and ``place`` and the poles against ``numpy.linalg.eigvals``.

**N.**  ``u = -K x + N xD`` at rest at ``x*``: ``0 = (A - B K) x* + B N xD``, so the controlled position's static
gain is ``-C (A - B K)^-1 B N`` and ``N = -1 / (C (A - B K)^-1 B)`` makes it 1 (zero steady-state position error
without load).  On the elastic joint without gravity the rest state ``[xD, 0, xD, 0]`` has ``A x* = 0``, so
``N = K1 + K3`` (``u = -K (x - x*)``): the tests check both routes agree.  A load torque ``w`` on the link leaves
``x3 - xD = -C (A - B K)^-1 D w`` (no integral action: the regulator is a proportional state feedback).
"""

from __future__ import annotations

import numpy as np

__all__ = ["load_offset", "reference_gain"]


def _closed(A: np.ndarray, B: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    A = np.asarray(A, float)
    B = np.asarray(B, float).reshape(A.shape[0], -1)
    return A - B @ np.asarray(K, float).reshape(B.shape[1], A.shape[0]), B


def reference_gain(A: np.ndarray, B: np.ndarray, K: np.ndarray, position: int) -> float | np.ndarray:
    """``N = -1/(C (A - B K)^-1 B)``, ``C`` selecting state ``position``: unit static gain from ``xD``.

    With several inputs ``g = C (A - B K)^-1 B`` is a row and ``N = -g^T / (g g^T)``, the least-norm ``N`` with
    ``-g N = 1`` (one entry per input); one input gives a float."""
    Acl, B = _closed(A, B, K)
    g = np.linalg.solve(Acl, B)[position]
    if g.size == 1:
        return float(-1.0 / g[0])
    return -g / float(g @ g)


def load_offset(A: np.ndarray, B: np.ndarray, D: np.ndarray, K: np.ndarray, position: int) -> float:
    """Steady-state position error per unit of constant disturbance: ``-C (A - B K)^-1 D`` (state unit per
    disturbance unit; the first disturbance)."""
    Acl, _ = _closed(A, B, K)
    return float(-np.linalg.solve(Acl, np.asarray(D, float)[:, 0])[position])
