"""What a self-tuning run recorded, at its sample instants: estimates, regressors, controller coefficients; the
true parameters along the run; the excitation indicator, the Sylvester condition number and the closed-loop
polynomial of the estimated model (NumPy, after the run).

The law records its memory as signals (:mod:`designkit.families.self_tuning.laws`); they are constant
between samples, so a sample instant is where the sample count ``k`` steps.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.families.self_tuning.arx_runs import (
    arx_characteristic_error,
    arx_designed,
    arx_sylvester_condition,
    arx_true_theta,
)
from designkit.families.self_tuning.laws import controller_names
from designkit.families.self_tuning.model import theta_of

__all__ = ["Samples", "characteristic_error", "excitation", "samples", "simulate", "sylvester_condition",
           "true_link_at", "true_theta"]


@dataclass(frozen=True)
class Samples:
    """A run at its sample instants (``M`` samples, ``n`` parameters).

    Attributes
    ----------
    t : ndarray (M,)
        Sample instants (s).
    theta : ndarray (M, n)
        Estimates after each sample's update.
    phi : ndarray (M, n)
        The regressor of each sample.
    eps : ndarray (M,)
        A-priori prediction errors.
    coefs : ndarray (M, 4)
        Controller coefficients in use (``R1, S0, S1, T0`` or ``K1, K2, K3, I``).
    held, bounded : ndarray (M,) of bool
        The design was refused (previous coefficients kept); the covariance bound fired.
    trace : ndarray (M,)
        ``trace P`` after each sample (sum of the recorded diagonal).
    """

    t: np.ndarray
    theta: np.ndarray
    phi: np.ndarray
    eps: np.ndarray
    coefs: np.ndarray
    held: np.ndarray
    bounded: np.ndarray
    trace: np.ndarray


def samples(sim: Any, design: Any) -> Samples:
    """The sample instants of ``sim`` (a run of ``design``'s law)."""
    sig = sim.signals
    n = len(design.data.settings.theta0)
    k = np.asarray(sig["k"], dtype=float)
    idx = np.flatnonzero(np.diff(k, prepend=0.0) > 0.5)
    col = lambda name: np.asarray(sig[name], dtype=float)[idx]  # noqa: E731
    return Samples(t=np.asarray(sim.time, dtype=float)[idx],
                   theta=np.column_stack([col(f"th{i + 1}") for i in range(n)]),
                   phi=np.column_stack([col(f"phi{i + 1}") for i in range(n)]), eps=col("eps"),
                   coefs=np.column_stack([col(c) for c in controller_names(design.data.settings.design,
                                                                              design.data.settings)]),
                   held=col("held") > 0.5, bounded=col("bounded") > 0.5,
                   trace=sum(col(f"P{i + 1}{i + 1}") for i in range(n)))


def true_link_at(spec: Any, plant: Any, t: np.ndarray) -> np.ndarray:
    """``(Km, tau)`` of the true link at each instant ``t`` (``simulation.plant_change`` applied), ``(len(t), 2)``."""
    Km, tau = float(plant.parameter("Km").value), float(plant.parameter("tau").value)
    out = np.tile([Km, tau], (len(t), 1))
    change = spec.simulation.plant_change
    if change is not None:
        after = t >= change.time - 1e-12
        out[after, 0] = change.values.get("Km", Km)
        out[after, 1] = change.values.get("tau", tau)
    return out


def true_theta(spec: Any, plant: Any, design: Any, t: np.ndarray) -> np.ndarray:
    """The exactly discretized parameters of the true link (ARX form: plant) at each instant, in the estimates'
    order (ARX form: NaN where the orders do not hold the sampled plant)."""
    x = design.data
    if x.settings.form == "arx":
        return arx_true_theta(spec, plant, design, t)
    links = true_link_at(spec, plant, np.asarray(t, dtype=float))
    cache: dict[tuple[float, float], tuple[float, ...]] = {}
    rows = []
    for Km, tau in links:
        key = (float(Km), float(tau))
        if key not in cache:
            cache[key] = theta_of(key[0], key[1], x.settings.Ts, x.settings.form)
        rows.append(cache[key])
    return np.asarray(rows, dtype=float).reshape(len(links), len(x.settings.theta0))


def position_models(theta: np.ndarray, Ts: float, form: str) -> np.ndarray:
    """``(a1, a2, b0, b1)`` per row of ``theta`` (vectorised
    :func:`~designkit.families.self_tuning.model.position_model`; the speed form's ``A22`` clipped into (0, 1)
    for the logarithm)."""
    A22 = theta[:, 0]
    if form == "speed":
        a = np.clip(A22, 1e-9, 1 - 1e-12)
        B2 = theta[:, 1]
        A12 = -Ts * (1 - a) / np.log(a)
        B1 = B2 / (1 - a) * (Ts - A12)
        b0, b1 = B1, A12 * B2 - a * B1
    else:
        b0, b1 = theta[:, 1], theta[:, 2]
    return np.column_stack([-(1 + A22), A22, b0, b1])


def sylvester_condition(s: Samples, design: Any) -> np.ndarray:
    """2-norm condition number of the Sylvester matrix of the estimated model at each sample."""
    if design.data.settings.form == "arx":
        return arx_sylvester_condition(s, design)
    m = position_models(s.theta, design.data.settings.Ts, design.data.settings.form)
    M = np.zeros((len(m), 3, 3))
    M[:, 0, 0] = 1.0
    M[:, 0, 1], M[:, 1, 0], M[:, 1, 1], M[:, 1, 2] = m[:, 2], m[:, 0], m[:, 3], m[:, 2]
    M[:, 2, 0], M[:, 2, 2] = m[:, 1], m[:, 3]
    cond = np.full(len(m), np.nan)  # NaN where the estimate is not finite (a diverged run)
    finite = np.all(np.isfinite(M), axis=(1, 2))
    if finite.any():
        with np.errstate(all="ignore"):
            cond[finite] = np.linalg.cond(M[finite])
    return cond


def characteristic_error(s: Samples, design: Any) -> np.ndarray:
    """Per sample, ``max |coef(A R + B S) - coef(Acl)| / max(1, |coef(Acl)|)`` of the estimated model and the
    coefficients in use (pole placement; NaN where the controller was held).  ARX form:
    :func:`~designkit.families.self_tuning.arx_runs.arx_characteristic_error`."""
    x = design.data
    if x.settings.form == "arx":
        return arx_characteristic_error(s, design)
    m = position_models(s.theta, x.settings.Ts, x.settings.form)
    a1, a2, b0, b1 = m.T
    R1, S0, S1 = s.coefs[:, 0], s.coefs[:, 1], s.coefs[:, 2]
    got = np.column_stack([a1 + R1 + b0 * S0, a2 + a1 * R1 + b1 * S0 + b0 * S1, a2 * R1 + b1 * S1])
    want = np.asarray(x.desired, dtype=float)
    err = np.max(np.abs(got - want), axis=1) / max(1.0, float(np.max(np.abs(want))))
    err[s.held] = np.nan
    return err


def excitation(s: Samples, window: int) -> tuple[np.ndarray, np.ndarray]:
    """``(lam_min, normalized)`` per sample over the last ``window`` samples: the smallest eigenvalue of the
    information matrix ``sum phi phi'`` divided by ``window`` (mixed units), and the smallest eigenvalue of the
    same matrix scaled to a unit diagonal (dimensionless, in [0, 1]: 0 when the regressors are collinear or
    one is zero); NaN before a full window."""
    phi = s.phi
    M, n = phi.shape
    with np.errstate(all="ignore"):  # a diverged run's regressors overflow: inf, then NaN below
        csum = np.cumsum(phi[:, :, None] * phi[:, None, :], axis=0)
    lam, norm = np.full(M, np.nan), np.full(M, np.nan)
    if window > M:
        return lam, norm
    with np.errstate(all="ignore"):  # a diverged run's regressors overflow: NaN from there on
        R = csum[window - 1:].copy()
        R[1:] -= csum[: M - window]
        finite = np.all(np.isfinite(R), axis=(1, 2))
        d = np.sqrt(np.clip(np.einsum("kii->ki", R), 1e-300, None))
        C = R / (d[:, :, None] * d[:, None, :])
        zero = np.einsum("kii->ki", R).min(axis=1) <= 1e-300
    lam_w, vals = np.full(len(R), np.nan), np.full(len(R), np.nan)
    if finite.any():
        lam_w[finite] = np.linalg.eigvalsh(R[finite] / window)[:, 0]
        vals[finite] = np.linalg.eigvalsh(C[finite])[:, 0]
    vals[zero & finite] = 0.0
    lam[window - 1:] = lam_w
    norm[window - 1:] = np.where(np.isfinite(vals), np.clip(vals, 0.0, None), np.nan)
    return lam, norm


def simulate(spec: Any, design: Any, plant: Any) -> Any:
    """``design`` in the scenario of ``spec`` on the true ``plant`` (a simulator of its own)."""
    from designkit.simulation.run import build

    return build(spec, design, plant=plant).run()


def designed_response(sim: Any, design: Any, spec: Any, plant: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t, x1, ym)`` at the sample instants: the position and the response the requested loop gives on the true
    link, ``ym = (Am(1)/B(1)) B(z)/Am(z) xD`` (pole placement: ``A R + B S = Am Ao`` cancels the observer), ``B``
    the true sampled link's numerator at each sample; started at rest at the initial position."""
    x = design.data
    s = samples(sim, design)
    idx = np.searchsorted(np.asarray(sim.time, dtype=float), s.t)
    x1 = np.asarray(sim.position, dtype=float)[idx]
    r = np.asarray(sim.desired, dtype=float)[idx, 0]
    Ts = x.settings.Ts
    th = true_theta(spec, plant, design, s.t)
    if x.settings.form == "arx":
        return s.t, x1, arx_designed(r, float(x1[0]), th, design)
    am = np.real(np.poly(np.exp(np.array(x.settings.poles) * Ts)))
    model = position_models(th, Ts, x.settings.form)
    ym = np.empty_like(r)
    y1 = y2 = float(x1[0])
    r1 = r2 = float(x1[0])
    for k in range(len(r)):
        b0, b1 = model[k, 2], model[k, 3]
        g = (am[0] + am[1] + am[2]) / (b0 + b1)
        ym[k] = -am[1] * y1 - am[2] * y2 + g * (b0 * r1 + b1 * r2)
        y1, y2, r1, r2 = ym[k], y1, r[k], r1
    return s.t, x1, ym
