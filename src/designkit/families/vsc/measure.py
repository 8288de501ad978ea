"""What a run of the variable structure regulator shows: reaching, the hold band, the sliding poles, chattering,
the equivalent control (theorem 1) and the offset an unmatched perturbation leaves (theorem 4).

Only the :class:`~designkit.simulation.result.SimulationResult` (time, reference, states, command, the recorded
``sigma`` and ``u_eq``, the perturbation) and the design's numbers are read.  With ``x~ = x - x*(xD)`` the error
state (``x*`` the rest state at the reference):

* **hold band**: one held step moves ``sigma`` by at most ``h S(x~)`` with
  ``S(x~) = cB_max (sum_i G_i |x~_i| + delta) + |cD|_max d_bar`` and ``G_i = max(l_i,max - alpha_i,
  beta_i - l_i,min)`` (``sigma' = cB (sum_i (psi_i - l_i) x~_i - delta sign sigma) + cD d``, every factor bounded
  over the box).  The band at sample ``k`` is ``h`` times the largest ``S`` over the last ``WINDOW`` samples (the
  state moves little over them), or the boundary layer ``epsilon``.  **Reaching**: the first sample with
  ``|sigma| <= band``; the **invariant** is ``|sigma| <= band`` at every later sample of the segment.
* **sliding poles**: the error state without the driven state (``z``: ``x1, x3, x4`` of the elastic joint, ``x1``
  of the link; ``u`` does not enter their equations, and on ``sigma = 0`` they are the reduced-order system) is
  fitted on the sliding samples by least squares ``z' = F z + k sigma + g d`` (exact for the linear plant: the
  reduced system driven by the residual ``sigma`` of the chattering and by ``d``), in integral form over two
  steps (trapezoid rule; samples across a jump of ``d`` left out); ``eig F`` against the requested poles (the
  reduced system's poles at the nominal plant).
* **chattering**: sign changes of ``sigma`` per second after reaching, total variation of ``u``.
* **equivalent control**: ``u_eq = -(cB)^-1 (c A x~ + c D d)`` with the run's plant (``settings["plant"]``, then
  the changed one after a ``plant_change``) and perturbation, and the
  fraction of the sliding samples where it lies in ``[min(u+, u-), max(u+, u-)]`` (theorem 1), ``u+`` and
  ``u-`` the law's two controls at ``sigma = 0+`` and ``0-``.
* **matching** (theorem 4): ``rank [B D] == rank B``; the offset of the sliding motion under a constant ``d``,
  ``x~_ss`` solving ``(I - B c/cB)(A x~ + D d) = 0``, ``c x~ = 0``, against the last sample of the run, within
  what the chattering's residual ``|sigma| <= band`` over the last 5 % of the run can move it (plus 2 %).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.families.vsc.data import VscData

__all__ = ["VscRun", "WINDOW", "measure", "static_offset"]

WINDOW = 10
"""Samples over which the hold band takes the largest ``S``."""
MIN_FIT_SAMPLES = 40


@dataclass(frozen=True)
class VscRun:
    """The measurements of one run (module docstring); times in s."""

    hold: float
    reach: int | None
    reaching_time: float | None
    worst_ratio: float | None
    worst_at: float | None
    poles: tuple[complex, ...] | None
    fit_samples: int
    switches: int
    sliding_time: float
    switching_frequency: float | None
    total_variation: float
    ueq_fraction: float | None
    ueq_model_error: float | None
    matched: bool
    predicted_offset: float
    final_offset: float
    offset_tolerance: float = 0.0
    sigma_gain: float = 0.0
    expected_poles: tuple[complex, ...] = ()
    data: dict[str, Any] = field(default_factory=dict, repr=False)


def hold_of(sim: Any) -> float:
    """How long one command is held (s): the step, or the sampling period, plus the delay."""
    st = sim.settings
    return max(float(st["dt"]), float(st.get("sampling_period") or 0.0)) + float(st.get("delay") or 0.0)


def static_offset(A: np.ndarray, B: np.ndarray, D: np.ndarray, c: np.ndarray, d: float,
                  sigma: float = 0.0) -> np.ndarray:
    """``x~_ss``: the rest of the sliding motion under a constant disturbance ``d`` with ``c x~ = sigma``
    (module docstring)."""
    n = A.shape[0]
    B = B.reshape(n, 1)
    c = np.asarray(c, float).reshape(1, n)
    proj = np.eye(n) - B @ c / float((c @ B)[0, 0])
    M = np.vstack([proj @ A, c])
    rhs = np.concatenate([-(proj @ D.reshape(n, -1)[:, :1]).ravel() * d, [sigma]])
    return np.linalg.lstsq(M, rhs, rcond=None)[0]


@functools.lru_cache(maxsize=8)
def _model(plant: Any) -> Any:
    from designkit.synthesis.state_space import linear_model

    return linear_model(plant)


def run_models(design: Any, sim: Any) -> list[tuple[float, tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """``[(t_start, (A, B, D))]``: the linear model of the plant the run simulates (``settings["plant"]``), and
    after ``simulation.plant_change`` the changed one."""
    model = _model(design.plant)
    st = sim.settings
    values = dict(st.get("plant") or {})
    out = [(float(sim.time[0]), model.at(values))]
    change = st.get("plant_change")
    if change and change.get("time_applied") is not None:  # None: the change falls after the end of the run
        out.append((float(change["time_applied"]), model.at({**values, **change["values"]})))
    return out


def _sign_changes(s: np.ndarray) -> int:
    nz = s[s != 0]
    return int(np.count_nonzero(np.sign(nz[1:]) != np.sign(nz[:-1]))) if nz.size > 1 else 0


def measure(design: Any, sim: Any) -> VscRun:
    """The measurements of ``sim``, a run of the ``design`` (module docstring); of a run that diverged, the
    measurements are not finite from that instant on (``finite_run`` reports it) and are computed so."""
    if getattr(sim, "diverged_at", None) is None:
        return _measure(design, sim)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _measure(design, sim)


def _measure(design: Any, sim: Any) -> VscRun:
    info: VscData = design.data
    c = np.asarray(info.c, float)
    al, be = np.asarray(info.alpha, float), np.asarray(info.beta, float)
    delta = float(info.delta)
    t = np.asarray(sim.time, float)
    xd = np.asarray(sim.reference[:, 0, 0], float)
    rest = np.asarray(info.rest_direction, float)
    xt = np.asarray(sim.state, float) - np.outer(xd, rest)
    sigma = np.asarray(sim.signals["sigma"], float)
    u = np.asarray(sim.u_command[:, 0], float)
    hold = hold_of(sim)
    G = np.asarray(info.G, float)
    S = info.cB_max * (np.abs(xt) @ G + delta) + info.cD_max * info.d_bar
    if info.boundary_layer is not None:
        band = np.full_like(t, float(info.boundary_layer))
    else:
        from numpy.lib.stride_tricks import sliding_window_view

        padded = np.concatenate([np.full(WINDOW - 1, S[0]), S])
        band = hold * sliding_window_view(padded, WINDOW).max(axis=1)
    inside = np.abs(sigma) <= band * (1 + 1e-9)
    idx = np.flatnonzero(inside)
    reach = int(idx[0]) if idx.size else None
    pieces = run_models(design, sim)
    A, B, D = pieces[-1][1]  # the plant the run ends with
    d = np.asarray(sim.perturbation, float).reshape(len(t), -1)[:, 0]
    u_eq = np.empty(len(t))
    for (t0, (Ak, Bk, Dk)), nxt in zip(pieces, [*pieces[1:], (np.inf, None)], strict=True):
        sel = (t >= t0) & (t < nxt[0])
        cDk = float(c @ Dk[:, 0]) if Dk.size else 0.0
        u_eq[sel] = -((xt[sel] @ Ak.T) @ c + cDk * d[sel]) / float(c @ Bk.ravel())
    ueq_model = np.asarray(sim.signals["u_eq"], float)
    out: dict[str, Any] = {"time": t, "xt": xt, "sigma": sigma, "band": band, "u": u, "u_eq": u_eq,
                           "u_eq_law": ueq_model, "S": S}
    matched = bool(np.linalg.matrix_rank(np.column_stack([B, D[:, :1]])) == np.linalg.matrix_rank(B)) \
        if D.size else True
    d_final = float(d[-1]) if d.size else 0.0
    offset = static_offset(A, B, D, c, d_final) if D.size else np.zeros(len(c))
    k_pos = int(info.position_index)
    pred, final = float(offset[k_pos]), float(xt[-1, k_pos])
    # the residual sigma of the chattering (|sigma| <= band) moves the rest by at most |g_sigma| band
    g_sigma = float(static_offset(A, B, D if D.size else np.zeros((len(c), 1)), c, 0.0, 1.0)[k_pos])
    tail = slice(max(0, len(t) - max(2, len(t) // 20)), None)
    offset_tol = abs(g_sigma) * float(np.max(band[tail])) + 0.02 * abs(pred)
    if reach is None:
        from designkit.families.vsc.surface import reduced_poles

        return VscRun(hold, None, None, None, None, None, 0, 0, 0.0, None, 0.0, None, None, matched, pred, final,
                      offset_tolerance=offset_tol, sigma_gain=g_sigma,
                      expected_poles=tuple(complex(v) for v in reduced_poles(A, B, c)), data=out)
    after = np.abs(sigma[reach:]) / band[reach:]
    j = int(np.argmax(after))
    # the sliding samples: after the first sign change of sigma past the reaching time
    s_after = sigma[reach:]
    nz = np.flatnonzero(s_after != 0)
    flips = np.flatnonzero(np.sign(s_after[nz[1:]]) != np.sign(s_after[nz[:-1]])) if nz.size > 1 else []
    k1 = reach + (int(nz[flips[0] + 1]) if len(flips) else 0)
    dt = float(sim.settings["dt"])
    sliding_time = float(t[-1] - t[reach])
    switches = _sign_changes(sigma[reach:])
    # theorem 1: u_eq between the two controls at sigma = 0+ and 0-
    psi_plus = np.where(xt > 0, al, be)  # sigma > 0: x_i sigma > 0 where x_i > 0
    psi_minus = np.where(xt < 0, al, be)
    u_plus = np.sum(psi_plus * xt, axis=1) - delta
    u_minus = np.sum(psi_minus * xt, axis=1) + delta
    lo, hi = np.minimum(u_plus, u_minus), np.maximum(u_plus, u_minus)
    sl = slice(k1, None)
    ok = (u_eq[sl] >= lo[sl] - 1e-12) & (u_eq[sl] <= hi[sl] + 1e-12)
    out.update(u_plus=u_plus, u_minus=u_minus)
    # sliding poles: z = x~ without the driven state (its motion on sigma = 0 is the reduced system, u does not
    # enter it), z' = F z + g d by least squares on the sliding samples
    k_drive = info.drive_index
    keep_cols = [i for i in range(len(c)) if i != k_drive]
    z = xt[:, keep_cols]
    scale = np.max(np.abs(z[k1:]), axis=0) if z[k1:].size else np.ones(len(keep_cols))
    keep = np.arange(max(k1, 1), len(t) - 1)
    norm = np.linalg.norm(z[keep] / np.where(scale > 0, scale, 1.0), axis=1)
    keep = keep[norm >= 1e-3 * (norm.max() if norm.size else 0.0)]
    keep = keep[(d[keep + 1] == d[keep]) & (d[keep - 1] == d[keep])]  # not across a jump of the disturbance
    keep = keep[t[keep - 1] >= pieces[-1][0]]  # on the plant the run ends with (after a plant change)
    poles: tuple[complex, ...] | None = None
    if keep.size >= MIN_FIT_SAMPLES:
        # integral form over [t_k-1, t_k+1] (trapezoid): sigma chatters from sample to sample, its integral does not
        dz = z[keep + 1] - z[keep - 1]
        extra = [sigma] + ([d] if np.any(d[keep] != 0) else [])
        full = np.column_stack([z, *extra])
        h2 = (t[keep + 1] - t[keep - 1])[:, None] / 2.0
        reg = h2 * (full[keep - 1] / 2 + full[keep] + full[keep + 1] / 2)
        F = np.linalg.lstsq(reg, dz, rcond=None)[0].T[:, :len(keep_cols)]
        eig = np.linalg.eigvals(F)
        poles = tuple(complex(v) for v in eig[np.lexsort((eig.imag, eig.real))])
    from designkit.families.vsc.surface import reduced_poles

    expected = tuple(complex(v) for v in reduced_poles(A, B, c))
    nominal_ueq = -(xt @ np.asarray(info.cA_nominal)) / info.cB_nominal
    return VscRun(
        hold=hold, reach=reach, reaching_time=float(t[reach] - t[0]), worst_ratio=float(after[j]),
        worst_at=float(t[reach + j]), poles=poles, fit_samples=int(keep.size), switches=switches,
        sliding_time=sliding_time, switching_frequency=switches / sliding_time if sliding_time > 0 else None,
        total_variation=float(np.sum(np.abs(np.diff(u[reach:])))),
        ueq_fraction=float(np.mean(ok)) if ok.size else None,
        ueq_model_error=float(np.max(np.abs(ueq_model[sl] - nominal_ueq[sl]))) if ok.size else None,
        matched=matched, predicted_offset=pred, final_offset=final, offset_tolerance=offset_tol,
        sigma_gain=g_sigma, expected_poles=expected, data={**out, "k1": k1, "dt": dt},
    )
