"""Per-joint reference signals ``(xD, xD', xD'')`` as analytic NumPy functions of time.

Every reference starts at the joints' initial positions ``q0`` and moves each joint ``j`` by its
own displacement ``A_j``; :meth:`Reference.evaluate` returns an array of shape ``(N, n, 3)``:
``[..., j, 0]`` position (rad), ``[..., j, 1]`` velocity (rad/s), ``[..., j, 2]`` acceleration
(rad/s^2).  Shapes, with ``s = clip(t/T, 0, 1)``:

* ``step`` (servo controllers): ``xD = q0 + A`` for ``t >= 0``, ``xD' = xD'' = 0``;
* ``quintic``: ``xD = q0 + A (10 s^3 - 15 s^4 + 6 s^5)`` over ``T``, rest to rest;
* ``sine``: ``xD = q0 + c + A sin(w t + phi)``, ``w = 2 pi frequency``, ``c`` the ``offset`` and ``phi`` the
  ``phase`` (both 0 by default); ``c = A``, ``phi = -pi/2`` gives ``A (1 - cos w t)``, which starts at ``q0`` at
  rest;
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
  ``t_k``;
* ``multisine``: joint ``j`` of ``n`` follows ``xD = q0 + (A/K) sum_i (sin(2 pi h_i t/T + phi_i) - sin phi_i)``
  over ``K`` harmonics ``h_i = j + i n`` (``i = 0 .. K - 1``) of ``1/T``, interleaved so that no two joints share a
  frequency, with Schroeder's phases ``phi_i = -pi i (i - 1)/K`` (a low crest factor): it starts at ``q0`` and
  swings within ``A`` of its centre ``q0 - (A/K) sum_i sin phi_i``.
  A smooth, persistently exciting reference whose joints are orthogonal over a period (identification);
* ``square`` (servos): ``xD = q0 + A`` over the first half of every period ``T``, ``q0 - A`` over the
  second, ``xD' = xD'' = 0``;
* ``prbs`` (servos): ``xD = q0 + A (2 b_k - 1)`` on ``[k T_b, (k + 1) T_b)``, ``b_k`` the output of the
  maximal-length Fibonacci shift register of ``order`` stages (:data:`PRBS_TAPS`, period
  ``2^order - 1`` bits) started from a non-zero state drawn from the seed: a persistently exciting
  signal whose every window of ``2^order - 1`` bits holds each non-zero ``order``-bit pattern once.

:func:`reference_of` gives the reference a design follows in a spec's scenario: the task-space path
of ``design.motion``, else ``simulation.trajectory`` when given, else a step (``simulation.step``) for a
servo and the default quintic for a tracker.  Which kinds a controller family can follow is its own
declaration (:attr:`designkit.synthesis.family.Family.references`), checked when the spec is read.
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

__all__ = ["PRBS_TAPS", "Reference", "multisine", "prbs", "prbs_bits", "quintic", "reference_for", "reference_of",
           "sine", "square", "step_reference", "trapezoidal", "via_points"]


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
    before : tuple of float
        The reference's positions before the motion (default ``start``; a task-space path: the task
        coordinates at ``start``), where the loop is at rest at ``t = 0-`` (:meth:`rest`).
    piecewise_constant : bool
        The reference only jumps (a step, a square wave, a PRBS): the simulator holds its value at each step's
        start over the step, so a jump at ``t_k`` acts from ``t_k`` (and never inside an integrator stage).
    """

    evaluate: Callable[[np.ndarray], np.ndarray]
    n: int
    horizon: float
    rate: float
    settings: Any = field(default_factory=dict)
    start: tuple[float, ...] = ()
    before: tuple[float, ...] = ()
    piecewise_constant: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "settings", freeze(dict(self.settings)))
        object.__setattr__(self, "start", tuple(float(v) for v in self.start) or (0.0,) * self.n)
        object.__setattr__(self, "before", tuple(float(v) for v in self.before) or self.start[:self.n])

    def rest(self) -> np.ndarray:
        """The ``3 n`` law inputs before the motion: positions ``before``, zero velocities and accelerations."""
        return np.concatenate([np.asarray(self.before, dtype=float), np.zeros(2 * self.n)])

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

    return Reference(evaluate, n, 0.0, 0.0, _settings("step", q0, amplitude=amp), tuple(q0), piecewise_constant=True)


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


