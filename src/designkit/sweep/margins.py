"""Each requirement's margin per sample, computed in NumPy over a batch of runs.

The definitions are the time-domain requirements' (:mod:`designkit.verification.time_domain`: overshoot,
settling time to the band, 10-90 % rise time, steady-state error over the last 5 % of the run, largest
tracking error, peak commanded control; on a trajectory run the overshoot requirement bounds the largest
tracking error as a percentage of the move), evaluated for ``B`` runs at once.  The margin is
``limit - achieved`` in the requirement's unit, positive when met; NaN when the metric is undefined (the
run diverged, never settles, never rises), which fails the sample.  ``tests/sweep`` checks these margins
against the checks the pipeline computes on the same runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from designkit.verification.tolerances import REST_TOL, RISE_LIMITS, STEADY_STATE_WINDOW

__all__ = ["REQUIREMENTS", "JointMetrics", "Margins", "joint_metrics", "margins", "margins_of"]

REQUIREMENTS = {
    "overshoot": "%", "settling_time": "s", "rise_time": "s", "steady_state_error": "rad",
    "tracking_error": "rad", "max_control": "N*m",
}
"""The requirements a sweep evaluates per sample, in report order, with their units."""


@dataclass(frozen=True, eq=False)
class Margins:
    """Per requirement: the limit, the achieved value and the margin of every sample (NaN: undefined)."""

    names: tuple[str, ...]
    limits: dict[str, float]
    achieved: dict[str, np.ndarray]
    margin: dict[str, np.ndarray]

    @property
    def passed(self) -> np.ndarray:
        """True where every requirement holds with a defined metric."""
        if not self.names:
            return np.ones(0, dtype=bool)
        return np.all(np.stack([np.nan_to_num(self.margin[k], nan=-1.0) >= 0 for k in self.names]), axis=0)

    def normalized(self) -> np.ndarray:
        """``(B, r)``: each margin over its limit (dimensionless); -inf where undefined."""
        cols = [np.where(np.isnan(self.margin[k]), -np.inf, self.margin[k] / max(self.limits[k], 1e-300))
                for k in self.names]
        return np.stack(cols, axis=1) if cols else np.zeros((0, 0))


def _settling(t: np.ndarray, dev: np.ndarray, band: np.ndarray) -> np.ndarray:
    """``(B,)``: when ``dev`` (``(B, N)``) last enters ``band`` (``(B,)``) for good, from ``t[0]``; NaN when outside
    at the end."""
    B, N = dev.shape
    outside = dev > band[:, None]
    any_out = outside.any(axis=1)
    k = N - 1 - np.argmax(outside[:, ::-1], axis=1)
    out = np.zeros(B)
    last = any_out & (k == N - 1)
    mid = any_out & ~last
    kk = np.minimum(k, N - 2)
    rows = np.arange(B)
    d0, d1 = dev[rows, kk], dev[rows, kk + 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.where(d0 != d1, (d0 - band) / (d0 - d1), 1.0)
    out[mid] = (t[kk] + (t[kk + 1] - t[kk]) * frac - t[0])[mid]
    out[last] = np.nan
    return out


def _first_crossing(t: np.ndarray, x: np.ndarray, level: float) -> np.ndarray:
    """``(B,)``: first time ``x`` (``(B, N)``) reaches ``level``, interpolated; NaN when never."""
    B = x.shape[0]
    hit = x >= level
    k = np.argmax(hit, axis=1)
    rows = np.arange(B)
    out = np.full(B, np.nan)
    ok = hit[rows, k]
    at0 = ok & (k == 0)
    out[at0] = t[0]
    mid = ok & (k > 0)
    km = np.maximum(k, 1)
    x0, x1 = x[rows, km - 1], x[rows, km]
    with np.errstate(invalid="ignore", divide="ignore"):
        val = t[km - 1] + (t[km] - t[km - 1]) * (level - x0) / (x1 - x0)
    out[mid] = val[mid]
    return out


def _joint_step(t, y, xd, band_frac, scale, several):
    """Step metrics of one joint over the batch: overshoot, rise, settling, sse, amplitude, max error."""
    r = xd[:, -1]
    amp = r - y[:, 0]
    zero = np.abs(amp) <= REST_TOL * (1.0 + np.abs(r))
    with np.errstate(invalid="ignore", divide="ignore"):
        yn = (y - y[:, :1]) / np.where(zero, 1.0, amp)[:, None]
    overshoot = np.where(zero, np.nan, 100.0 * np.maximum(0.0, np.max(yn, axis=1) - 1.0))
    lo, hi = (_first_crossing(t, yn, lv) for lv in RISE_LIMITS)
    rise = np.where(zero, np.nan, hi - lo)
    band = np.where(zero, band_frac * (scale if several else np.nan), band_frac * np.abs(amp))
    settle = _settling(t, np.abs(y - r[:, None]), np.nan_to_num(band, nan=np.inf))
    settle = np.where(np.isnan(band), np.nan, settle)
    return overshoot, rise, settle, amp


@dataclass(frozen=True, eq=False)
class JointMetrics:
    """The per-joint metrics of ``B`` runs, before the worst over the joints is taken (:func:`margins_of`).

    Parameters
    ----------
    finite : ndarray of bool, shape (B, n)
        The joint's tracked and desired positions are finite over the whole run.
    overshoot, rise, settle : ndarray, shape (B, n)
        Overshoot (%), 10-90 % rise time (s), settling time (s); NaN where undefined.
    moving : ndarray, shape (B, n)
        The joint's move: the step's signed amplitude, or the trajectory's largest excursion (NaN: not finite).
    sse, max_err : ndarray, shape (B, n)
        Mean tracking error over the last 5 % of the run, largest tracking error (rad or m).
    amps : ndarray, shape (B, n)
        ``|xD(end) - y(0)|`` (step) or ``max |xD - xD(0)|`` (trajectory): the joints' scale.
    u_peak : ndarray, shape (B, nu)
        Peak ``|u|`` of every input (N*m).
    u_ok : ndarray of bool, shape (B,)
        Every command is finite.
    """

    finite: np.ndarray
    overshoot: np.ndarray
    rise: np.ndarray
    settle: np.ndarray
    moving: np.ndarray
    sse: np.ndarray
    max_err: np.ndarray
    amps: np.ndarray
    u_peak: np.ndarray
    u_ok: np.ndarray


def joint_metrics(records, kind: str, settling_band: float, control: bool = True) -> JointMetrics:
    """The per-joint metrics of the runs ``records`` (``time``, ``desired``, ``tracked``, ``u_command``), in NumPy.

    ``kind`` is ``"step"`` or ``"trajectory"``; ``settling_band`` the requirement's band (fraction of the move);
    ``control`` False skips the peak commands (left NaN).
    """
    t = np.asarray(records.time, dtype=float)
    y_all, xd_all = np.asarray(records.tracked, dtype=float), np.asarray(records.desired, dtype=float)
    B, N, n = y_all.shape
    finite = np.all(np.isfinite(y_all), axis=1) & np.all(np.isfinite(xd_all), axis=1)  # (B, n)
    err = np.abs(y_all - xd_all)
    window = t >= t[-1] - STEADY_STATE_WINDOW * float(t[-1] - t[0])
    # each run's mean over its own contiguous row: the same sum whatever the batch (bitwise across splits)
    sse = np.where(finite, np.mean(np.ascontiguousarray(err[:, window, :].transpose(0, 2, 1)), axis=2), np.nan)
    max_err = np.where(finite, np.max(err, axis=1), np.nan)
    sb = settling_band
    several = n > 1
    if kind == "trajectory":
        amps = np.max(np.abs(xd_all - xd_all[:, :1, :]), axis=1)
    else:
        amps = np.abs(xd_all[:, -1, :] - y_all[:, 0, :])
    scale = np.where(np.all(np.isfinite(amps), axis=1), np.max(amps, axis=1), np.nan) if several else np.full(B, np.nan)
    os_j, rise_j, settle_j, moving = (np.full((B, n), np.nan) for _ in range(4))
    for j in range(n):
        y, xd = y_all[:, :, j], xd_all[:, :, j]
        if kind == "trajectory":
            amp = amps[:, j]
            own = amp > REST_TOL * (1.0 + np.max(np.abs(xd), axis=1))
            band_scale = np.where(own, amp, np.nan_to_num(scale, nan=0.0) if several else 0.0)
            band = np.where(band_scale > 0, sb * band_scale, np.nan)
            s = _settling(t, err[:, :, j], np.nan_to_num(band, nan=np.inf))
            settle_j[:, j] = np.where(np.isnan(band), np.nan, s)
            moving[:, j] = amp
        else:
            o, r_, s, a = _joint_step(t, y, xd, sb, scale, several)
            os_j[:, j], rise_j[:, j], settle_j[:, j], moving[:, j] = o, r_, s, a
        bad = ~finite[:, j]
        for arr in (os_j, rise_j, settle_j):
            arr[bad, j] = np.nan
        moving[bad, j] = np.nan
    if control:
        u = np.asarray(records.u_command, dtype=float)
        u_peak = np.max(np.abs(u), axis=1)  # (B, nu)
        u_ok = np.all(np.isfinite(u), axis=(1, 2))
    else:
        u_peak, u_ok = np.full((B, 0), np.nan), np.ones(B, dtype=bool)
    return JointMetrics(finite=finite, overshoot=os_j, rise=rise_j, settle=settle_j, moving=moving, sse=sse,
                        max_err=max_err, amps=amps, u_peak=u_peak, u_ok=u_ok)


def margins_of(jm: JointMetrics, kind: str, requirements) -> Margins:
    """Each requirement's margin from the per-joint metrics: the worst joint (module docstring)."""
    names = tuple(k for k in REQUIREMENTS if requirements is not None and getattr(requirements, k) is not None)
    B, n = jm.finite.shape
    several = n > 1
    finite, amps, max_err = jm.finite, jm.amps, jm.max_err
    scale = np.where(np.all(np.isfinite(amps), axis=1), np.max(amps, axis=1), np.nan) if several else np.full(B, np.nan)

    def worst(vals: np.ndarray, candidates: np.ndarray) -> np.ndarray:
        """Worst over candidate joints; NaN when a candidate is undefined or there is none."""
        has = candidates.any(axis=1)
        undefined = np.any(candidates & np.isnan(vals), axis=1)
        v = np.where(candidates, vals, -np.inf).max(axis=1)
        return np.where(has & ~undefined, v, np.nan)

    everyone = np.ones((B, n), dtype=bool)
    is_moving = np.isfinite(jm.moving) & (jm.moving != 0)
    if kind == "trajectory":
        big = np.argmax(np.nan_to_num(amps, nan=-np.inf), axis=1) if several else np.zeros(B, dtype=int)
        amplitude = np.where(np.isfinite(scale) if several else True, amps[np.arange(B), big], np.nan)
        mte = worst(max_err, everyone)
        with np.errstate(invalid="ignore", divide="ignore"):
            overshoot = np.where(amplitude > 0, 100.0 * mte / amplitude, np.nan)
        rise = np.full(B, np.nan)
    else:
        overshoot = worst(jm.overshoot, is_moving) if several else jm.overshoot[:, 0]
        rise = worst(jm.rise, is_moving) if several else jm.rise[:, 0]
    values = {
        "overshoot": overshoot,
        "settling_time": worst(jm.settle, everyone),
        "rise_time": rise,
        "steady_state_error": worst(jm.sse, everyone),
        "tracking_error": np.where(finite.all(axis=1), np.max(max_err, axis=1), np.nan),
    }
    limits: dict[str, float] = {}
    achieved: dict[str, np.ndarray] = {}
    margin: dict[str, np.ndarray] = {}
    for k in names:
        if k == "max_control":
            peaks = jm.u_peak
            lim = np.broadcast_to(np.asarray(requirements.max_control, dtype=float), (peaks.shape[1],))
            worst_in = np.argmax(np.nan_to_num(peaks / lim, nan=np.inf), axis=1)
            achieved[k] = np.where(jm.u_ok, peaks[np.arange(B), worst_in], np.nan)
            margin[k] = np.where(jm.u_ok, lim[worst_in] - achieved[k], np.nan)
            limits[k] = float(np.min(lim))
            continue
        limits[k] = float(getattr(requirements, k))
        achieved[k] = values[k]
        margin[k] = limits[k] - values[k]
    return Margins(names=names, limits=limits, achieved=achieved, margin=margin)


def margins(records, kind: str, requirements) -> Margins:
    """The margin of every requirement in ``requirements`` for every run of ``records`` (module docstring).

    Parameters
    ----------
    records : BatchRecords
        ``time``, ``desired`` and ``tracked`` ``(B, N, n)``, ``u_command`` ``(B, N, nu)``.
    kind : str
        ``"step"`` or ``"trajectory"``.
    requirements : Requirements or None
        The spec's requirements.
    """
    sb = requirements.settling_band if requirements is not None else 0.02
    control = requirements is not None and requirements.max_control is not None
    return margins_of(joint_metrics(records, kind, sb, control), kind, requirements)
