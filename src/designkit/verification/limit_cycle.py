"""The limit cycle a relay sustains in a linear loop: predicted from the loop, before any run.

The loop seen by the switch is linear and single-input single-output: a state space ``x' = A x + B v`` (the
plant, its sliding or switching variable and, when given, a first-order actuator lag) from the relay's output
``v`` (the command's switching input, in the input's unit) to the switching variable ``s = C x``.  The relay
closes it negatively, ``v = -M sign(s)`` (amplitude ``M``), optionally with a hysteresis ``h`` (``v`` turns to
``-M`` once ``s > h`` and to ``+M`` once ``s < -h``), through a pure delay ``L`` and, when the controller is
sampled, a zero-order hold of period ``Ts``.

Three predictions, each for a symmetric orbit (``x(t + T/2) = -x(t)``, half a period at ``-M`` and half at
``+M``; an input bias, such as an equivalent control, makes the orbit asymmetric and is not covered):

* :func:`describing_function` -- the harmonic balance ``G(jw) = -1/N(A)`` with ``N(A) = 4M/(pi A)`` (with
  hysteresis ``-1/N(A) = -(pi/(4M)) (sqrt(A^2 - h^2) + j h)``), ``G`` including the delay ``exp(-jwL)``: the
  frequency and the amplitude of ``s`` and of the command at the fundamental.  An approximation (it assumes the
  loop filters the harmonics away), for a continuous loop with a lag or a delay;
* :func:`continuous_orbit` -- the exact symmetric orbit of the continuous relay loop, in state space: the half
  period ``tau`` at which ``x(tau) = -x(0)``, with ``s`` crossing the switching threshold ``-h`` the delay ``L``
  before the input switches; from the matrix exponential (scipy ``expm``);
* :func:`sampled_orbit` -- the exact periodic orbit of the sampled relay loop: ``k`` samples at ``-M`` and
  ``k`` at ``+M`` (period ``2 k Ts``, frequency ``1/(2 k Ts)``), the state at the orbit solved from the linear
  system ``(Phi^k + I) x0 = -(forced response)`` of the discretised loop, the switching signs checked on every
  sample of the half period; the smallest consistent ``k`` is the prediction.

Without a hold, a lag or a delay (a relay on a loop of relative degree one) the continuous switch has no finite
limit cycle: the ideal relay then slides, switching infinitely often, and a simulation's chatter is set by its
integration step (:func:`no_cycle_words`).  Behind a first-order lag alone (relative degree two, the poles real) it
has none either: the phase of ``G(jw)`` tends to -180 deg without crossing it, the swing decays while the
switching frequency grows, and a simulation's chatter is again set by its step.  A finite continuous cycle needs
a delay, a hysteresis or a relative degree of three or more.

:func:`critical_gain` and :func:`layer_for_gain` size a boundary layer: inside ``|s| < eps`` the relay becomes
the linear gain ``M/eps``, and the oscillation vanishes when that gain is below the loop's critical gain (the
gain at which the sampled, delayed or lagged linear loop loses stability).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

__all__ = ["ContinuousOrbit", "DescribingCycle", "Loop", "SampledOrbit", "continuous_orbit", "critical_gain",
           "describing_function", "layer_for_gain", "no_cycle_words", "relative_degree", "sampled_orbit",
           "sampled_orbits"]

MAX_HALF_PERIOD = 200
"""The sampled orbits searched: ``k`` from 1 to this many samples per half period."""
INTERSAMPLE = 32
"""Points per sample interval (or per half period / 256 for the continuous orbit) where the peaks are read."""


@dataclass(frozen=True)
class Loop:
    """The linear loop seen by the switch.

    Parameters
    ----------
    a, b, c : ndarray
        ``x' = A x + B v``, ``s = C x`` (``A`` n x n, ``B`` n, ``C`` n); ``v`` in the relay's unit (N*m or V),
        ``s`` in the switching variable's.
    outputs : tuple of (str, ndarray)
        Further rows read on the orbit (the plant output, the actuator's output), named.
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    outputs: tuple[tuple[str, np.ndarray], ...] = ()

    @classmethod
    def of(cls, a: Any, b: Any, c: Any, outputs: dict[str, Any] | None = None) -> Loop:
        """A loop from array-likes (``outputs``: name -> row)."""
        a = np.atleast_2d(np.asarray(a, float))
        return cls(a, np.asarray(b, float).reshape(-1), np.asarray(c, float).reshape(-1),
                   tuple((k, np.asarray(v, float).reshape(-1)) for k, v in (outputs or {}).items()))

    @classmethod
    def transfer(cls, num: Any, den: Any) -> Loop:
        """A loop ``s = num(p)/den(p) v`` (strictly proper; coefficients highest power first)."""
        from scipy.signal import tf2ss

        a, b, c, d = tf2ss(np.asarray(num, float), np.asarray(den, float))
        if np.any(np.abs(d) > 0):
            from designkit.errors import SpecError

            raise SpecError("num", "the transfer must be strictly proper (a relay on a direct feedthrough has no "
                            "orbit)")
        return cls.of(a, b, c)

    def with_lag(self, bandwidth: float) -> Loop:
        """The loop behind a first-order actuator lag ``u_a' = bandwidth (v - u_a)`` (rad/s): its state gains
        ``u_a`` (last, also the output ``"actuator"``), which drives the plant where ``v`` did."""
        n = self.a.shape[0]
        a = np.zeros((n + 1, n + 1))
        a[:n, :n], a[:n, n], a[n, n] = self.a, self.b, -bandwidth
        b = np.zeros(n + 1)
        b[n] = bandwidth
        pad = [(k, np.append(r, 0.0)) for k, r in self.outputs]
        return Loop(a, b, np.append(self.c, 0.0), (*pad, ("actuator", np.eye(n + 1)[n])))

    def response(self, omega: np.ndarray, delay: float = 0.0) -> np.ndarray:
        """``G(jw) = C (jw I - A)^-1 B exp(-jwL)`` at ``omega`` (rad/s), delay ``L`` (s)."""
        n = self.a.shape[0]
        out = np.array([self.c @ np.linalg.solve(1j * w * np.eye(n) - self.a, self.b) for w in np.ravel(omega)])
        return out * np.exp(-1j * np.ravel(omega) * delay)


def _positive(**values: float) -> None:
    """Refuse a relay amplitude or a period that is not a positive finite number, naming the argument."""
    from designkit.errors import SpecError

    for name, value in values.items():
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise SpecError(name, f"must be a positive finite number, got {value!r}")


def _hold(a: np.ndarray, b: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """``(exp(A t), int_0^t exp(A r) dr B)`` by one exponential of the augmented matrix."""
    from scipy.linalg import expm

    n = a.shape[0]
    big = np.zeros((n + 1, n + 1))
    big[:n, :n], big[:n, n] = a, b
    e = expm(big * t)
    return e[:n, :n], e[:n, n]


@dataclass(frozen=True)
class DescribingCycle:
    """The describing-function prediction.

    Parameters
    ----------
    frequency : float
        ``w`` (rad/s) where ``G(jw) = -1/N(A)``.
    amplitude : float
        ``A``, the amplitude of ``s`` at the fundamental (the unit of ``s``).
    command : float
        ``4M/pi``, the amplitude of the relay output's fundamental (the relay's unit).
    """

    frequency: float
    amplitude: float
    command: float

    @property
    def hertz(self) -> float:
        """``w/(2 pi)`` (Hz)."""
        return self.frequency / (2 * math.pi)

    @property
    def period(self) -> float:
        """``2 pi/w`` (s)."""
        return 2 * math.pi / self.frequency


def describing_function(loop: Loop, amplitude: float, hysteresis: float = 0.0, delay: float = 0.0,
                        band: tuple[float, float] = (1e-3, 1e6)) -> DescribingCycle | None:
    """Harmonic balance of the relay (amplitude ``M``, hysteresis ``h``, the relay's unit and ``s``'s) on ``loop``
    with a delay (s): the lowest frequency in ``band`` (rad/s) where ``Im G(jw) = -pi h/(4M)`` with
    ``Re G(jw) < 0``; None when the locus never meets ``-1/N`` (no predicted cycle)."""
    from scipy.optimize import brentq

    m = float(amplitude)
    target = -math.pi * hysteresis / (4 * m)

    def im(w: float) -> float:
        return float(loop.response(np.array([w]), delay)[0].imag) - target

    grid = np.geomspace(band[0], band[1], 4000)
    g = loop.response(grid, delay)
    f = g.imag - target
    for i in np.flatnonzero(np.sign(f[:-1]) * np.sign(f[1:]) < 0):
        w = brentq(im, grid[i], grid[i + 1], xtol=1e-14 * grid[i], rtol=1e-13)
        re = float(loop.response(np.array([w]), delay)[0].real)
        if re < 0:
            a = math.hypot(-4 * m * re / math.pi, hysteresis)
            return DescribingCycle(float(w), float(a), 4 * m / math.pi)
    return None


@dataclass(frozen=True)
class ContinuousOrbit:
    """The exact symmetric orbit of the continuous relay loop.

    Parameters
    ----------
    half_period : float
        ``tau`` (s): the input holds ``-M`` for ``tau``, then ``+M`` for ``tau``.
    amplitude : float
        ``max |s|`` on the orbit (the unit of ``s``).
    peaks : tuple of (str, float)
        ``max |y|`` on the orbit of each named output of the loop.
    state : ndarray
        ``x(0)``, the state as the input turns to ``-M``.
    """

    half_period: float
    amplitude: float
    peaks: tuple[tuple[str, float], ...]
    state: np.ndarray

    @property
    def frequency(self) -> float:
        """``1/(2 tau)`` (Hz)."""
        return 1 / (2 * self.half_period)

    def peak(self, name: str) -> float:
        """``max |y|`` of the named output."""
        return dict(self.peaks)[name]


def _orbit_start(loop: Loop, m: float, tau: float) -> np.ndarray | None:
    phi, gam = _hold(loop.a, loop.b, tau)
    lhs = phi + np.eye(phi.shape[0])
    if np.linalg.cond(lhs) > 1e12:
        return None
    return np.linalg.solve(lhs, gam * m)  # x(tau) = phi x0 - gam M = -x0


def _trace(loop: Loop, x0: np.ndarray, v: float, t: np.ndarray) -> np.ndarray:
    """States at the instants ``t`` (s) from ``x0`` under the constant input ``v``."""
    return np.array([phi @ x0 + gam * v for phi, gam in (_hold(loop.a, loop.b, float(ti)) for ti in t)])


def continuous_orbit(loop: Loop, amplitude: float, hysteresis: float = 0.0, delay: float = 0.0,
                     band: tuple[float, float] = (1e-5, 1e3)) -> ContinuousOrbit | None:
    """The exact symmetric orbit (module docstring) of the relay (amplitude ``M``, hysteresis ``h``) on ``loop``
    with a delay ``L`` (s): the shortest half period ``tau`` in ``band`` (s), ``tau > L``, at which ``s``
    reaches ``-h`` downwards exactly ``L`` before the input switches back, ``s`` staying above ``-h`` until
    then.  None when there is none (the loop slides, or diverges)."""
    from scipy.optimize import brentq

    m = float(amplitude)

    def miss(tau: float) -> float:
        x0 = _orbit_start(loop, m, tau)
        if x0 is None:
            return math.nan
        phi, gam = _hold(loop.a, loop.b, tau - delay)
        return float(loop.c @ (phi @ x0 - gam * m)) + hysteresis

    lo = max(band[0], delay * (1 + 1e-9) + band[0])
    grid = np.geomspace(lo, band[1], 500)
    f = np.array([miss(t) for t in grid])
    for i in np.flatnonzero(np.isfinite(f[:-1]) & np.isfinite(f[1:]) & (np.sign(f[:-1]) * np.sign(f[1:]) < 0)):
        tau = brentq(miss, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-13)
        x0 = _orbit_start(loop, m, tau)
        t = np.linspace(0.0, tau, 8 * INTERSAMPLE + 1)
        xs = _trace(loop, x0, -m, t)
        s = xs @ loop.c
        before = t < tau - delay - 1e-9 * tau
        if np.any(s[before] < -hysteresis - 1e-9 * max(1.0, abs(hysteresis))):
            continue  # s met -h earlier: the input would have switched before tau
        peaks = tuple((k, float(np.max(np.abs(xs @ r)))) for k, r in loop.outputs)
        return ContinuousOrbit(float(tau), float(np.max(np.abs(s))), peaks, x0)
    return None


@dataclass(frozen=True)
class SampledOrbit:
    """The periodic orbit of the sampled relay loop (module docstring).

    Parameters
    ----------
    half_period : int
        ``k``: samples at ``-M``, then ``k`` at ``+M``.
    period : float
        ``2 k Ts`` (s).
    amplitude : float
        ``max |s|`` on the orbit, between the samples too (the unit of ``s``).
    sampled_amplitude : float
        ``max |s_j|`` over the samples.
    peaks : tuple of (str, float)
        ``max |y|`` on the orbit of each named output of the loop.
    samples : ndarray
        ``s_j`` over one period (``2 k`` values, from the first sample whose command is ``-M``).
    state : ndarray
        The state at that sample.
    tried : int
        The half periods ``k`` found inconsistent before this one.
    """

    half_period: int
    period: float
    amplitude: float
    sampled_amplitude: float
    peaks: tuple[tuple[str, float], ...]
    samples: np.ndarray
    state: np.ndarray
    tried: int

    @property
    def frequency(self) -> float:
        """``1/(2 k Ts)`` (Hz)."""
        return 1 / self.period

    @property
    def reversal_rate(self) -> float:
        """Reversals of the command per second, ``2/period`` (1/s)."""
        return 2 / self.period

    def peak(self, name: str) -> float:
        """``max |y|`` of the named output."""
        return dict(self.peaks)[name]


def _sampled_matrices(loop: Loop, period: float, delay: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``(Phi, G0, G1, m)``: ``x_{j+1} = Phi x_j + G0 v_{j-m} + G1 v_{j-m-1}`` for a delay ``L = m Ts + r``,
    ``0 <= r < Ts``: over a period the input is ``v_{j-m-1}`` for ``r`` and then ``v_{j-m}``."""
    m = int(math.floor(delay / period + 1e-12))
    r = max(delay - m * period, 0.0)
    if r < 1e-12 * period:
        r = 0.0
    phi, g = _hold(loop.a, loop.b, period)
    if r == 0.0:
        return phi, g, np.zeros_like(g), m
    phi_late, g_late = _hold(loop.a, loop.b, period - r)
    _, g_early = _hold(loop.a, loop.b, r)
    return phi, g_late, phi_late @ g_early, m


def _orbit_of(loop: Loop, amplitude: float, period: float, delay: float, k: int) -> SampledOrbit | None:
    """The symmetric orbit of half period ``k`` samples when its switching signs are consistent, else None."""
    m_amp = float(amplitude)
    phi, g0, g1, m = _sampled_matrices(loop, period, delay)
    n = phi.shape[0]

    def v(j: int) -> float:  # commands -M for j in [0, k), +M for j in [k, 2k), periodic
        return -m_amp if (j % (2 * k)) < k else m_amp

    forced = np.zeros(n)
    for j in range(k):
        forced = phi @ forced + g0 * v(j - m) + g1 * v(j - m - 1)
    lhs = np.linalg.matrix_power(phi, k) + np.eye(n)
    if np.linalg.cond(lhs) > 1e12:
        return None
    x0 = np.linalg.solve(lhs, -forced)
    xs = [x0]
    for j in range(2 * k - 1):
        xs.append(phi @ xs[-1] + g0 * v(j - m) + g1 * v(j - m - 1))
    s = np.array(xs) @ loop.c
    if not (np.all(s[:k] > 0) and np.all(s[k:] < 0)):
        return None
    r = delay - m * period if g1.any() else 0.0
    fine = np.linspace(0.0, period, INTERSAMPLE + 1)[1:]
    holds = [(_hold(loop.a, loop.b, min(t, r)), _hold(loop.a, loop.b, max(t - r, 0.0))) for t in fine]
    pts = []
    for j, x in enumerate(xs):  # the input is v_{j-m-1} for r, then v_{j-m}
        for (ph1, ga1), (ph2, ga2) in holds:
            pts.append(ph2 @ (ph1 @ x + ga1 * v(j - m - 1)) + ga2 * v(j - m))
    every = np.vstack([np.array(xs), np.array(pts)])
    peaks = tuple((name, float(np.max(np.abs(every @ row)))) for name, row in loop.outputs)
    return SampledOrbit(k, 2 * k * period, float(np.max(np.abs(every @ loop.c))), float(np.max(np.abs(s))),
                        peaks, s, x0, 0)


def sampled_orbits(loop: Loop, amplitude: float, period: float, delay: float = 0.0,
                   max_half: int = MAX_HALF_PERIOD) -> list[SampledOrbit]:
    """Every consistent symmetric orbit (module docstring) with ``k`` up to ``max_half``: the relay
    ``v_j = -M sign(s_j)`` sampled every ``period`` (s), each command applied ``delay`` (s) after its sample and
    held.  A sampled relay loop often has several (neighbouring ``k``); which one a run settles on depends on
    where it starts.  With an integrator in the loop each orbit is one of a family shifted along the
    integrator's direction (a neutral direction of the map), and the symmetric member is the one given."""
    _positive(amplitude=amplitude, period=period)
    found = []
    for k in range(1, max_half + 1):
        orbit = _orbit_of(loop, amplitude, period, delay, k)
        if orbit is not None:
            found.append(orbit)
    return found


def sampled_orbit(loop: Loop, amplitude: float, period: float, delay: float = 0.0,
                  max_half: int = MAX_HALF_PERIOD) -> SampledOrbit | None:
    """The consistent symmetric orbit (module docstring) of the smallest ``k`` up to ``max_half`` (its ``tried``
    counts the ``k`` found inconsistent before it), None when there is none; arguments as
    :func:`sampled_orbits`."""
    _positive(amplitude=amplitude, period=period)
    for k in range(1, max_half + 1):
        orbit = _orbit_of(loop, amplitude, period, delay, k)
        if orbit is not None:
            return replace(orbit, tried=k - 1)
    return None


def critical_gain(loop: Loop, period: float = 0.0, delay: float = 0.0, ceiling: float = 1e12) -> float:
    """The smallest gain ``K`` of the linear feedback ``v = -K s`` at which the loop stops being stable (the
    relay's unit per unit of ``s``): on the sampled loop (spectral radius of the closed loop reaching 1), or, when
    continuous, at the first crossing of -180 deg by ``G(jw)`` (with the delay); ``inf`` when no gain up to
    ``ceiling`` destabilises it (a continuous loop of relative degree one without a delay); 0 when a sampled loop
    is not stable at a small gain already."""
    if period > 0:
        phi, g0, g1, m = _sampled_matrices(loop, period, delay)
        n = phi.shape[0]
        d = m + (1 if g1.any() else 0)

        def radius(gain: float) -> float:
            # state (x, v_{j-1}, ..., v_{j-d}) with v_j = -K C x_j
            big = np.zeros((n + d, n + d))
            big[:n, :n] = phi
            fb = -gain * loop.c
            for lag, g in ((m, g0), (m + 1, g1)):
                if not g.any():
                    continue
                if lag == 0:
                    big[:n, :n] += np.outer(g, fb)
                else:
                    big[:n, n + lag - 1] += g
            if d:
                big[n, :n] = fb
                for i in range(1, d):
                    big[n + i, n + i - 1] = 1.0
            return float(np.max(np.abs(np.linalg.eigvals(big))))

        # start where a small gain has moved the loop's slowest pole by 1e-6 of the unit circle (an integrator's
        # pole at 1 then reads inside it above round-off); a loop that gain does not make stable has no margin
        lo = hi = 1e-6 / max(abs(float(loop.c @ loop.b)) * period, 1e-300)
        if radius(hi) >= 1:
            return 0.0
        while radius(hi) < 1 and hi < ceiling:
            lo, hi = hi, hi * 2
        if hi >= ceiling:
            return math.inf
        for _ in range(200):
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if radius(mid) < 1 else (lo, mid)
            if hi / lo < 1 + 1e-12:
                break
        return hi
    cycle = describing_function(loop, 1.0, 0.0, delay)
    if cycle is None:
        return math.inf
    g = loop.response(np.array([cycle.frequency]), delay)[0]
    return float(1 / abs(g))


def layer_for_gain(amplitude: float, gain: float, share: float) -> float:
    """The boundary layer ``eps = M / (share K)`` whose linear gain ``M/eps`` is ``share`` of the gain ``K``
    (``M`` in the relay's unit, ``eps`` in ``s``'s unit)."""
    return float(amplitude) / (share * gain)


def relative_degree(loop: Loop) -> int:
    """The relative degree of ``C (pI - A)^-1 B``: the smallest ``r`` with ``C A^(r-1) B != 0`` (relative to the
    loop's scale), ``n + 1`` when every Markov parameter vanishes."""
    n = loop.a.shape[0]
    scale = max(float(np.max(np.abs(loop.a))), 1e-300)
    v = loop.b.copy()
    ref = float(np.linalg.norm(loop.c)) * float(np.linalg.norm(loop.b))
    for r in range(1, n + 1):
        if abs(float(loop.c @ v)) > 1e-12 * ref * scale ** (r - 1):
            return r
        v = loop.a @ v
    return n + 1


def no_cycle_words(step: float, degree: int = 1) -> str:
    """Why a continuous switch has no finite limit cycle, and what the run's chatter then is (``step`` in s,
    ``degree`` the loop's relative degree: 1, or 2 behind a first-order lag)."""
    if degree == 2:
        return ("the continuous-time switch on a loop of relative degree two (the loop of relative degree one "
                "behind the actuator's first-order lag), without a hold or a delay, has no finite limit cycle in "
                "theory: the phase of G(jω) tends to −180° without crossing it, so the describing function has no "
                "balance and the exact orbit none; the swing of s decays while its frequency grows without bound, "
                f"until the run's integration step {step:.3g} s stops it: the run's chatter is set by that step")
    return ("the continuous-time switch on a loop of relative degree one, without a hold, a lag or a delay, has no "
            "finite limit cycle in theory (it slides, switching infinitely often); the run's chatter is set by its "
            f"integration step {step:.3g} s")