def sine(amplitude: Any, frequency: float, start: Any = 0.0, n: int | None = None, offset: Any = 0.0,
         phase: Any = 0.0) -> Reference:
    """``xD = start + offset + amplitude sin(2 pi frequency t + phase)`` (rad per joint, Hz, rad per joint, rad per
    joint).

    >>> r = sine([0.5], 1.0, offset=[0.5], phase=[-math.pi / 2])  # 0.5 (1 - cos 2 pi t)
    >>> [round(float(v), 12) for v in r.evaluate(np.array([0.0, 0.5]))[:, 0, 0]]
    [0.0, 1.0]
    """
    n = n or np.size(amplitude)
    amp, q0, w = _vec(amplitude, n), _vec(start, n), 2.0 * math.pi * float(frequency)
    c, phi = _vec(offset, n), _vec(phase, n)

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        arg = w * t[:, None] + phi[None, :]
        out = np.empty((t.size, n, 3))
        out[:, :, 0] = q0[None, :] + c[None, :] + amp[None, :] * np.sin(arg)
        out[:, :, 1] = amp[None, :] * w * np.cos(arg)
        out[:, :, 2] = -amp[None, :] * w**2 * np.sin(arg)
        return out

    extra = {k: v for k, v in (("offset", c), ("phase", phi)) if np.any(v != 0)}
    return Reference(evaluate, n, 3.0 / float(frequency), w,
                     _settings("sine", q0, amplitude=amp, frequency=float(frequency), **extra), tuple(q0))


def multisine(amplitude: Any, period: float, harmonics: int, start: Any = 0.0, n: int | None = None) -> Reference:
    """A sum of ``harmonics`` sines per joint, interleaved between the joints (module docstring): rad, s.

    Examples
    --------
    >>> x = multisine([1.0, 0.5], 10.0, 3).evaluate(np.linspace(0, 10, 2001))[:, :, 0]
    >>> x[0].tolist(), ((x.max(axis=0) - x.min(axis=0)) / 2).round(3).tolist()
    ([0.0, 0.0], [0.831, 0.347])
    """
    n = n or np.size(amplitude)
    amp, q0, T, K = _vec(amplitude, n), _vec(start, n), float(period), int(harmonics)
    i = np.arange(K)
    phase = -math.pi * i * (i - 1) / K
    w = 2.0 * math.pi * (np.arange(1, n + 1)[:, None] + n * i[None, :]) / T  # (n, K) rad/s

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        arg = w[None, :, :] * t[:, None, None] + phase[None, None, :]
        scale = (amp / K)[None, :]
        out = np.empty((t.size, n, 3))
        out[:, :, 0] = q0[None, :] + scale * (np.sin(arg) - np.sin(phase)[None, None, :]).sum(axis=2)
        out[:, :, 1] = scale * (w[None] * np.cos(arg)).sum(axis=2)
        out[:, :, 2] = -scale * (w[None] ** 2 * np.sin(arg)).sum(axis=2)
        return out

    return Reference(evaluate, n, 3.0 * T, float(w.max()),
                     _settings("multisine", q0, amplitude=amp, period=T, harmonics=K), tuple(q0))


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


