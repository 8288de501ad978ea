"""Per-joint reference signals ``(xD, xD', xD'')`` as analytic NumPy functions of time.

Every reference starts at the joints' initial positions ``q0`` and moves each joint ``j`` by its
own displacement ``A_j``; :meth:`Reference.evaluate` returns an array of shape ``(N, n, 3)``:
``[..., j, 0]`` position (rad), ``[..., j, 1]`` velocity (rad/s), ``[..., j, 2]`` acceleration
(rad/s^2).  Shapes, with ``s = clip(t/T, 0, 1)``:

* ``step`` (servo controllers): ``xD = q0 + A`` for ``t >= 0``, ``xD' = xD'' = 0``;
* ``quintic``: ``xD = q0 + A (10 s^3 - 15 s^4 + 6 s^5)`` over ``T``, rest to rest;
* ``sine``: ``xD = q0 + A sin(w t)``, ``w = 2 pi frequency``;
* ``trapezoidal``: every joint follows ``q0 + A sigma(t)`` with one normalised trapezoid
  ``sigma`` (acceleration ``1/(ta (T - ta))`` for ``ta``, cruise, symmetric deceleration), so the
  joints start and stop together.  Limits ``|A_j| sigma'max <= vmax_j`` and
  ``|A_j| sigma''max <= amax_j`` give ``Tv = max |A_j|/vmax_j`` and ``Ka = max |A_j|/amax_j`` and
  need ``T - ta >= Tv`` and ``ta (T - ta) >= Ka``.  Minimum time: ``ta = T - ta = sqrt(Ka)``
  (triangular) when ``sqrt(Ka) >= Tv``, else ``T - ta = Tv``, ``ta = Ka/Tv``.  For a given
  ``T``: the largest ``ta <= T/2`` with ``T - ta >= Tv`` (lowest acceleration), refused when
  ``ta (T - ta) < Ka``;
* ``via_points``: a clamped cubic spline (scipy ``CubicSpline``, zero velocity at both ends;
  continuous acceleration) through ``(0, 0), (t_1, P_1), ..., (t_k, P_k)`` per joint, held after
  ``t_k``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.spec.fields import per_joint
from designkit.synthesis.design import freeze

__all__ = ["Reference", "quintic", "reference_for", "sine", "step_reference", "trapezoidal", "via_points"]


@dataclass(frozen=True)
class Reference:
    """A reference for ``n`` joints.

    Parameters
    ----------
    evaluate : callable
        ``t (s, array of N) -> array (N, n, 3)`` of positions, velocities and accelerations.
    n : int
        Number of joints.
    horizon : float
        Time the reference itself needs (s): the motion's duration, three sine periods, 0 for a step.
    rate : float
        Fastest rate of the reference (rad/s), for the choice of the integration step (0 for a step).
    settings : Mapping
        Parameters used, JSON-serialisable.
    start : tuple of float
        The joints' initial positions ``q0`` (rad), where the plant starts at rest.
    """

    evaluate: Callable[[np.ndarray], np.ndarray]
    n: int
    horizon: float
    rate: float
    settings: Any = field(default_factory=dict)
    start: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "settings", freeze(dict(self.settings)))
        object.__setattr__(self, "start", tuple(float(v) for v in self.start) or (0.0,) * self.n)

    def flat(self, t: np.ndarray) -> np.ndarray:
        """The reference as the ``3 n`` law inputs per instant: ``(N, 3 n)``, positions then velocities then
        accelerations (the layout of a law's ``r``)."""
        return self.evaluate(t).transpose(0, 2, 1).reshape(np.size(t), 3 * self.n)


def _vec(value: Any, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(value, dtype=float), (n,)).astype(float)


def _shape(t: np.ndarray, start: np.ndarray, amp: np.ndarray, s: np.ndarray, ds: np.ndarray,
           dds: np.ndarray) -> np.ndarray:
    """``q0 + A sigma`` and its derivatives for a normalised profile ``(sigma, sigma', sigma'')`` of shape (N,)."""
    out = np.empty((t.size, amp.size, 3))
    out[:, :, 0] = start[None, :] + amp[None, :] * s[:, None]
    out[:, :, 1] = amp[None, :] * ds[:, None]
    out[:, :, 2] = amp[None, :] * dds[:, None]
    return out


def _settings(kind: str, start: np.ndarray, **values: Any) -> dict[str, Any]:
    def plain(v: Any) -> Any:
        arr = np.asarray(v, dtype=float)
        return float(arr) if arr.ndim == 0 else (float(arr[0]) if arr.size == 1 else arr.tolist())

    out = {"kind": kind, **{k: plain(v) for k, v in values.items()}}
    if np.any(start != 0):
        out["start"] = plain(start)
    return out


def step_reference(amplitude: Any, start: Any = 0.0, n: int | None = None) -> Reference:
    """``xD = start + amplitude`` (rad, per joint) from ``t = 0``."""
    n = n or np.size(amplitude)
    amp, q0 = _vec(amplitude, n), _vec(start, n)

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        return _shape(t, q0, amp, np.ones(t.size), np.zeros(t.size), np.zeros(t.size))

    return Reference(evaluate, n, 0.0, 0.0, _settings("step", q0, amplitude=amp), tuple(q0))


def quintic(amplitude: Any, duration: float, start: Any = 0.0, n: int | None = None) -> Reference:
    """Quintic rest-to-rest move of ``amplitude`` (rad, per joint) over ``duration`` (s)."""
    n = n or np.size(amplitude)
    amp, q0, T = _vec(amplitude, n), _vec(start, n), float(duration)

    def evaluate(t: np.ndarray) -> np.ndarray:
        s = np.clip(np.atleast_1d(np.asarray(t, float)) / T, 0.0, 1.0)
        return _shape(s, q0, amp, s**3 * (10.0 - 15.0 * s + 6.0 * s**2),
                      s**2 * (30.0 - 60.0 * s + 30.0 * s**2) / T, s * (60.0 - 180.0 * s + 120.0 * s**2) / T**2)

    return Reference(evaluate, n, T, 2.0 * math.pi / T, _settings("quintic", q0, amplitude=amp, duration=T),
                     tuple(q0))


def sine(amplitude: Any, frequency: float, start: Any = 0.0, n: int | None = None) -> Reference:
    """``xD = start + amplitude sin(2 pi frequency t)`` (rad per joint, Hz)."""
    n = n or np.size(amplitude)
    amp, q0, w = _vec(amplitude, n), _vec(start, n), 2.0 * math.pi * float(frequency)

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        return _shape(t, q0, amp, np.sin(w * t), w * np.cos(w * t), -w**2 * np.sin(w * t))

    return Reference(evaluate, n, 3.0 / float(frequency), w,
                     _settings("sine", q0, amplitude=amp, frequency=float(frequency)), tuple(q0))


def trapezoid_timing(amplitude: Any, max_velocity: Any, max_acceleration: Any,
                     duration: float | None = None) -> tuple[float, float]:
    """``(T, ta)``: total and acceleration time (s) of the synchronised trapezoid (module docstring).

    Raises
    ------
    ValueError
        When ``duration`` is too short for the limits (the message gives the minimum).
    """
    amp = np.abs(np.atleast_1d(np.asarray(amplitude, dtype=float)))
    vmax = np.broadcast_to(np.asarray(max_velocity, dtype=float), amp.shape)
    amax = np.broadcast_to(np.asarray(max_acceleration, dtype=float), amp.shape)
    Tv, Ka = float(np.max(amp / vmax)), float(np.max(amp / amax))
    if Tv == 0.0 and Ka == 0.0:
        return (float(duration) if duration else 0.0), 0.0
    if math.sqrt(Ka) >= Tv:
        t_min, ta_min = 2.0 * math.sqrt(Ka), math.sqrt(Ka)
    else:
        t_min, ta_min = Tv + Ka / Tv, Ka / Tv
    if duration is None:
        return t_min, ta_min
    T = float(duration)
    ta = min(T / 2.0, T - Tv)
    if ta <= 0 or ta * (T - ta) < Ka * (1.0 - 1e-12):
        raise ValueError(f"duration: {T:g} s is too short for the velocity and acceleration limits "
                         f"(the minimum is {t_min:.6g} s)")
    return T, ta


def trapezoidal(amplitude: Any, max_velocity: Any, max_acceleration: Any, duration: float | None = None,
                start: Any = 0.0, n: int | None = None) -> Reference:
    """Synchronised trapezoidal-velocity move (module docstring); limits in rad/s and rad/s^2 per joint."""
    n = n or np.size(amplitude)
    amp, q0 = _vec(amplitude, n), _vec(start, n)
    T, ta = trapezoid_timing(amp, _vec(max_velocity, n), _vec(max_acceleration, n), duration)
    if T == 0.0:
        return step_reference(np.zeros(n), q0, n)
    c = T - ta
    a = 1.0 / (ta * c)  # normalised acceleration; peak normalised velocity a ta = 1/c

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.clip(np.atleast_1d(np.asarray(t, float)), 0.0, T)
        rise, fall = t < ta, t > T - ta
        s = np.where(rise, 0.5 * a * t**2, np.where(fall, 1.0 - 0.5 * a * (T - t) ** 2, a * ta * (t - 0.5 * ta)))
        ds = np.where(rise, a * t, np.where(fall, a * (T - t), a * ta))
        dds = np.where(rise, a, np.where(fall, -a, 0.0))
        done = np.atleast_1d(np.asarray(t, float)) >= T
        ds, dds = np.where(done, 0.0, ds), np.where(done, 0.0, dds)
        return _shape(t, q0, amp, s, ds, dds)

    return Reference(evaluate, n, T, 2.0 * math.pi / max(ta, 1e-12),
                     _settings("trapezoidal", q0, amplitude=amp, duration=T, acceleration_time=ta,
                               peak_velocity=np.abs(amp) / c, peak_acceleration=np.abs(amp) * a), tuple(q0))


def via_points(times: Sequence[float], points: Sequence[Any], start: Any = 0.0, n: int | None = None) -> Reference:
    """Clamped cubic spline from rest at ``t = 0`` through displacements ``points`` at ``times`` (s)."""
    from scipy.interpolate import CubicSpline

    n = n or np.size(points[0])
    tk = np.concatenate([[0.0], np.asarray(times, dtype=float)])
    pk = np.vstack([np.zeros(n), np.array([_vec(p, n) for p in points])])
    q0 = _vec(start, n)
    spline = CubicSpline(tk, pk, axis=0, bc_type="clamped")
    d1, d2 = spline.derivative(1), spline.derivative(2)
    T = float(tk[-1])

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        tc = np.clip(t, 0.0, T)
        out = np.empty((t.size, n, 3))
        out[:, :, 0] = q0[None, :] + spline(tc)
        inside = ((t >= 0.0) & (t <= T))[:, None]
        out[:, :, 1] = np.where(inside, d1(tc), 0.0)
        out[:, :, 2] = np.where(inside, d2(tc), 0.0)
        return out

    gap = float(np.min(np.diff(tk)))
    return Reference(evaluate, n, T, 2.0 * math.pi / gap,
                     _settings("via_points", q0, times=tk[1:], points=pk[1:].tolist() if n > 1 else pk[1:, 0]),
                     tuple(q0))


def _trajectory(traj: Any, start: np.ndarray, n: int) -> Reference:
    if traj.kind in ("line", "circle"):
        raise SpecError("simulation.trajectory.kind", f"{traj.kind!r} is an end-effector path, for a task-space "
                        "controller; this controller tracks joints: use quintic, sine, trapezoidal or via_points")
    def joints(value: Any, key: str) -> tuple[float, ...]:
        try:
            return per_joint(value, n, f"simulation.trajectory.{key}")
        except ValueError as exc:
            path, msg = str(exc).split(": ", 1)
            raise SpecError(path, msg) from None

    if traj.kind == "quintic":
        return quintic(joints(traj.amplitude, "amplitude"), traj.duration, start, n)
    if traj.kind == "sine":
        return sine(joints(traj.amplitude, "amplitude"), traj.frequency, start, n)
    if traj.kind == "trapezoidal":
        try:
            return trapezoidal(joints(traj.amplitude, "amplitude"), joints(traj.max_velocity, "max_velocity"),
                               joints(traj.max_acceleration, "max_acceleration"), traj.duration, start, n)
        except ValueError as exc:
            raise SpecError("simulation.trajectory." + str(exc).split(": ", 1)[0], str(exc).split(": ", 1)[1]) from None
    points = [joints(p, f"points[{k}]") for k, p in enumerate(traj.points)]
    return via_points(traj.times, points, start, n)


DEFAULT_TRAJECTORY = {"kind": "quintic", "amplitude": 1.0, "duration": 1.0}
"""The trajectory of a tracking controller whose spec gives none."""


def reference_for(kind: str, sim: Any, n: int = 1) -> Reference:
    """The reference of kind ``"step"`` or ``"trajectory"`` that ``simulation`` describes, for ``n`` joints.

    Raises
    ------
    SpecError
        A per-joint list of the wrong length (``simulation.step``, ``simulation.initial_position``,
        ``simulation.trajectory.amplitude``...) or a trapezoid too short for its limits.
    """
    try:
        start = np.array(per_joint(sim.initial_position if sim.initial_position is not None else 0.0, n,
                                   "simulation.initial_position"))
        if kind == "step":
            return step_reference(per_joint(sim.step, n, "simulation.step"), start, n)
    except ValueError as exc:
        path, msg = str(exc).split(": ", 1)
        raise SpecError(path, msg) from None
    if kind != "trajectory":
        raise SpecError("controller.kind", f"unknown reference kind {kind!r}; known: ['step', 'trajectory']")
    if sim.trajectory is None:
        from designkit.spec.sections import QuinticTrajectory

        return _trajectory(QuinticTrajectory(**DEFAULT_TRAJECTORY), start, n)
    return _trajectory(sim.trajectory, start, n)
