"""The robot form's run recomputed from the record (the true arm is known in simulation): the samples, the regressors
the identifier formed, the true base parameters, the estimation errors, ``V`` and the sampled inequality it obeys,
and the two-point information matrices.

Everything here is computed from the recorded state, command and estimates and the model layer's base regressor at
the true arm's kinematics, not read from the law's internals: the regressor at sample ``k`` is
``Y1 = Wb((q(k-1) + q(k))/2, (qd(k-1) + qd(k))/2, (qd(k) - qd(k-1))/Ts)`` with the command ``u(k-1)``, and ``Y2``
the same ``N = D/Ts`` samples earlier.  With ``thetah`` the estimates before the sample's update and ``theta`` the
true identified parameters, the torque error splits into ``eps = e + r``, ``e = Y (theta - thetah)`` (what the
update can remove) and ``r = u - Wk betak - Y theta`` (what the sampled reconstruction and the known parameters leave,
O(Ts^2) of the torque for a fixed arm).  The update ``thetah+ = thetah + Ts Gamma Ybar' eps`` gives exactly
``V+ - V = -2 Ts e'(e + r) + Ts^2 (e + r)' Ybar Gamma Ybar' (e + r)`` (``Ybar`` the two regressors stacked), hence::

    V+ - V <= Ts (-2 |e|^2 + 2 |e| |r| + s (|e| + |r|)^2),   s = Ts lambda_max(Gamma^1/2 Phi Gamma^1/2),

``Phi = Y1' Y1 + Y2' Y2``: ``V`` cannot increase while ``s < 2`` and ``|e| >= x* |r|``,
``x* = ((1 + s) + sqrt((1 + s)^2 + s (2 - s)))/(2 - s)`` (``x* = 1`` as ``s -> 0``); inside that band it rises by at
most ``Ts |r|^2 ((1 + s)^2/(2 - s) + s)`` per sample.  With the law's normalisation ``m2``
(:mod:`~designkit.families.sliding_mode_identification.arm_law`) ``Ts`` reads ``Ts/m2`` and ``s`` reads ``s/m2``
(at most ``sigma = 1``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.families.sliding_mode_identification.arm import base_of, true_beta
from designkit.families.sliding_mode_identification.arm_design import regressor_rows
from designkit.families.sliding_mode_identification.arm_law import STEP_LIMIT, ArmIdentifier

__all__ = ["ArmRun", "arm_run", "band_factor", "contraction", "counted", "segment_rate", "segments_of", "window_rates"]


def band_factor(s: np.ndarray) -> np.ndarray:
    """``x*(s)``: ``V`` does not increase at a sample where ``|e| >= x* |r|`` (module docstring); inf for ``s >= 2``."""
    s = np.asarray(s, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        x = ((1 + s) + np.sqrt((1 + s) ** 2 + s * (2 - s))) / (2 - s)
    return np.where(s < 2, x, np.inf)


@dataclass(frozen=True)
class ArmRun:
    """The recomputed run, one row per sample (``K`` samples, ``n`` joints, ``p`` identified parameters).

    Attributes
    ----------
    ident : ArmIdentifier
        The identifier's settings.
    t : ndarray (K,)
        Sample times (s).
    rows : ndarray (K,)
        Record index of each sample.
    theta : ndarray (K, p)
        True identified parameters at each sample (SI units).
    estimate : ndarray (K, p)
        Estimates after each sample's update.
    V : ndarray (K,)
        ``(theta - thetah)' Gamma^-1 (theta - thetah)`` (N^2*m^2*s).
    dV, bound : ndarray (K,)
        ``V(k) - V(k-1)`` and its bound (module docstring); 0 at the first sample.
    e, r : ndarray (K,)
        ``|e|`` and ``|r|`` of the two time points stacked (N*m).
    step : ndarray (K,)
        The update's sampled step ``s = Ts lambda_max(Gamma^1/2 Phi Gamma^1/2)/m2`` (below 2: ``V`` decreases).
    raw_step : ndarray (K,)
        ``Ts lambda_max(Gamma^1/2 Phi Gamma^1/2)``, the step without the normalisation.
    m2 : ndarray (K,)
        The normalisation ``max(1, Ts tr(Gamma Phi)/sigma)`` recomputed from the regressors.
    phi : ndarray (K, p, p)
        The two-point information matrix ``Phi`` (identified columns), zero where a time point is not counted.
    eps_gap : float
        Largest difference between the recorded torque errors and their recomputation (N*m).
    true_accel_error : ndarray (K, n)
        The observer's model term minus the true arm's acceleration at the sample's state and command (rad/s^2).
    """

    ident: ArmIdentifier
    t: np.ndarray
    rows: np.ndarray
    theta: np.ndarray
    estimate: np.ndarray
    V: np.ndarray
    dV: np.ndarray
    bound: np.ndarray
    e: np.ndarray
    r: np.ndarray
    step: np.ndarray
    raw_step: np.ndarray
    m2: np.ndarray
    phi: np.ndarray
    eps_gap: float
    true_accel_error: np.ndarray


def segments_of(spec: Any, t: np.ndarray, window: float, Ts: float) -> list[np.ndarray]:
    """Masks of the samples where the arm and both time points see one arm: ``[0, T)`` and
    ``[T + D + 2 Ts, end]`` around a ``simulation.plant_change`` at ``T`` (the link's rule)."""
    change = spec.simulation.plant_change
    if change is None or float(change.time) > t[-1]:
        return [np.ones(t.shape, dtype=bool)]
    T = float(change.time)
    return [m for m in (t < T, t >= T + window + 2 * Ts) if m.any()]


def _true_plant_at(spec: Any, plant: Any, t: np.ndarray) -> list[tuple[np.ndarray, Any]]:
    change = spec.simulation.plant_change
    if change is None:
        return [(np.ones(t.shape, dtype=bool), plant)]
    after = t >= float(change.time)
    return [(~after, plant), (after, plant.with_params(**change.values))]


def arm_run(design: Any, spec: Any, plant: Any, sim: Any) -> ArmRun:
    """The run of a robot-form design recomputed from its record (module docstring); ``plant`` the true arm."""
    ident = design.data.identifier
    base = base_of(design.plant)
    n, N, Ts = ident.n, ident.samples, ident.Ts
    cols = list(ident.columns)
    time = np.asarray(sim.time, dtype=float)
    stride = max(1, int(round(Ts / float(time[1] - time[0])))) if len(time) > 1 else 1
    rows = np.arange(0, len(time), stride)
    t = time[rows]
    state = np.asarray(sim.state, dtype=float)[rows]
    q, qd = state[:, list(sim.positions)], state[:, list(sim.velocities)]
    u = np.asarray(sim.u_command, dtype=float)[rows]
    est = np.stack([np.asarray(sim.signals[f"{x}_hat"], dtype=float)[rows] for x in ident.names], axis=1)
    theta = np.zeros_like(est)
    beta_true = np.zeros((len(t), len(base.names)))
    for mask, arm in _true_plant_at(spec, plant, t):
        beta_true[mask] = true_beta(base, arm)
    theta = beta_true[:, cols]
    K = len(t)
    prev = np.concatenate([[0], np.arange(K - 1)])
    qm, qdm = 0.5 * (q[prev] + q), 0.5 * (qd[prev] + qd)
    acc = (qd - qd[prev]) / Ts
    up = u[prev]
    Y = regressor_rows(base.W_base, qm, qdm, acc)  # (K, n, b)
    known = np.zeros(len(base.names))
    for c, v in ident.known:
        known[c] = v
    w1 = (np.arange(K) >= 1).astype(float)
    w2 = (np.arange(K) >= N + 1).astype(float)
    before = np.concatenate([np.asarray(ident.initial, dtype=float)[None, :], est[:-1]])
    Yi = Y[:, :, cols]
    eps = up - np.einsum("kib,b->ki", Y, known) - np.einsum("kip,kp->ki", Yi, before)  # with today's estimates
    res = up - np.einsum("kib,b->ki", Y, known) - np.einsum("kip,kp->ki", Yi, theta)
    delayed = np.concatenate([np.zeros(N, dtype=int), np.arange(K - N)]) if K > N else np.zeros(K, dtype=int)
    Y2 = Yi[delayed]
    eps2 = (up[delayed] - np.einsum("kib,b->ki", Y[delayed], known) - np.einsum("kip,kp->ki", Y2, before))
    res2 = (up[delayed] - np.einsum("kib,b->ki", Y[delayed], known) - np.einsum("kip,kp->ki", Y2, theta))
    eps, res, eps2, res2 = eps * w1[:, None], res * w1[:, None], eps2 * w2[:, None], res2 * w2[:, None]
    e_vec = np.concatenate([eps - res, eps2 - res2], axis=1)
    r_vec = np.concatenate([res, res2], axis=1)
    gamma = np.asarray(ident.gamma, dtype=float)
    tilde = theta - est
    V = np.einsum("kp,p,kp->k", tilde, 1.0 / gamma, tilde)
    tilde_before = theta - before
    V_before = np.einsum("kp,p,kp->k", tilde_before, 1.0 / gamma, tilde_before)
    dV = V - V_before
    Ybar = np.concatenate([Yi * w1[:, None, None], Y2 * w2[:, None, None]], axis=1)  # (K, 2n, p)
    phi = np.einsum("kip,kiq->kpq", Ybar, Ybar)
    finite = np.all(np.isfinite(Ybar), axis=(1, 2))
    raw = np.full(K, np.inf)  # a diverged run: no step below 2 (the checks fail and say so)
    if finite.any():
        raw[finite] = Ts * np.linalg.eigvalsh(np.einsum("kip,p,kjp->kij", Ybar[finite], gamma, Ybar[finite]))[:, -1]
    m2 = np.maximum(1.0, Ts * np.einsum("kip,p->k", Ybar**2, gamma) / STEP_LIMIT)
    step = raw / m2
    e, r = np.linalg.norm(e_vec, axis=1), np.linalg.norm(r_vec, axis=1)
    bound = (Ts / m2) * (-2 * e**2 + 2 * e * r + step * (e + r) ** 2)
    recorded = np.stack([np.asarray(sim.signals[f"eps1_{j + 1}"], dtype=float)[rows] for j in range(n)], axis=1)
    recorded2 = np.stack([np.asarray(sim.signals[f"eps2_{j + 1}"], dtype=float)[rows] for j in range(n)], axis=1)
    gap = float(max(np.max(np.abs(recorded - eps), initial=0.0), np.max(np.abs(recorded2 - eps2), initial=0.0)))
    model = np.stack([np.asarray(sim.signals[f"model{j + 1}"], dtype=float)[rows] for j in range(n)], axis=1)
    true_acc = np.zeros_like(model)
    for mask, arm in _true_plant_at(spec, plant, t):
        if mask.any():
            true_acc[mask] = np.asarray(arm.robot.forward_dynamics(q[mask], qd[mask], u[mask],
                                                                   p=arm.model_parameters()), dtype=float)
    return ArmRun(ident, t, rows, theta, est, V, dV, bound, e, r, step, raw, m2, phi, gap, model - true_acc)


def contraction(run: ArmRun, idx: np.ndarray) -> float:
    """``kappa``: the largest ``V(end)/V(start)`` the update can leave over the consecutive samples ``idx``, for any
    initial error and without the residual ``r``: ``||A_K ... A_1||_2^2`` with
    ``A_k = I - (Ts/m2_k) Gamma^1/2 Phi_k Gamma^1/2`` (the update in the coordinates ``Gamma^-1/2 theta~``, where
    ``V`` is the squared norm).  1 when some direction of the parameters is not excited over the samples; for one
    sample with ``p <= 2n`` parameters, ``kappa < 1`` exactly when ``Phi`` is invertible (the link's determinant)."""
    root = np.sqrt(np.asarray(run.ident.gamma, dtype=float))
    p = root.size
    T = np.eye(p)
    with np.errstate(all="ignore"):  # a diverged run's regressors overflow: no contraction (inf)
        for k in idx:
            A = np.eye(p) - (run.ident.Ts / run.m2[k]) * (root[:, None] * run.phi[k] * root[None, :])
            T = A @ T
    if not np.all(np.isfinite(T)):
        return math.inf
    return float(np.linalg.norm(T, 2) ** 2) if idx.size else 1.0


def _slowest_rate(run: ArmRun, idx: np.ndarray, root: np.ndarray) -> float:
    """``lambda_min(Gamma^1/2 Gbar Gamma^1/2)`` (1/s) over the samples ``idx``; NaN when the regressors of a
    diverged run are not finite there."""
    with np.errstate(all="ignore"):
        G = (run.phi[idx] / run.m2[idx, None, None]).mean(axis=0)
        H = root[:, None] * G * root[None, :]
    return float(np.linalg.eigvalsh(H)[0]) if np.all(np.isfinite(H)) else math.nan


def counted(run: ArmRun, mask: np.ndarray) -> np.ndarray:
    """The samples of ``mask`` where both time points are counted (after the first ``D`` plus a sample)."""
    return np.flatnonzero(mask & (np.arange(len(run.t)) >= run.ident.samples + 1))


def window_rates(run: ArmRun, mask: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(ends s, kappa, rate 1/s)`` over consecutive windows of ``length`` s of the counted samples of ``mask``:
    the contraction :func:`contraction` of each window and ``lambda_min(Gamma^1/2 Gbar Gamma^1/2)/m2``, ``Gbar`` the
    mean two-point information matrix over it (the slowest rate of the averaged update)."""
    idx = counted(run, mask)
    per = max(1, int(round(length / run.ident.Ts)))
    root = np.sqrt(np.asarray(run.ident.gamma, dtype=float))
    ends, kappa, rate = [], [], []
    for start in range(0, idx.size - per + 1, per):
        block = idx[start:start + per]
        ends.append(float(run.t[block[-1]]))
        kappa.append(contraction(run, block))
        rate.append(_slowest_rate(run, block, root))
    return np.asarray(ends), np.asarray(kappa), np.asarray(rate)


def segment_rate(run: ArmRun, mask: np.ndarray) -> tuple[float, float, float]:
    """``(kappa, rate 1/s, span s)`` over the counted samples of ``mask``: the contraction of the whole segment,
    the slowest rate of the averaged update (as :func:`window_rates`) and the span."""
    idx = counted(run, mask)
    if idx.size == 0:
        return 1.0, 0.0, 0.0
    root = np.sqrt(np.asarray(run.ident.gamma, dtype=float))
    rate = _slowest_rate(run, idx, root)
    return contraction(run, idx), (rate if math.isfinite(rate) else 0.0), float(run.t[idx[-1]] - run.t[idx[0]])