def square(amplitude: Any, period: float, start: Any = 0.0, n: int | None = None) -> Reference:
    """``xD = start + amplitude`` for the first half of every ``period`` (s), ``start - amplitude`` for the second."""
    n = n or np.size(amplitude)
    amp, q0, T = _vec(amplitude, n), _vec(start, n), float(period)

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        phase = np.mod(t, T) / T
        level = np.where(phase < 0.5 - 1e-12, 1.0, -1.0)
        return _shape(t, q0, amp, level, np.zeros(t.size), np.zeros(t.size))

    return Reference(evaluate, n, 2.0 * T, 0.0, _settings("square", q0, amplitude=amp, period=T), tuple(q0),
                     piecewise_constant=True)


PRBS_TAPS: dict[int, tuple[int, ...]] = {
    3: (3, 2), 4: (4, 3), 5: (5, 3), 6: (6, 5), 7: (7, 6), 8: (8, 6, 5, 4), 9: (9, 5), 10: (10, 7), 11: (11, 9),
    12: (12, 6, 4, 1), 13: (13, 4, 3, 1), 14: (14, 5, 3, 1), 15: (15, 14), 16: (16, 15, 13, 4),
}
"""Feedback taps (stage numbers, 1-based) of a maximal-length Fibonacci shift register per order: primitive
trinomials and pentanomials from the standard tables (e.g. Xilinx XAPP052, 1996); the tests check every
period is ``2^order - 1``."""


def prbs_bits(order: int, count: int, seed: int = 0) -> np.ndarray:
    """``count`` bits (0/1) of the maximal-length shift register of ``order`` stages started from the seed's state.

    The register starts at ``1 + seed mod (2^order - 1)`` (never the all-zero lock-up state); each step outputs
    its last stage and shifts in the XOR of the tapped stages.
    """
    taps = PRBS_TAPS[int(order)]
    state = [(1 + int(seed) % (2**order - 1)) >> k & 1 for k in range(order)]
    out = np.empty(int(count), dtype=np.int8)
    for k in range(int(count)):
        out[k] = state[-1]
        feedback = 0
        for tap in taps:
            feedback ^= state[tap - 1]
        state = [feedback, *state[:-1]]
    return out


def prbs(amplitude: Any, bit: float, order: int = 7, seed: int = 0, start: Any = 0.0, n: int | None = None,
         horizon: float | None = None) -> Reference:
    """A PRBS of positions ``start +- amplitude`` switching at multiples of ``bit`` (s) (module docstring).

    The sequence repeats every ``2^order - 1`` bits; ``horizon`` (s, default one period of the sequence) is how
    long the reference itself lasts for the default duration.
    """
    n = n or np.size(amplitude)
    amp, q0, Tb = _vec(amplitude, n), _vec(start, n), float(bit)
    length = 2**int(order) - 1
    bits = prbs_bits(order, length, seed).astype(float)

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        k = np.mod(np.floor(np.maximum(t, 0.0) / Tb + 1e-9).astype(np.int64), length)
        return _shape(t, q0, amp, 2.0 * bits[k] - 1.0, np.zeros(t.size), np.zeros(t.size))

    span = length * Tb if horizon is None else float(horizon)
    return Reference(evaluate, n, span, 0.0, _settings("prbs", q0, amplitude=amp, bit=Tb, order=int(order),
                                                       seed=int(seed), period_bits=length), tuple(q0),
                     piecewise_constant=True)


def _joints(value: Any, n: int, key: str) -> tuple[float, ...]:
    try:
        return per_joint(value, n, f"simulation.trajectory.{key}")
    except ValueError as exc:
        path, msg = str(exc).split(": ", 1)
        raise SpecError(path, msg) from None


