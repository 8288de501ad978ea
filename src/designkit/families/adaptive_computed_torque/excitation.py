"""Persistent excitation of the desired trajectory for the adapted parameters.

The notes (section 4.4, iv) state parameter convergence under ``int_t0^{t0+rho} W'W dt >= alpha I``.  Two
numbers are computed along the *desired* trajectory ``(qD, qD', qD'')`` (a property of the trajectory,
known before the run), with ``W_a`` the adapted parameters' columns of the regressor:

* ``alpha(t)``: the smallest eigenvalue of ``int_{t - T}^{t} W_a' W_a dt`` over a sliding window of length
  ``T`` (:data:`WINDOW_FRACTION` of the run) -- the notes' condition, in (N*m / unit of p)^2 s;
* ``rate``: the slowest rate (1/s) at which the averaged update removes a parameter error.  For a slow
  parameter error ``phi`` the error filter is near its static gain, ``e1 ~ H(0) u = K1^-1 D^-1 W_a phi``,
  so ``phi' ~ -K W_a' D^-1 K1^-1 D^-1 W_a phi``: ``rate = lambda_min(K^1/2 G K^1/2)`` with
  ``G = mean(W_a' D^-1 K1^-1 D^-1 W_a)`` over the last half of the run (``D`` the true inertia).  A
  dimensionless ``rate x duration`` of at least :data:`EFOLDS` is "exciting".

Both are indicators, not theorems: the averaging assumes the parameters move slowly against the error
dynamics.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["EFOLDS", "Excitation", "WINDOW_FRACTION", "excitation"]

WINDOW_FRACTION = 0.25
"""Sliding window of ``alpha(t)``: this fraction of the run."""
EFOLDS = 3.0
"""The trajectory is exciting when the averaged rate times the duration is at least this."""
MAX_POINTS = 2000
"""At most this many samples of the trajectory are evaluated."""


@dataclass(frozen=True)
class Excitation:
    """The excitation indicators of a run's desired trajectory (module docstring).

    Parameters
    ----------
    time : ndarray
        Sample times (s).
    alpha : ndarray
        ``lambda_min`` of the sliding-window Gram matrix at each time (nan before a full window).
    window : float
        The window (s).
    rate : float
        Averaged convergence rate (1/s).
    duration : float
        The run's length (s).
    """

    time: np.ndarray
    alpha: np.ndarray
    window: float
    rate: float
    duration: float

    @property
    def efolds(self) -> float:
        """``rate x duration`` (dimensionless)."""
        return self.rate * self.duration

    @property
    def exciting(self) -> bool:
        """At least :data:`EFOLDS` e-folds of the averaged parameter error in the run."""
        return self.efolds >= EFOLDS

    @property
    def alpha_min(self) -> float:
        """The smallest full-window ``alpha`` (0 when none)."""
        full = self.alpha[np.isfinite(self.alpha)]
        return float(np.min(full)) if full.size else 0.0


def excitation(plant: Any, names: Sequence[str], K1: Sequence[float], gain: Any, time: np.ndarray,
               reference: np.ndarray, scheme: str = "craig") -> Excitation:
    """The indicators of the trajectory ``reference`` (``(N, n, 3)``: position, velocity, acceleration) at ``time``.

    ``scheme="slotine_li"``: ``K1`` is then ``KD`` and the averaged update is ``phi' ~ -K Y' KD^-1 Y phi`` (for slow
    parameter errors ``s ~ KD^-1 Y phi``; ``Y = W`` on the desired trajectory)."""
    t = np.asarray(time, dtype=float)
    ref = np.asarray(reference, dtype=float)
    step = max(1, int(np.ceil(len(t) / MAX_POINTS)))
    t, ref = t[::step], ref[::step]
    idx = [list(plant.robot.parameter_names).index(x) for x in names]
    p = plant.model_parameters()
    W = np.asarray(plant.robot.regressor(ref[:, :, 0], ref[:, :, 1], ref[:, :, 2], p=p), dtype=float)[:, :, idx]
    D = np.asarray(plant.robot.mass_matrix(ref[:, :, 0], p=p), dtype=float)
    dt = np.gradient(t) if len(t) > 1 else np.ones(1)
    gram = np.einsum("kia,kib->kab", W, W) * dt[:, None, None]
    cum = np.concatenate([np.zeros((1, *gram.shape[1:])), np.cumsum(gram, axis=0)])
    window = WINDOW_FRACTION * float(t[-1] - t[0])
    start = np.searchsorted(t, t - window)
    alpha = np.full(len(t), np.nan)
    for k in range(len(t)):
        if t[k] - t[0] >= window - 1e-12:
            alpha[k] = float(np.linalg.eigvalsh(cum[k + 1] - cum[start[k]])[0])
    k1 = np.asarray(K1, dtype=float)
    late = t >= t[0] + 0.5 * (t[-1] - t[0])
    if scheme == "slotine_li":
        G = np.einsum("kia,kib->ab", W[late] / k1[None, :, None], W[late]) / max(int(late.sum()), 1)
    else:
        Wt = np.linalg.solve(D, W)
        G = np.einsum("kia,kib->ab", Wt[late] / k1[None, :, None], Wt[late]) / max(int(late.sum()), 1)
    K = np.asarray(gain, dtype=float)
    L = np.linalg.cholesky(K if K.ndim == 2 else np.diag(K))  # K = L L': the rate is lambda_min(L' G L)
    M = L.T @ G @ L
    rate = float(np.linalg.eigvalsh((M + M.T) / 2)[0])
    return Excitation(time=t, alpha=alpha, window=window, rate=max(rate, 0.0), duration=float(t[-1] - t[0]))
