"""Time-domain requirements measured on a :class:`~designkit.simulation.result.SimulationResult`.

Only the result's fields are used (``time``, ``reference``, ``state``, ``u_command``,
``u_applied``, ``kind``), never the simulation engine, so any integrator or a measured record can
be verified the same way.  Crossing instants are linearly interpolated between samples (so they
can differ from python-control's ``step_info``, which takes the first sample past the level, by
less than one sample period).

Step runs (``kind == "step"``), with ``y = x1``, ``y0 = y[0]``, the command ``r = xD[-1]`` and the
commanded step ``A = r - y0``:

- overshoot (%): ``100 * max(0, max((y - y0)/A) - 1)``;
- settling time (s, from ``time[0]``): when ``|y - r|`` last enters the band ``settling_band*|A|``
  for good; undefined if it is outside the band at the end of the run;
- rise time (s): between the first crossings of 10 % and 90 % of the step; undefined if 90 % is
  never reached;
- steady-state error (rad): mean of ``|y - xD|`` over the last 5 % of the run;
- peak ``|u_command|`` and peak ``|u_applied|`` (N*m); the ``max_control`` requirement bounds the
  *commanded* control (what the controller demands; a saturation would hide it in ``u_applied``,
  which is reported alongside).

Trajectory runs (``kind == "trajectory"``), with the tracking error ``e = x1 - xD`` and the move
``M = max |xD - xD[0]|``: the step metrics are replaced by

- max tracking error ``max |e|`` (rad), checked against the ``overshoot`` requirement as a
  percentage of the move (``100 max|e| / M <= overshoot``): the largest departure from the
  commanded motion, the tracking analogue of overshooting a commanded step;
- final error: mean ``|e|`` over the last 5 % (the ``steady_state_error`` requirement);
- settling time: when ``|e|`` last enters ``settling_band * M`` for good;
- rise time is a step-response notion and is *undefined* for a trajectory run, so a
  ``rise_time`` requirement fails there with a detail saying so.

A requirement whose metric is undefined (never settles, never rises, zero step, non-finite
samples) fails (``passed=False``) with a detail saying why.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.verification.check import Check
from designkit.verification.tolerances import REST_TOL, RISE_LIMITS, STEADY_STATE_WINDOW


@dataclass(frozen=True)
class ResponseMetrics:
    """Time-domain metrics of one run; None means undefined (see module docstring).

    Parameters
    ----------
    kind : str
        ``"step"`` or ``"trajectory"``.
    amplitude : float
        Commanded step ``A`` (step) or move ``M`` (trajectory), rad.
    overshoot : float or None
        Percent of the step (step runs only).
    rise_time : float or None
        10-90 % rise time, s (step runs only).
    settling_time : float or None
        s, from ``time[0]``.
    steady_state_error : float or None
        Mean ``|x1 - xD|`` over the last 5 % of the run, rad.
    max_tracking_error : float or None
        ``max |x1 - xD|``, rad (trajectory runs only).
    peak_u_command, peak_u_applied : float or None
        N*m.
    duration : float
        Length of the run, s.
    why_undefined : dict
        Reason for each None metric.
    per_joint : tuple of ResponseMetrics
        Each joint's own metrics (empty for one joint).
    worst_joint : dict
        Metric name -> 0-based joint of its worst value (several joints only).
    """

    kind: str
    amplitude: float
    overshoot: float | None
    rise_time: float | None
    settling_time: float | None
    steady_state_error: float | None
    max_tracking_error: float | None
    peak_u_command: float | None
    peak_u_applied: float | None
    duration: float
    why_undefined: dict[str, str]
    per_joint: tuple[ResponseMetrics, ...] = ()
    worst_joint: dict[str, int] = field(default_factory=dict)


def _first_crossing(t: np.ndarray, x: np.ndarray, level: float) -> float | None:
    """First time ``x`` reaches ``level`` from below (linear interpolation), or None."""
    idx = np.flatnonzero(x >= level)
    if idx.size == 0:
        return None
    k = int(idx[0])
    if k == 0:
        return float(t[0])
    x0, x1 = x[k - 1], x[k]
    return float(t[k - 1] + (t[k] - t[k - 1]) * (level - x0) / (x1 - x0))


def _settling(t: np.ndarray, dev: np.ndarray, band: float) -> float | None:
    """Time (from ``t[0]``) after which ``dev <= band`` for good; None if outside at the end."""
    outside = np.flatnonzero(dev > band)
    if outside.size == 0:
        return 0.0
    k = int(outside[-1])
    if k == len(t) - 1:
        return None
    d0, d1 = dev[k], dev[k + 1]
    frac = (d0 - band) / (d0 - d1) if d0 != d1 else 1.0
    return float(t[k] + (t[k + 1] - t[k]) * frac - t[0])


def _peak(u: np.ndarray) -> float | None:
    u = np.asarray(u, dtype=float)
    if u.size == 0 or not np.all(np.isfinite(u)):
        return None
    return float(np.max(np.abs(u)))


def _joint_metrics(t: np.ndarray, y: np.ndarray, xd: np.ndarray, u_c: np.ndarray, u_a: np.ndarray, kind: str,
                   settling_band: float, scale: float | None) -> ResponseMetrics:
    """Metrics of one joint; ``scale`` (rad) replaces the joint's own step/move for the settling band when it
    does not move itself (a resting joint disturbed by the others)."""
    why: dict[str, str] = {}
    duration = float(t[-1] - t[0])
    peak_c, peak_a = _peak(u_c), _peak(u_a)
    if peak_c is None:
        why["peak_u_command"] = "non-finite or empty u_command"
    if peak_a is None:
        why["peak_u_applied"] = "non-finite or empty u_applied"
    window = t >= t[-1] - STEADY_STATE_WINDOW * duration
    finite = bool(np.all(np.isfinite(y)) and np.all(np.isfinite(xd)))
    err = np.abs(y - xd)
    sse = float(np.mean(err[window])) if finite else None
    if not finite:
        for k in ("overshoot", "rise_time", "settling_time", "steady_state_error", "max_tracking_error"):
            why[k] = "the simulated position is not finite (diverged?)"
        amp = float("nan")
        return ResponseMetrics(kind, amp, None, None, None, None, None, peak_c, peak_a, duration, why)
    if kind == "trajectory":
        amp = float(np.max(np.abs(xd - xd[0])))
        settle = None
        band_scale = amp if amp > REST_TOL * (1.0 + np.max(np.abs(xd))) else (scale or 0.0)
        if band_scale <= 0:
            why["settling_time"] = "the trajectory does not move (zero move amplitude)"
        else:
            settle = _settling(t, err, settling_band * band_scale)
            if settle is None:
                why["settling_time"] = (
                    f"|x1 - xD| still outside the {100 * settling_band:g} % band at the end of the run ({duration:g} s)"
                )
        why["rise_time"] = "rise time is a step-response metric, undefined for a trajectory run"
        return ResponseMetrics(
            "trajectory", amp, None, None, settle, sse, float(np.max(err)), peak_c, peak_a, duration, why
        )
    r = float(xd[-1])
    amp = r - float(y[0])
    if abs(amp) <= REST_TOL * (1.0 + abs(r)):
        for k in ("overshoot", "rise_time"):
            why[k] = "the commanded step is zero (command equals the initial position)"
        settle = None
        if scale:
            settle = _settling(t, np.abs(y - r), settling_band * scale)
            if settle is None:
                why["settling_time"] = (f"the joint is still outside the {100 * settling_band:g} % band of the largest "
                                        f"step at the end of the run ({duration:g} s)")
        else:
            why["settling_time"] = "the commanded step is zero (command equals the initial position)"
        return ResponseMetrics("step", amp, None, None, settle, sse, float(np.max(err)), peak_c, peak_a, duration,
                               why)
    yn = (y - y[0]) / amp
    overshoot = float(100.0 * max(0.0, float(np.max(yn)) - 1.0))
    lo, hi = (_first_crossing(t, yn, level) for level in RISE_LIMITS)
    rise = None if lo is None or hi is None else hi - lo
    if rise is None:
        why["rise_time"] = f"the response never reaches {100 * RISE_LIMITS[1]:g} % of the step within {duration:g} s"
    settle = _settling(t, np.abs(y - r), settling_band * abs(amp))
    if settle is None:
        why["settling_time"] = (
            f"the response is still outside the {100 * settling_band:g} % band at the end of the run ({duration:g} s)"
        )
    return ResponseMetrics("step", amp, overshoot, rise, settle, sse, None, peak_c, peak_a, duration, why)


_WORST = ("overshoot", "rise_time", "settling_time", "steady_state_error", "max_tracking_error")


def response_metrics(sim: Any, *, settling_band: float = 0.02) -> ResponseMetrics:
    """Metrics of a step or trajectory run (see module docstring), the worst over the joints.

    Parameters
    ----------
    sim : SimulationResult
        ``time`` (N,), ``reference`` (N, n, 3), ``state``, ``positions``, ``u_command``, ``u_applied``, ``kind``.
    settling_band : float
        Half-width of the settling band as a fraction of the step (or move).

    Returns
    -------
    ResponseMetrics
        For one joint, its metrics.  For several: each metric's worst value over the joints
        (a metric undefined for some joint is undefined, with that joint's reason), the largest
        step as ``amplitude``, ``per_joint`` the joints' own metrics and ``worst_joint`` the
        0-based joint of each worst value.  A joint commanded to stay where it is counts for
        the settling time (within the band of the largest step: the intercoupling it suffers)
        and the steady-state error, not for overshoot and rise time.
    """
    t = np.asarray(sim.time, dtype=float)
    pos = _tracked(sim)
    ref = np.asarray(sim.reference, dtype=float)
    xd = ref[:, :, 0] if ref.ndim == 3 else ref[:, :1]
    n = pos.shape[1]
    kind = sim.kind
    amps = np.abs(xd[-1] - pos[0]) if kind == "step" else np.max(np.abs(xd - xd[0]), axis=0)
    scale = float(np.max(amps)) if np.all(np.isfinite(amps)) and amps.size else None
    joints = tuple(_joint_metrics(t, pos[:, j], xd[:, j], sim.u_command, sim.u_applied, kind, settling_band,
                                  scale if n > 1 else None) for j in range(n))
    if n == 1:
        return joints[0]
    moving = [j for j, m in enumerate(joints) if m.amplitude == m.amplitude and abs(m.amplitude) > 0]
    values: dict[str, float | None] = {}
    worst: dict[str, int] = {}
    why: dict[str, str] = {}
    for key in _WORST:
        candidates = moving if key in ("overshoot", "rise_time") else list(range(n))
        if kind == "trajectory" and key in ("overshoot", "rise_time"):
            candidates = []
        vals = [(getattr(joints[j], key), j) for j in candidates]
        missing = [j for v, j in vals if v is None]
        if not vals or missing:
            values[key] = None
            j = missing[0] if missing else 0
            why[key] = (f"joint {j + 1}: " + joints[j].why_undefined.get(key, "undefined")) if vals else \
                joints[0].why_undefined.get(key, "no joint moves")
            continue
        v, j = max(vals)
        values[key], worst[key] = float(v), j
    for key in ("peak_u_command", "peak_u_applied"):
        if key in joints[0].why_undefined:
            why[key] = joints[0].why_undefined[key]
    big = int(np.argmax(amps)) if scale is not None else 0
    return ResponseMetrics(
        kind, float(joints[big].amplitude), values["overshoot"], values["rise_time"], values["settling_time"],
        values["steady_state_error"], values["max_tracking_error"], joints[0].peak_u_command, joints[0].peak_u_applied,
        joints[0].duration, why, per_joint=joints, worst_joint=worst,
    )


def _check(name: str, limit: float, value: float | None, unit: str, what: str, why: str | None,
           cert: dict[str, Any], fmt: str = ".4g", note: str = "") -> Check:
    target = f"<= {limit:g} {unit}"
    if value is None:
        return Check(name=name, passed=False, target=target, achieved=None, margin=None, unit=unit,
                     detail=f"{what}: undefined: {why}", certificate=cert)
    margin = float(limit - value)
    ok = margin >= 0
    detail = f"{what} = {value:{fmt}} {unit} " + ("meets" if ok else "exceeds") + f" {target}{note}"
    return Check(name=name, passed=ok, target=target, achieved=float(value), margin=margin, unit=unit,
                 detail=detail, certificate=cert)


def time_domain_checks(requirements: Any, sim: Any) -> tuple[Check, ...]:
    """One Check per requirement present in ``requirements`` (a spec's ``Requirements``).

    Order: overshoot, settling_time, rise_time, steady_state_error, tracking_error, max_control.  Margins are
    ``limit - achieved`` in the requirement's unit (positive when met).
    """
    m = response_metrics(sim, settling_band=requirements.settling_band)
    cert = {
        "kind": m.kind, "amplitude": m.amplitude, "duration": m.duration, "settling_band": requirements.settling_band,
        "overshoot_percent": m.overshoot, "rise_time": m.rise_time, "settling_time": m.settling_time,
        "steady_state_error": m.steady_state_error, "max_tracking_error": m.max_tracking_error,
        "peak_u_command": m.peak_u_command, "peak_u_applied": m.peak_u_applied,
        "steady_state_window": STEADY_STATE_WINDOW, "rise_limits": list(RISE_LIMITS),
        "why_undefined": dict(m.why_undefined),
    }
    out: list[Check] = []
    req = requirements
    traj = m.kind == "trajectory"
    if m.per_joint:
        cert["worst_joint"] = {k: j + 1 for k, j in m.worst_joint.items()}
        cert["joints"] = len(m.per_joint)

    def at(key: str) -> str:
        return f" (worst: joint {m.worst_joint[key] + 1})" if key in m.worst_joint else ""

    if req.overshoot is not None:
        if traj:
            pct = None
            if m.max_tracking_error is not None and m.amplitude > 0:
                pct = 100.0 * m.max_tracking_error / m.amplitude
            why = m.why_undefined.get("max_tracking_error", "the trajectory does not move (zero move amplitude)")
            out.append(_check("overshoot", req.overshoot, pct, "%", "max |x1 - xD| as % of the move", why, cert,
                              note=at("max_tracking_error")))
        else:
            out.append(_check("overshoot", req.overshoot, m.overshoot, "%", "overshoot",
                              m.why_undefined.get("overshoot"), cert, note=at("overshoot")))
    if req.settling_time is not None:
        what = f"settling time of |x1 - xD| to {100 * req.settling_band:g} % of the move" if traj else \
            f"settling time to the {100 * req.settling_band:g} % band"
        out.append(_check("settling_time", req.settling_time, m.settling_time, "s", what,
                          m.why_undefined.get("settling_time"), cert, note=at("settling_time")))
    if req.rise_time is not None:
        out.append(_check("rise_time", req.rise_time, m.rise_time, "s", "10-90 % rise time",
                          m.why_undefined.get("rise_time"), cert, note=at("rise_time")))
    if req.steady_state_error is not None:
        what = ("final tracking error" if traj else "steady-state error") + " (mean |x1 - xD|, last 5 %)"
        out.append(_check("steady_state_error", req.steady_state_error, m.steady_state_error, "rad", what,
                          m.why_undefined.get("steady_state_error"), cert, fmt=".3g", note=at("steady_state_error")))
    if req.tracking_error is not None:
        err = np.abs(_tracked(sim) - _desired(sim))
        value = float(np.max(err)) if err.size and np.all(np.isfinite(err)) else None
        names = getattr(sim, "coordinate_names", None)
        k = int(np.argmax(np.max(err, axis=0))) if value is not None else 0
        worst = "" if value is None or err.shape[1] == 1 else (
            f" ({names[k]})" if getattr(sim, "task_space", False) else f" (joint {k + 1})")
        task = getattr(sim, "task_space", False)
        unit = "/".join(sorted(set(sim.coordinate_units))) if task else "rad"
        out.append(_check("tracking_error", req.tracking_error, value, unit,
                          "largest |x - xD| of the end effector over the run" if task else
                          "largest |q - qD| over the run",
                          "the simulated position is not finite (diverged?)", cert, fmt=".4g", note=worst))
    if req.max_control is not None:
        out.append(_max_control(req.max_control, sim, m, cert))
    return tuple(out)


def _tracked(sim: Any) -> np.ndarray:
    tracked = getattr(sim, "tracked", None)
    if tracked is not None:
        return np.asarray(tracked, dtype=float)
    return np.asarray(sim.state, dtype=float)[:, list(getattr(sim, "positions", (0,)))]


def _desired(sim: Any) -> np.ndarray:
    ref = np.asarray(sim.reference, dtype=float)
    return ref[:, :, 0] if ref.ndim == 3 else ref[:, :1]


def _max_control(limit: Any, sim: Any, m: ResponseMetrics, cert: dict[str, Any]) -> Check:
    """Peak ``|u_command|`` of every input against its limit (one for all inputs, or one per input)."""
    u = np.asarray(sim.u_command, dtype=float)
    u = u.reshape(u.shape[0], -1)
    limits = np.broadcast_to(np.asarray(limit, dtype=float), (u.shape[1],))
    if m.peak_u_command is None:
        return _check("max_control", float(np.min(limits)), None, "N*m", "peak |u_command|",
                      m.why_undefined.get("peak_u_command"), cert)
    peaks = np.max(np.abs(u), axis=0)
    k = int(np.argmax(peaks / limits))
    note = f" (peak |u_applied| {m.peak_u_applied:.4g} N*m)" if m.peak_u_applied is not None else ""
    if u.shape[1] > 1:
        names = getattr(sim, "input_names", ()) or tuple(f"u{j + 1}" for j in range(u.shape[1]))
        note = f" on {names[k]}, the input nearest its limit" + note
    return _check("max_control", float(limits[k]), float(peaks[k]), "N*m", "peak |u_command|", None, cert, note=note)
