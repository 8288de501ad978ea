"""What a run of the ARX self-tuner recorded, read after the run (NumPy): the true plant's exact ARX parameters along
the run, the Sylvester matrix's condition number and the characteristic polynomial of the estimated model at each
sample, the poles of the true sampled loop under a controller, and the response the requested loop gives.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.families.self_tuning.arx import Orders, link_matrices, polynomials, sylvester, true_arx

__all__ = ["arx_characteristic_error", "arx_designed", "arx_sylvester_condition", "arx_true_loop_poles",
           "arx_true_theta", "controller_polynomials", "plant_matrices", "wanted_poles"]


def _orders(design: Any) -> Orders:
    return Orders(*design.data.settings.orders)


def plant_matrices(plant: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(F, G, C, D)`` of a link or a linear plant: its first input to its first output."""
    if plant.kind == "link":
        return link_matrices(float(plant.parameter("Km").value), float(plant.parameter("tau").value))
    A, B, C, D = plant.matrices()
    return A, np.asarray(B)[:, 0], np.asarray(C)[:1, :], np.asarray(D)[:1, :1]


def arx_true_theta(spec: Any, plant: Any, design: Any, t: np.ndarray) -> np.ndarray:
    """The true plant's exact ARX parameters at each instant ``t`` (``simulation.plant_change`` applied); rows of
    NaN where the orders do not hold the sampled plant."""
    st = design.data.settings
    o = _orders(design)
    t = np.asarray(t, dtype=float)
    change = spec.simulation.plant_change

    def theta(p: Any) -> np.ndarray:
        th = true_arx(*plant_matrices(p), st.Ts, o)
        return th if th is not None else np.full(o.count, np.nan)

    before = theta(plant)
    out = np.tile(before, (len(t), 1))
    if change is not None:
        after = t >= change.time - 1e-12
        if after.any():
            out[after] = theta(plant.with_params(**dict(change.values)))
    return out


def _matrices(theta: np.ndarray, design: Any) -> np.ndarray:
    """Per row of ``theta``: the Sylvester matrix the design solves."""
    st = design.data.settings
    o = _orders(design)
    m, deg_ao = len(st.am) - 1, len(st.ao) - 1
    rp = m + deg_ao - o.n
    mats = []
    for row in theta:
        A, B = polynomials(list(row), o)
        mats.append(np.asarray(sylvester(A, [B[0]] if st.cancel else B, rp, o.n - 1), dtype=float))
    return np.asarray(mats)


def arx_sylvester_condition(s: Any, design: Any) -> np.ndarray:
    """2-norm condition number of the Sylvester matrix of the estimated model at each sample (NaN where an estimate
    is not finite)."""
    M = _matrices(s.theta, design)
    cond = np.full(len(M), np.nan)
    finite = np.all(np.isfinite(M), axis=(1, 2))
    if finite.any():
        with np.errstate(all="ignore"):
            cond[finite] = np.linalg.cond(M[finite])
    return cond


def _split(coefs: np.ndarray, design: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from designkit.families.self_tuning.arx_law import degrees

    nr, ns, _ = degrees(design.data.settings)
    return (np.r_[1.0, coefs[:nr]], np.asarray(coefs[nr:nr + ns + 1]), np.asarray(coefs[nr + ns + 1:]))


def controller_polynomials(coefs: np.ndarray, design: Any) -> dict[str, list[float | None]]:
    """``{"R": ..., "S": ..., "T": ...}`` (highest power first) from one sample's recorded coefficients."""
    def num(v: float) -> float | None:
        return float(v) if np.isfinite(v) else None

    return {k: [num(v) for v in p] for k, p in zip("RST", _split(np.asarray(coefs, dtype=float), design),
                                                      strict=True)}


def arx_characteristic_error(s: Any, design: Any) -> np.ndarray:
    """Per sample, ``max |coef(A R + B S) - coef(wanted)| / max(1, |coef(wanted)|)``, wanted ``Am Ao`` (zeros kept)
    or ``B+ Am Ao`` (zeros cancelled, ``B+`` the estimated ``B/b0``); NaN where the controller was held or an
    estimate is not finite."""
    st = design.data.settings
    o = _orders(design)
    amao = np.polymul(st.am, st.ao)
    err = np.full(len(s.t), np.nan)
    for k in range(len(s.t)):
        if s.held[k] or not np.all(np.isfinite(s.theta[k])) or not np.all(np.isfinite(s.coefs[k])):
            continue
        A, B = polynomials(list(s.theta[k]), o)
        R, S, _ = _split(s.coefs[k], design)
        got = np.polyadd(np.polymul(A, R), np.polymul(B, S))
        want = np.polymul(np.asarray(B) / B[0], amao) if st.cancel else amao
        n = max(len(got), len(want))
        got, want = np.r_[np.zeros(n - len(got)), got], np.r_[np.zeros(n - len(want)), want]
        err[k] = float(np.max(np.abs(got - want)) / max(1.0, float(np.max(np.abs(want)))))
    return err


def arx_true_loop_poles(design: Any, theta_true: np.ndarray, coefs: np.ndarray) -> np.ndarray:
    """Poles ``z`` of the true sampled plant (exact ARX ``theta_true``) under ``R u = T r - S y``."""
    A, B = polynomials(list(np.asarray(theta_true, dtype=float)), _orders(design))
    R, S, _ = _split(np.asarray(coefs, dtype=float), design)
    return np.roots(np.polyadd(np.polymul(A, R), np.polymul(B, S)))


def wanted_poles(design: Any, theta: np.ndarray) -> np.ndarray:
    """The poles ``z`` the design asks for: the roots of ``Am Ao`` (and, zeros cancelled, of ``B`` of ``theta``)."""
    st = design.data.settings
    z = list(np.roots(np.polymul(st.am, st.ao)))
    if st.cancel:
        _, B = polynomials(list(theta), _orders(design))
        z += list(np.roots(B))
    return np.asarray(z, dtype=complex)


def arx_designed(r: np.ndarray, y0: float, theta: np.ndarray, design: Any) -> np.ndarray:
    """The response the requested loop gives at the samples: ``ym = t0 B(q)/Am(q) r`` (zeros kept, ``B`` of the true
    plant ``theta`` at each sample, ``t0 = Am(1)/B(1)``) or ``Am(1)/Am(q) r`` (zeros cancelled); at rest at ``y0``
    before the first sample."""
    st = design.data.settings
    o = _orders(design)
    am = np.asarray(st.am, dtype=float)
    m = len(am) - 1
    ym = np.empty(len(r))
    past_y = [float(y0)] * m
    past_r = [float(y0)] * (m + 1)
    for k in range(len(r)):
        past_r = [float(r[k]), *past_r[:-1]]
        if st.cancel:
            num = np.r_[np.zeros(m), am.sum()]
        else:
            _, B = polynomials(list(theta[k]), o)
            B = np.asarray(B, dtype=float)
            num = np.r_[np.zeros(m + 1 - len(B)), B * am.sum() / B.sum()]
        # Am(q) ym = num(q) r, divided by q^m
        ym[k] = -float(np.dot(am[1:], past_y)) + float(np.dot(num, past_r))
        past_y = [ym[k], *past_y[:-1]]
    return ym
