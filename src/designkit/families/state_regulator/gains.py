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


def reference_gain(A: np.ndarray, B: np.ndarray, K: np.ndarray, position: int) -> float:
    """``N = -1/(C (A - B K)^-1 B)``, ``C`` selecting state ``position``: unit static gain from ``xD``."""
    Acl = np.asarray(A, float) - np.outer(np.asarray(B, float).reshape(-1), K)
    return float(-1.0 / np.linalg.solve(Acl, np.asarray(B, float).reshape(-1))[position])


def load_offset(A: np.ndarray, B: np.ndarray, D: np.ndarray, K: np.ndarray, position: int) -> float:
    """Steady-state position error per unit of constant disturbance: ``-C (A - B K)^-1 D`` (state unit per
    disturbance unit)."""
    Acl = np.asarray(A, float) - np.outer(np.asarray(B, float).reshape(-1), K)
    return float(-np.linalg.solve(Acl, np.asarray(D, float)[:, 0])[position])