def _trajectory(traj: Any, start: np.ndarray, n: int) -> Reference:
    if traj.kind in ("line", "circle"):
        raise SpecError("simulation.trajectory.kind", f"{traj.kind!r} is an end-effector path, for a task-space "
                        "controller; this controller tracks joints: use quintic, sine, trapezoidal or via_points")
    if traj.kind in ("square", "prbs"):
        raise SpecError("simulation.trajectory.kind", f"{traj.kind!r} jumps between positions, for a servo; a "
                        "tracking controller needs a smooth trajectory: use quintic, sine, trapezoidal or via_points")
    if traj.kind == "quintic":
        return quintic(_joints(traj.amplitude, n, "amplitude"), traj.duration, start, n)
    if traj.kind == "multisine":
        return multisine(_joints(traj.amplitude, n, "amplitude"), traj.period, traj.harmonics, start, n)
    if traj.kind == "sine":
        return sine(_joints(traj.amplitude, n, "amplitude"), traj.frequency, start, n,
                    _joints(traj.offset, n, "offset"), _joints(traj.phase, n, "phase"))
    if traj.kind == "trapezoidal":
        try:
            return trapezoidal(_joints(traj.amplitude, n, "amplitude"), _joints(traj.max_velocity, n, "max_velocity"),
                               _joints(traj.max_acceleration, n, "max_acceleration"), traj.duration, start, n)
        except ValueError as exc:
            raise SpecError("simulation.trajectory." + str(exc).split(": ", 1)[0], str(exc).split(": ", 1)[1]) from None
    points = [_joints(p, n, f"points[{k}]") for k, p in enumerate(traj.points)]
    return via_points(traj.times, points, start, n)


def _servo_reference(traj: Any, start: np.ndarray, n: int) -> Reference:
    """A piecewise-constant ``simulation.trajectory`` (square wave, PRBS) for a servo."""
    if traj.kind == "square":
        return square(_joints(traj.amplitude, n, "amplitude"), traj.period, start, n)
    if traj.kind == "prbs":
        return prbs(_joints(traj.amplitude, n, "amplitude"), traj.bit, traj.order, traj.seed, start, n)
    raise SpecError("simulation.trajectory.kind", f"{traj.kind!r} is a smooth trajectory, for a tracking "
                    "controller; a servo follows simulation.step, or a square or prbs simulation.trajectory")


DEFAULT_TRAJECTORY = {"kind": "quintic", "amplitude": 1.0, "duration": 1.0}
"""The trajectory of a tracking controller whose spec gives none."""


def reference_for(kind: str, sim: Any, n: int = 1) -> Reference:
    """The reference of a ``"step"`` (servo) or ``"trajectory"`` (tracker) design in ``simulation``, for ``n`` joints.

    A servo follows ``simulation.trajectory`` when it is a square wave or a PRBS, else the step
    ``simulation.step``; a tracker follows ``simulation.trajectory`` (default: :data:`DEFAULT_TRAJECTORY`).

    Raises
    ------
    SpecError
        A per-joint list of the wrong length (``simulation.step``, ``simulation.initial_position``,
        ``simulation.trajectory.amplitude``...), a trapezoid too short for its limits, or a trajectory kind
        the design cannot follow (``simulation.trajectory.kind``).
    """
    try:
        start = np.array(per_joint(sim.initial_position if sim.initial_position is not None else 0.0, n,
                                   "simulation.initial_position"))
        if kind == "step" and sim.trajectory is None:
            return step_reference(per_joint(sim.step, n, "simulation.step"), start, n)
    except ValueError as exc:
        path, msg = str(exc).split(": ", 1)
        raise SpecError(path, msg) from None
    if kind == "step":
        return _servo_reference(sim.trajectory, start, n)
    if kind != "trajectory":
        raise SpecError("controller.kind", f"unknown reference kind {kind!r}; known: ['step', 'trajectory']")
    if sim.trajectory is None:
        from designkit.spec.sections import QuinticTrajectory

        return _trajectory(QuinticTrajectory(**DEFAULT_TRAJECTORY), start, n)
    return _trajectory(sim.trajectory, start, n)


def reference_of(spec: Any, design: Any) -> Reference:
    """The reference ``design`` follows in the scenario of ``spec`` (module docstring)."""
    if design.motion is not None:
        return design.motion.reference
    return reference_for(design.reference, spec.simulation, len(design.plant.positions))
