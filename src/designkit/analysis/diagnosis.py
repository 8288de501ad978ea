"""Why a run failed: shortfalls, divergence, limit cycles, linear instability, solver failures.

:func:`diagnose` reads a :class:`~designkit.pipeline.PipelineResult` and returns a frozen
:class:`Diagnosis` that the report renders at the top ("why it failed").  Every sentence is
generated from numbers computed here from the run; nothing is written in advance.  Numbers are
formatted with :func:`designkit.report.certificates.fmt_number` (four significant digits), so they
match the rest of the report; torques are written ``N·m``.

What is diagnosed (SI units: s, rad, rad/s, N·m; derivations in ``docs/diagnosis.md``):

* **Shortfall** of every failing or undecided *required* check: from its ``target`` (``"<= 5 %"``)
  and signed ``margin`` (negative when violated by ``|margin|``), absolute and relative to the limit.
* **Divergence** of the nonlinear run (:func:`divergence_of`): non-finite samples, an integrator
  failure, or an error envelope that keeps growing -- the largest ``|x - xD|`` over the last
  :data:`TAIL_FRACTION` of the run exceeds :data:`GROWTH_FACTOR` times the error scale (the commanded
  step, the move, or the initial error) and the one over the preceding quarter.  Its onset is when
  ``|x - xD|`` first exceeds that scale.  With a saturation element: from when ``|u_command|``
  exceeds the limit, for which fraction of the run, and from when the saturation's gain
  ``|u_applied / u_command|`` stays below the loop's lower gain margin (a conditionally stable loop
  goes unstable when its gain drops below it); whether the integrator has an anti-windup.
* **The settling time the actuator limit allows** on the link ``Km / (s (tau s + 1))`` under
  ``|u| <= U`` (:func:`minimum_settling_time`, time-optimal bang-bang bound) and the limit a
  required settling time needs (:func:`limit_for_settling_time`).
* **Limit cycle** (:func:`measure_oscillation`, :func:`relay_limit_cycle`): a sustained, regular
  oscillation of the position over the last :data:`CYCLE_WINDOW` of the run; for a relay with
  hysteresis its describing-function prediction (:func:`relay_describing_function`,
  :func:`relay_harmonic_balance`) on the loop transfer ``L(s)`` seen by the element (the design's
  loop broken at the plant input, :func:`designkit.verification.loop.loop_frequency_response`), and
  the exact symmetric periodic solution of the relay loop (:func:`relay_periodic_solution`, the
  Tsypkin/Hamel switching condition), which tells how much of the gap is the describing function's
  approximation.
* **Instability of the linear loop**: closed-loop poles with ``Re >= 0``.
* **A solver that did not converge**: an undecided or failed check whose certificate holds a
  ``solver_status`` other than ``"optimal"``.
* **A model mismatch of a model-based law** (:func:`model_error_prediction`; gains ``K1``, ``K2``, an
  ``error_poles`` check, joints tracked, a controller model that differs from the true plant): the
  model-error torque ``tau_plant - tau_model`` along the run
  (:func:`designkit.analysis.experiment1.model_error_torque`) drives
  ``e'' + K2 e' + K1 e = M^^-1 (tau_plant - tau_model)``; its quasi-static response
  ``(M^ K1)^-1 (tau_plant - tau_model)`` against the measured error (joint and instant of the worst),
  ``(M^ K1)^-1 (g - g^)`` at rest at the final configuration (:func:`static_model_error`), the worst
  corner or sample of ``tracking_bounds`` (its certificate); fixes: the factor on ``K1`` that brings
  the predicted error to the limit (the error scales as ``1/K1``; poles scale as its square root at
  the same damping), or the plant's payload or parameter values in ``controller.model``.
* **A path near a singular configuration** (``singularity`` check, from its certificate): condition
  number, instant, configuration, the joint whose motion raises ``1/kappa`` fastest; fixes: damped
  least squares with ``lambda = sigma_max / (2 kappa_max)`` (:func:`damping_for_condition`: the
  check's bound ``1/(2 lambda)`` is then the ``1/sigma_min`` the exact inverse has at the allowed
  condition number), or the first-order move of that joint that brings the condition to the limit.
* **Linear versus nonlinear**: the metrics of :func:`~designkit.verification.time_domain.response_metrics`
  on the ideal linear response (:func:`~designkit.simulation.linear.linear_response`, same instants,
  reference and perturbation, no nonlinear element, noise, delay or sampling) and on the simulation.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from designkit.report.certificates import fmt_number, fmt_signed

__all__ = [
    "CYCLE_WINDOW",
    "Diagnosis",
    "Divergence",
    "Finding",
    "GROWTH_FACTOR",
    "LimitCycle",
    "MetricPair",
    "Oscillation",
    "PeriodicSolution",
    "TAIL_FRACTION",
    "ModelErrorPrediction",
    "bang_bang_trajectory",
    "damping_for_condition",
    "diagnose",
    "divergence_of",
    "full_thrust_time",
    "limit_for_settling_time",
    "linear_vs_nonlinear",
    "measure_oscillation",
    "minimum_move_time",
    "minimum_settling_time",
    "model_error_prediction",
    "relay_describing_function",
    "relay_harmonic_balance",
    "relay_periodic_solution",
    "shortfall",
    "static_model_error",
]

TAIL_FRACTION = 0.25
"""Final fraction of a run whose error envelope is compared with the error scale (divergence)."""
GROWTH_FACTOR = 2.0
"""A run diverges when its error over the last :data:`TAIL_FRACTION` exceeds this times the error scale
(the commanded step or move) and still grows: a stable loop ends well inside its initial error."""
CYCLE_WINDOW = 0.4
"""Final fraction of a run searched for a sustained oscillation."""
MIN_CYCLES = 3
"""A limit cycle needs at least this many full periods in the window."""
REGULARITY = 0.2
"""Largest relative spread (std/mean) of the measured periods of a limit cycle (noise is irregular)."""
SUSTAINED = 0.8
"""Smallest ratio of the oscillation amplitude in the second half of the window to the first (not decaying)."""
NOISE_FLOOR = 1e-6
"""Oscillations below this fraction of the error scale (rad) are numerical, not limit cycles."""

_TIME_DOMAIN = ("overshoot", "settling_time", "rise_time", "steady_state_error", "tracking_error", "max_control")
_STABILITY = ("routh_hurwitz", "lyapunov", "pole_placement", "robust_box", "robust_grid", "robustness",
              "error_poles", "hurwitz")
_LABELS = {"overshoot": "overshoot", "settling_time": "settling time", "rise_time": "rise time",
           "steady_state_error": "steady-state error", "tracking_error": "tracking error",
           "max_control": "peak |u| commanded", "routh_hurwitz": "Routh-Hurwitz", "lyapunov": "Lyapunov",
           "pole_placement": "pole placement"}


# ----------------------------------------------------------------------------- values


@dataclass(frozen=True)
class Finding:
    """Why one required check failed or is undecided.

    Parameters
    ----------
    check : str
        The check's name, e.g. ``"overshoot"``.
    status : str
        ``"FAIL"`` or ``"UNDECIDED"``.
    requirement : str
        Human text, e.g. ``"overshoot <= 5 %"``.
    achieved : str
        Formatted with its unit, e.g. ``"168.6 %"``; ``""`` when the check has no value.
    shortfall : str
        Absolute, with unit, e.g. ``"163.6 % over the limit"``; ``""`` when not meaningful.
    shortfall_percent : str
        Relative to the limit, e.g. ``"3272 % of the limit"``; ``""`` when not meaningful.
    cause : str
        Diagnosed cause (one or two sentences), ``""`` when the run shows none.
    fix : str
        What would fix it, with numbers where computable, or ``""``: the sentences of ``fixes`` joined.
    fixes : tuple of str
        The distinct fixes ``fix`` is made of, each a sentence of its own (capitalized, ending with a
        period), in order; a report shows a fix shared by several findings once.
    """

    check: str
    status: str
    requirement: str
    achieved: str
    shortfall: str
    shortfall_percent: str
    cause: str
    fix: str
    fixes: tuple[str, ...] = ()


@dataclass(frozen=True)
class LimitCycle:
    """A sustained oscillation of the position at the end of the run.

    Parameters
    ----------
    amplitude : float
        Measured half peak-to-peak of the position over the analysed window (rad).
    frequency : float
        Measured angular frequency (rad/s).
    predicted_amplitude : float or None
        Describing-function prediction of the position's first-harmonic amplitude (rad); None when
        the element has no describing function here or harmonic balance has no solution.
    predicted_frequency : float or None
        Describing-function prediction (rad/s).
    sentence : str
        Measured and predicted values in words.
    """

    amplitude: float
    frequency: float
    predicted_amplitude: float | None
    predicted_frequency: float | None
    sentence: str


@dataclass(frozen=True)
class MetricPair:
    """One metric on the ideal linear response and on the nonlinear simulation (formatted, ``""``: not available)."""

    metric: str
    unit: str
    linear: str
    nonlinear: str


@dataclass(frozen=True)
class Diagnosis:
    """What :func:`diagnose` found.

    Parameters
    ----------
    findings : tuple of Finding
        One per failing or undecided required check, in check order.
    diverged : bool
        The nonlinear run diverged.
    divergence : str
        When and how it diverged (``""`` otherwise).
    limit_cycle : LimitCycle or None
    linear_vs_nonlinear : tuple of MetricPair
        Overshoot, settling time, rise time, steady-state error, peak |u| (step runs); max tracking error,
        settling time, final error, peak |u| (trajectory runs).
    """

    findings: tuple[Finding, ...]
    diverged: bool
    divergence: str
    limit_cycle: LimitCycle | None
    linear_vs_nonlinear: tuple[MetricPair, ...]


@dataclass(frozen=True)
class Divergence:
    """Evidence of a diverging run (all times in s from ``time[0]``).

    Parameters
    ----------
    diverged : bool
    reason : str
        ``"non-finite"``, ``"integrator"``, ``"growing"`` or ``""``.
    scale : float
        The error scale (rad): the largest commanded step or move, or the initial error.
    onset : float or None
        When ``|x - xD|`` first exceeds ``scale`` (or the first non-finite sample).
    peaks : tuple of (float, float)
        ``(time, |e|)`` of the largest ``|e|`` of every half-cycle (between sign changes of ``e``).
    growth_rate : float or None
        Slope of ``ln |e|`` over the growing peaks (1/s).
    tail_error, previous_error : float
        Largest ``|e|`` over the last quarter of the run and over the quarter before (rad).
    joint : int
        0-based tracked coordinate with the largest final error.
    """

    diverged: bool
    reason: str
    scale: float
    onset: float | None
    peaks: tuple[tuple[float, float], ...]
    growth_rate: float | None
    tail_error: float
    previous_error: float
    joint: int


@dataclass(frozen=True)
class Oscillation:
    """A sustained oscillation measured on a signal.

    Parameters
    ----------
    amplitude : float
        Half peak-to-peak over the window (signal unit).
    frequency : float
        ``2 pi / period`` (rad/s), the period the mean spacing of the upward mean-crossings.
    mean : float
        Mean of the signal over the window.
    mean_abs_deviation : float
        Mean ``|signal - mean|`` over the window.
    cycles : int
        Full periods in the window.
    start : float
        Start of the window (s).
    """

    amplitude: float
    frequency: float
    mean: float
    mean_abs_deviation: float
    cycles: int
    start: float


@dataclass(frozen=True)
class PeriodicSolution:
    """The exact symmetric periodic solution of a relay-with-hysteresis loop.

    Parameters
    ----------
    frequency : float
        rad/s.
    input_amplitude : float
        Largest ``|u|`` at the relay input over the cycle (N·m).
    output_amplitude : float
        Half peak-to-peak of the observed output (e.g. the position, rad).
    output_mean_abs : float
        Mean ``|output - mean|`` over the cycle.
    """

    frequency: float
    input_amplitude: float
    output_amplitude: float
    output_mean_abs: float


# ----------------------------------------------------------------------------- formatting


def _unit(unit: str) -> str:
    return unit.replace("*", "·")


def _q(value: float | None, unit: str = "", digits: int = 4) -> str:
    """``value`` formatted as the report does, with its unit (``""`` for None)."""
    if value is None:
        return ""
    text = fmt_number(value, digits)
    unit = _unit(unit)
    if unit == "1" or unit.startswith("1 ("):  # dimensionless ("1", "1 (scaled)")
        unit = unit[2:]
    if not unit:
        return text
    return f"{text}{unit}" if unit in ("°",) else f"{text} {unit}"


def _t(value: float) -> str:
    return f"t = {fmt_number(value, 3)} s"


_TARGET = re.compile(r"^\s*(<=|>=|<|>|≤|≥)\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*)$")
_LIMIT = re.compile(r"(?:^|\s)(<=|>=|≤|≥)\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)(?=\s|$)")


def shortfall(target: str, margin: float | None, unit: str) -> tuple[str, str]:
    """The absolute and relative shortfall of a violated ``target`` (``""`` when not meaningful).

    Parameters
    ----------
    target : str
        ``"<= limit unit"`` or ``">= limit unit"``.
    margin : float or None
        Signed margin in ``unit``, negative when violated by ``|margin|``.
    unit : str
        Unit of the margin.

    Returns
    -------
    absolute, relative : str
        E.g. ``("163.6 % over the limit", "3272 % of the limit")``.

    Examples
    --------
    >>> shortfall("<= 5 %", -163.59085, "%")
    ('163.6 % over the limit', '3272 % of the limit')
    >>> shortfall("all first-column entries > 0", -1.0, "1 (scaled)")
    ('', '')
    """
    m = _TARGET.match(target or "") or _LIMIT.search(target or "")
    if m is None or margin is None or not math.isfinite(margin) or margin >= 0:
        return "", ""
    op, limit = m.group(1), float(m.group(2))
    side = "over" if op in ("<=", "<", "≤") else "under"
    absolute = f"{_q(-margin, unit)} {side} the limit"
    relative = f"{fmt_number(100.0 * -margin / abs(limit))} % of the limit" if limit != 0 else ""
    return absolute, relative


# ----------------------------------------------------------------------------- minimum-time bounds on the link


def _reach(t: float, V: float, tau: float) -> float:
    """Position after ``t`` s of full thrust from rest: ``V (t - tau (1 - exp(-t/tau)))``."""
    return V * (t - tau * -math.expm1(-t / tau))


def _braking_distance(v: float, V: float, tau: float) -> float:
    """Distance covered while braking from speed ``v >= 0`` to rest with ``u = -U``: ``tau (v - V ln(1 + v/V))``."""
    return tau * (v - V * math.log1p(v / V))


def _solve_increasing(f: Callable[[float], float], lo: float = 0.0) -> float:
    """Root of an increasing ``f`` with ``f(lo) <= 0`` (bracket doubled from ``lo + 1``, then Brent)."""
    from scipy.optimize import brentq

    hi = lo + 1.0
    while f(hi) < 0:
        hi *= 2.0
    return float(brentq(f, lo, hi, xtol=1e-14, rtol=1e-13))


def full_thrust_time(distance: float, Km: float, tau: float, limit: float) -> float:
    """Time (s) for the link ``tau x'' + x' = Km u`` to cover ``distance`` (rad) from rest with ``u = U``.

    No admissible control gets further in the same time (the step response ``Km (1 - exp(-t/tau))`` is
    non-negative), so this is a strict lower bound on any time to reach ``distance``.
    """
    V = Km * limit
    return _solve_increasing(lambda t: _reach(t, V, tau) - abs(distance))


def bang_bang_trajectory(distance: float, Km: float, tau: float, limit: float) -> tuple[float, float]:
    """Switch time ``t1`` and stop time ``T`` (s) of the rest-to-rest bang-bang move of ``distance`` (rad).

    ``u = +U`` on ``[0, t1]`` then ``-U`` until the speed is zero at ``T = t1 + t2``, with
    ``t2 = tau ln(2 - exp(-t1/tau))``; the move covers ``V (t1 - t2)``, ``V = Km U`` (module docs).
    """
    V, d = Km * limit, abs(distance)

    def t2(t1: float) -> float:
        return tau * math.log(2.0 - math.exp(-t1 / tau))

    t1 = _solve_increasing(lambda s: V * (s - t2(s)) - d)
    return t1, t1 + t2(t1)


def minimum_move_time(distance: float, Km: float, tau: float, limit: float) -> float:
    """Minimum rest-to-rest time (s) of a move of ``distance`` (rad) on the link under ``|u| <= limit`` (N·m)."""
    return bang_bang_trajectory(distance, Km, tau, limit)[1]


def minimum_settling_time(step: float, Km: float, tau: float, limit: float, band: float = 0.02) -> float:
    """Smallest settling time (s) to ``band * |step|`` of a step from rest on the link under ``|u| <= limit``.

    Settling at ``t_s`` needs the position at ``x >= A (1 - band)`` with a speed from which braking at
    ``-U`` stops by ``A (1 + band)``.  If full thrust reaches ``A (1 - band)`` slowly enough, that
    first entry is the answer; otherwise it is the instant the rest-to-rest bang-bang move over
    ``A (1 + band)`` crosses ``A (1 - band)`` (it arrives there at the fastest speed that can still
    stop inside the band).  ``A = |step|``.
    """
    A, V = abs(step), Km * limit
    lo, hi = A * (1.0 - band), A * (1.0 + band)
    t_reach = full_thrust_time(lo, Km, tau, limit)
    v_reach = V * -math.expm1(-t_reach / tau)
    if lo + _braking_distance(v_reach, V, tau) <= hi:
        return t_reach
    t1, _ = bang_bang_trajectory(hi, Km, tau, limit)
    x1, v1 = _reach(t1, V, tau), V * -math.expm1(-t1 / tau)
    if x1 >= lo:  # the band edge is crossed while still accelerating (not for band < 1)
        return full_thrust_time(lo, Km, tau, limit)

    def braking_position(s: float) -> float:  # position s after the switch, u = -U
        return x1 - V * s + tau * (v1 + V) * -math.expm1(-s / tau) - lo

    from scipy.optimize import brentq

    t_stop = tau * math.log1p(v1 / V)  # braking stops at hi > lo, so the band edge is crossed before
    return t1 + float(brentq(braking_position, 0.0, t_stop, xtol=1e-14, rtol=1e-13))


def limit_for_settling_time(step: float, Km: float, tau: float, settling_time: float, band: float = 0.02) -> float:
    """Smallest actuator limit ``U`` (N·m) for which :func:`minimum_settling_time` is ``settling_time`` (s)."""
    from scipy.optimize import brentq

    def f(logU: float) -> float:
        return minimum_settling_time(step, Km, tau, math.exp(logU), band) - settling_time

    lo, hi = -30.0, 30.0
    if f(hi) > 0:
        return math.inf
    return float(math.exp(brentq(f, lo, hi, xtol=1e-13, rtol=1e-13)))


# ----------------------------------------------------------------------------- relay with hysteresis


def relay_describing_function(a: float | np.ndarray, amplitude: float, hysteresis: float) -> complex | np.ndarray:
    """Describing function of the relay with hysteresis for an input ``a sin(w t)``, ``a >= hysteresis``.

    The element (as :func:`designkit.simulation.nonlinear.relay`): ``+M`` once ``u > h``, ``-M`` once
    ``u < -h``.  Its output's first harmonic over the input phasor::

        N(a) = 4 M / (pi a) (sqrt(1 - (h/a)^2) - j h/a)

    Parameters
    ----------
    a : float or ndarray
        Input amplitude (N·m), at least ``hysteresis``.
    amplitude, hysteresis : float
        ``M`` and ``h`` (N·m).
    """
    a = np.asarray(a, dtype=float)
    r = hysteresis / a
    out = 4.0 * amplitude / (np.pi * a) * (np.sqrt(np.clip(1.0 - r**2, 0.0, None)) - 1j * r)
    return complex(out) if out.ndim == 0 else out


def relay_harmonic_balance(loop: Callable[[np.ndarray], np.ndarray], amplitude: float, hysteresis: float,
                           w: np.ndarray) -> list[tuple[float, float]]:
    """Solutions ``(a, w)`` of ``1 + N(a) L(jw) = 0`` for the loop ``u = -L(s) v``, ``v = relay(u)``.

    ``-1/N(a) = -(pi / 4M) (sqrt(a^2 - h^2) + j h)``: its imaginary part does not depend on ``a``, so
    ``Im L(jw) = -pi h / (4 M)`` gives ``w`` (sign changes on the grid ``w``, refined by Brent) and
    ``a = sqrt(h^2 + (4 M Re(-L(jw)) / pi)^2)`` needs ``Re L(jw) <= 0``.

    Parameters
    ----------
    loop : callable
        ``L(jw)`` at an array of frequencies (rad/s).
    amplitude, hysteresis : float
        ``M`` and ``h`` (N·m).
    w : ndarray
        Increasing frequency grid (rad/s) searched for crossings.

    Returns
    -------
    list of (float, float)
        ``(a, w)`` pairs: relay-input amplitude (N·m) and frequency (rad/s), by increasing ``w``.
    """
    from scipy.optimize import brentq

    level = -math.pi * hysteresis / (4.0 * amplitude)

    def f(x: float) -> float:
        return float(np.imag(loop(np.array([x]))[0])) - level

    w = np.asarray(w, dtype=float)
    vals = np.imag(loop(w)) - level
    out = []
    for k in np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0):
        wk = float(brentq(f, w[k], w[k + 1], xtol=1e-12, rtol=1e-12))
        re = float(np.real(loop(np.array([wk]))[0]))
        if re <= 0:
            out.append((math.hypot(hysteresis, 4.0 * amplitude * -re / math.pi), wk))
    return out


def relay_periodic_solution(A: np.ndarray, b: np.ndarray, c: np.ndarray, amplitude: float, hysteresis: float,
                            output: np.ndarray, w_guess: float | None = None, delay: float = 0.0,
                            samples: int = 2001) -> PeriodicSolution | None:
    """Exact symmetric periodic solution of ``z' = A z + b v``, ``u = -c z``, ``v = relay(u)``.

    The relay switches to ``+M`` at ``t = 0``, ``delay`` s after ``u`` rose through ``+h``, and back
    to ``-M`` at ``T/2``.  Over the half period, symmetry ``z(T/2) = -z(0)`` gives
    ``(I + Phi(T/2)) z0 = -Gamma(T/2) M`` with ``Phi(t) = exp(A t)``, ``Gamma(t) = int_0^t exp(A s) ds b``
    (one exponential of the augmented matrix ``[[A, b], [0, 0]]``); the switching condition
    ``u(T/2 - delay) = -h``, i.e. ``c (Phi(T/2 - delay) z0 + Gamma(T/2 - delay) M) = h``, fixes ``T``
    (Tsypkin/Hamel; ``delay = 0``: ``-c z0 = h``).  The root nearest ``w_guess`` whose ``u`` does not
    cross ``-h`` before ``T/2 - delay`` is kept.

    Parameters
    ----------
    A, b, c : ndarray
        Open-loop state space (``n x n``, ``n x 1``, ``1 x n``).
    amplitude, hysteresis : float
        ``M`` and ``h`` (N·m).
    output : ndarray
        Row selecting the observed output (e.g. the position) from ``z``.
    w_guess : float, optional
        Frequency near which to look (rad/s); 1 by default.
    delay : float
        Switching delay (s), e.g. half the simulation step for an element evaluated once per step.
    samples : int
        Points per half period for the amplitudes.

    Returns
    -------
    PeriodicSolution or None
        None when no consistent solution is found.
    """
    from scipy.optimize import brentq

    A = np.asarray(A, float)
    b = np.asarray(b, float).reshape(-1, 1)
    c = np.asarray(c, float).reshape(1, -1)
    out_row = np.asarray(output, float).reshape(1, -1)
    n = A.shape[0]
    M, h = float(amplitude), float(hysteresis)
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n], aug[:n, n:] = A, b
    eye = np.eye(n)

    def pieces(times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        from scipy.linalg import expm  # batched over the leading axis

        E = expm(aug[None, :, :] * np.asarray(times, float)[:, None, None])
        return E[:, :n, :n], E[:, :n, n:] * M

    def g_many(halves: np.ndarray) -> np.ndarray:
        Phi, Gam = pieces(halves)
        Phi_s, Gam_s = pieces(np.maximum(halves - delay, 0.0))
        out = np.full(halves.size, np.nan)
        for k in range(halves.size):
            try:
                z0 = np.linalg.solve(eye + Phi[k], -Gam[k])
            except np.linalg.LinAlgError:
                continue
            out[k] = float((c @ (Phi_s[k] @ z0 + Gam_s[k]))[0, 0]) - h
        return out

    def g(half: float) -> float:
        return float(g_many(np.array([half]))[0])

    guess = w_guess if w_guess else 1.0
    halves = np.pi / (guess * np.logspace(-1.5, 1.5, 600))[::-1]
    halves = halves[halves > delay]
    vals = g_many(halves)
    roots = []
    for k in np.flatnonzero(np.isfinite(vals[:-1]) & np.isfinite(vals[1:]) & (vals[:-1] * vals[1:] < 0)):
        roots.append(float(brentq(g, halves[k], halves[k + 1], xtol=1e-15, rtol=1e-13)))
    for half in sorted(roots, key=lambda x: abs(math.log(np.pi / x / guess))):
        Phi, Gam = pieces(np.array([half, half / (samples - 1)]))
        z0 = np.linalg.solve(eye + Phi[0], -Gam[0])
        Z = np.empty((n, samples))
        Z[:, 0] = z0.ravel()
        for k in range(1, samples):
            Z[:, k] = Phi[1] @ Z[:, k - 1] + Gam[1].ravel()
        s = np.linspace(0.0, half, samples)
        u = -(c @ Z).ravel()
        active = s < half - delay - 1e-12 * half
        if np.any(u[1:][active[1:]] < -h - 1e-9 * max(1.0, h)):  # would switch back before T/2
            continue
        y = (out_row @ Z).ravel()
        # over the other half the output is -y (symmetry): mean 0, half peak-to-peak max |y|
        return PeriodicSolution(frequency=float(np.pi / half), input_amplitude=float(np.max(np.abs(u))),
                                output_amplitude=float(np.max(np.abs(y))),
                                output_mean_abs=float(np.trapezoid(np.abs(y), s) / half))
    return None


# ----------------------------------------------------------------------------- measuring a run


def measure_oscillation(t: np.ndarray, y: np.ndarray, *, window: float = CYCLE_WINDOW,
                        scale: float = 1.0) -> Oscillation | None:
    """A sustained, regular oscillation of ``y`` over the last ``window`` of the run, or None.

    The signal minus its window mean must cross zero upward at least :data:`MIN_CYCLES` + 1 times,
    with periods regular to :data:`REGULARITY`, an amplitude above :data:`NOISE_FLOOR` ``* scale``,
    and an amplitude in the window's second half at least :data:`SUSTAINED` times that of the first.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    if t.size < 8 or not np.all(np.isfinite(y)):
        return None
    start = t[-1] - window * (t[-1] - t[0])
    sel = t >= start
    tw, yw = t[sel], y[sel]
    mean = float(np.mean(yw))
    d = yw - mean
    amp = 0.5 * float(np.max(d) - np.min(d))
    if amp <= NOISE_FLOOR * max(scale, 1e-300):
        return None
    k = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
    if k.size < MIN_CYCLES + 1:
        return None
    crossings = tw[k] + (tw[k + 1] - tw[k]) * (-d[k]) / (d[k + 1] - d[k])
    periods = np.diff(crossings)
    if np.std(periods) > REGULARITY * np.mean(periods):
        return None
    half = tw >= 0.5 * (tw[0] + tw[-1])
    a1 = 0.5 * float(np.ptp(d[~half])) if np.any(~half) else amp
    a2 = 0.5 * float(np.ptp(d[half]))
    if a1 <= 0 or a2 < SUSTAINED * a1 or a2 > a1 / SUSTAINED:
        return None
    # whole periods only for the mean |deviation|
    whole = (tw >= crossings[0]) & (tw <= crossings[-1])
    mad = float(np.mean(np.abs(d[whole])))
    return Oscillation(amplitude=amp, frequency=float(2 * np.pi / np.mean(periods)), mean=mean,
                       mean_abs_deviation=mad, cycles=int(periods.size), start=float(tw[0]))


def _errors(sim: Any) -> np.ndarray:
    tracked = sim.tracked if getattr(sim, "tracked", None) is not None else \
        np.asarray(sim.state, float)[:, list(sim.positions)]
    return np.asarray(tracked, float) - np.asarray(sim.reference, float)[:, :, 0]


def _error_scale(sim: Any, e: np.ndarray) -> float:
    ref = np.asarray(sim.reference, float)[:, :, 0]
    with np.errstate(invalid="ignore"):
        moves = np.max(np.abs(ref - ref[0]), axis=0)
        first = np.abs(e[0])
    vals = [float(v) for v in (*moves, *first) if np.isfinite(v)]
    return max(vals) if vals else 0.0


def _rising(peaks: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """The final run of half-cycle peaks each 1 % above the one before (a last, smaller one cut short by the end
    of the run is left out)."""
    peaks = list(peaks)
    if len(peaks) >= 2 and peaks[-1][1] < peaks[-2][1]:
        peaks = peaks[:-1]
    k0 = len(peaks) - 1
    while k0 > 0 and 1.01 * peaks[k0 - 1][1] < peaks[k0][1]:
        k0 -= 1
    return peaks[k0:]


def divergence_of(sim: Any) -> Divergence:
    """Whether the simulated loop diverged (see the module docstring) and the evidence."""
    t = np.asarray(sim.time, float)
    e = _errors(sim)
    scale = _error_scale(sim, e)
    u = np.asarray(sim.u_command, float).reshape(t.size, -1)
    finite = np.all(np.isfinite(e), axis=1) & np.all(np.isfinite(u), axis=1) & \
        np.all(np.isfinite(np.asarray(sim.state, float)), axis=1)
    failure = dict(sim.settings).get("integrator_failure") if getattr(sim, "settings", None) else None
    n = t.size
    with np.errstate(invalid="ignore"):
        mag = np.abs(e)
    last_ok = int(np.flatnonzero(finite)[-1]) if finite.any() else 0
    joint = int(np.nanargmax(mag[last_ok])) if mag.shape[1] and np.any(np.isfinite(mag[last_ok])) else 0
    ej = e[:, joint]
    tail0, prev0 = int(n * (1 - TAIL_FRACTION)), int(n * (1 - 2 * TAIL_FRACTION))
    with np.errstate(invalid="ignore"):
        tail = float(np.nanmax(mag[tail0:])) if np.any(np.isfinite(mag[tail0:])) else math.inf
        prev = float(np.nanmax(mag[prev0:tail0])) if np.any(np.isfinite(mag[prev0:tail0])) else math.inf
    # half-cycle peaks of the finite part
    peaks: list[tuple[float, float]] = []
    good = np.flatnonzero(np.isfinite(ej))
    if good.size:
        seg_e, seg_t = ej[good], t[good]
        sign = np.sign(seg_e)
        cuts = np.flatnonzero(sign[1:] * sign[:-1] < 0) + 1
        for chunk in np.split(np.arange(seg_e.size), cuts):
            if chunk.size:
                k = chunk[int(np.argmax(np.abs(seg_e[chunk])))]
                peaks.append((float(seg_t[k] - t[0]), float(abs(seg_e[k]))))
    reason = ""
    onset = None
    if not np.all(finite):
        reason, onset = "non-finite", float(t[int(np.flatnonzero(~finite)[0])] - t[0])
    elif failure:
        reason = "integrator"
    elif scale > 0 and tail > GROWTH_FACTOR * scale and tail > prev:
        reason = "growing"
    if reason and onset is None:
        with np.errstate(invalid="ignore"):
            over = np.flatnonzero(np.nanmax(mag, axis=1) > scale) if scale > 0 else np.array([], int)
        onset = float(t[int(over[0])] - t[0]) if over.size else None
    growth = None
    if reason == "growing" and len(peaks) >= 2:
        rising = _rising(peaks)
        rising = rising[1:] if len(rising) >= 3 else rising  # the first is where growth starts, off the envelope
        if len(rising) >= 2 and rising[-1][0] > rising[0][0]:
            tt = np.array([p[0] for p in rising])
            yy = np.log([p[1] for p in rising])
            growth = float(np.polyfit(tt, yy, 1)[0])
    return Divergence(diverged=bool(reason), reason=reason, scale=scale, onset=onset, peaks=tuple(peaks),
                      growth_rate=growth, tail_error=tail, previous_error=prev, joint=joint)


# ----------------------------------------------------------------------------- linear versus nonlinear


def _metrics_of(sim: Any, band: float) -> Any:
    from designkit.verification.time_domain import response_metrics

    with np.errstate(all="ignore"):
        return response_metrics(sim, settling_band=band)


def _linear_run(result: Any) -> Any | None:
    """The ideal linear response on the simulation's instants, reference and perturbation, as a run-like value."""
    from designkit.simulation.linear import linear_response

    sim, design = result.simulation, result.design
    if sim is None or design.closed_loop is None or sim.task_space:
        return None
    t = np.asarray(sim.time, float)
    try:
        pert = np.asarray(sim.perturbation, float)
        positions, u = linear_response(design, t, np.asarray(sim.reference, float), pert if pert.size else None,
                                       plant=result.plant)
    except Exception:  # noqa: BLE001 -- no linear response (e.g. no equilibrium): the column stays empty
        return None
    nx = len(sim.state_names)
    state = np.full((t.size, nx), np.nan)
    state[:, list(sim.positions)] = positions
    return SimpleNamespace(time=t, reference=sim.reference, state=state, positions=sim.positions, tracked=None,
                           u_command=u, u_applied=u, kind=sim.kind)


def linear_vs_nonlinear(result: Any) -> tuple[MetricPair, ...]:
    """The time-domain metrics of the ideal linear response and of the simulation, side by side."""
    return _compare(result)[0]


def _compare(result: Any) -> tuple[tuple[MetricPair, ...], Any]:
    """The metric pairs and the linear response's :class:`ResponseMetrics` (None when not available)."""
    sim = result.simulation
    if sim is None:
        return (), None
    req = result.loaded.spec.requirements
    band = req.settling_band if req is not None else 0.02
    nl = _metrics_of(sim, band)
    lin_run = _linear_run(result)
    lin = _metrics_of(lin_run, band) if lin_run is not None else None
    units = sorted(set(sim.coordinate_units)) if sim.task_space else ["rad"]
    unit = "/".join(units)
    if sim.kind == "trajectory":
        rows = [("max tracking error", unit, "max_tracking_error"), ("settling time", "s", "settling_time"),
                ("final tracking error", unit, "steady_state_error"), ("peak |u| commanded", "N·m", "peak_u_command")]
    else:
        rows = [("overshoot", "%", "overshoot"), ("settling time", "s", "settling_time"),
                ("rise time", "s", "rise_time"), ("steady-state error", unit, "steady_state_error"),
                ("peak |u| commanded", "N·m", "peak_u_command")]
    digits = {"steady_state_error": 3}
    out = []
    for label, u, key in rows:
        d = digits.get(key, 4)
        out.append(MetricPair(label, u, _num(getattr(lin, key) if lin is not None else None, d),
                              _num(getattr(nl, key), d)))
    return tuple(out), lin


def _num(x: float | None, digits: int = 4) -> str:
    return "" if x is None else fmt_number(x, digits)


# ----------------------------------------------------------------------------- model mismatch (model-based laws)

MODEL_PATH_SAMPLES = 2001
"""At most this many instants of the run at which the model-error torque is evaluated."""
PREDICTION_AGREEMENT = 0.5
"""The model-error torque "explains" a measured error when its prediction is within this relative gap."""


@dataclass(frozen=True)
class ModelErrorPrediction:
    """The tracking error the model-error torque of a model-based law predicts along the run.

    With the true plant ``M q'' + h = u`` and the law ``u = M^ (qD'' + K1 e + K2 e') + h^``
    (``e = qD - q``), the errors obey ``e'' + K2 e' + K1 e = M^^-1 (tau_plant - tau_model)``, where
    ``tau_plant - tau_model = ID_plant(q, q', q'') - ID_model(q, q', q'')`` is the model-error torque
    (:func:`designkit.analysis.experiment1.model_error_torque`).  Its quasi-static response is
    ``e = (M^ K1)^-1 (tau_plant - tau_model)``; at rest ``(M^ K1)^-1 (g - g^)``.

    Parameters
    ----------
    time : ndarray, shape (N,)
        Instants of the run (s) at which the prediction is evaluated.
    torque : ndarray, shape (N, n)
        Model-error torque ``tau_plant - tau_model`` (N·m, N for a prismatic joint).
    predicted : ndarray, shape (N, n)
        Quasi-static error ``(M^ K1)^-1 (tau_plant - tau_model)`` (rad or m), sign of ``qD - q``.
    measured : ndarray, shape (N, n)
        Simulated ``|q - qD|`` at the same instants (rad or m).
    static_error : ndarray, shape (n,)
        ``(M^ K1)^-1 (g - g^)`` at the final configuration (rad or m).
    gravity_error : ndarray, shape (n,)
        ``g(q_f) - g^(q_f)`` at the final configuration (N·m).
    """

    time: np.ndarray
    torque: np.ndarray
    predicted: np.ndarray
    measured: np.ndarray
    static_error: np.ndarray
    gravity_error: np.ndarray

    @property
    def joint(self) -> int:
        """0-based joint of the largest measured error."""
        return int(np.unravel_index(int(np.argmax(self.measured)), self.measured.shape)[1])

    @property
    def measured_peak(self) -> float:
        """Largest measured ``|q - qD|`` (rad or m)."""
        return float(np.max(self.measured))

    @property
    def predicted_peak(self) -> float:
        """Largest predicted ``|e|`` over every joint (rad or m)."""
        return float(np.max(np.abs(self.predicted)))


def _model_based(result: Any) -> bool:
    """A model-based joint-space law whose controller model differs from the true plant (gains K1, K2, the
    ``error_poles`` check of ``e'' + K2 e' + K1 e = 0``, joints tracked), both plants robots."""
    from designkit.families import family

    design, plant = result.design, result.plant
    if plant is None or plant is design.plant or not (design.extra or {}).get("model_differs"):
        return False
    if not all(hasattr(p, "robot") for p in (plant, design.plant)) or result.simulation is None:
        return False
    if "K1" not in design.gains or "K2" not in design.gains or result.simulation.task_space:
        return False
    try:
        fam = family(design.kind)
    except Exception:  # noqa: BLE001 -- an unregistered kind: no claim on its error dynamics
        return False
    return fam.motion is None and "error_poles" in fam.checks


def static_model_error(plant: Any, model: Any, K1: Any, q: Any) -> tuple[np.ndarray, np.ndarray]:
    """The error at rest ``(M^(q) K1)^-1 (g(q) - g^(q))`` a model-based law leaves at configuration ``q``.

    Parameters
    ----------
    plant, model : RobotPlant
        The true plant and the controller's model.
    K1 : array_like, shape (n,)
        Position error gains (1/s²).
    q : array_like, shape (n,)
        Configuration (rad or m).

    Returns
    -------
    error, gravity_error : ndarray, shape (n,)
        ``qD - q`` at rest (rad or m) and ``g(q) - g^(q)`` (N·m or N).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[1]
    g = np.asarray(plant.robot.gravity_torque(q, p=plant.model_parameters()), dtype=float).reshape(n)
    g_hat = np.asarray(model.robot.gravity_torque(q, p=model.model_parameters()), dtype=float).reshape(n)
    M_hat = np.asarray(model.robot.mass_matrix(q, p=model.model_parameters()), dtype=float).reshape(n, n)
    k1 = np.broadcast_to(np.asarray(K1, dtype=float), (n,))
    return np.linalg.solve(M_hat * k1[None, :], g - g_hat), g - g_hat


def _quasi_static(plant: Any, model: Any, K1: np.ndarray, q: np.ndarray, qd: np.ndarray,
                  qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Model-error torque and ``(M^ K1)^-1`` of it at a batch of states (shapes (N, n))."""
    from designkit.analysis.experiment1 import model_error_torque

    torque = model_error_torque(plant, model, q, qd, qdd)
    n = q.shape[1]
    M_hat = np.asarray(model.robot.mass_matrix(q, p=model.model_parameters()), dtype=float).reshape(-1, n, n)
    return torque, np.linalg.solve(M_hat * K1[None, None, :], torque[..., None])[..., 0]


def _run_path(sim: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """``(t, q, qd, qdd, |q - qD|)`` of the run, at most :data:`MODEL_PATH_SAMPLES` instants (None if not finite)."""
    t = np.asarray(sim.time, dtype=float)
    state = np.asarray(sim.state, dtype=float)
    q, qd = state[:, list(sim.positions)], state[:, list(sim.velocities)]
    err = np.abs(np.asarray(sim.tracking_errors, dtype=float))
    if t.size < 3 or not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(err))):
        return None
    qdd = np.gradient(qd, t, axis=0)
    stride = max(1, math.ceil(t.size / MODEL_PATH_SAMPLES))
    keep = np.unique(np.append(np.arange(0, t.size, stride), np.argmax(np.max(err, axis=1))))
    return t[keep], q[keep], qd[keep], qdd[keep], err[keep]


def model_error_prediction(result: Any, plant: Any = None, model: Any = None) -> ModelErrorPrediction | None:
    """The quasi-static error the model-error torque predicts along the run (see :class:`ModelErrorPrediction`).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        A run of a model-based joint-space law (its ``simulation``, ``design`` and ``plant``).
    plant : RobotPlant, optional
        The true plant (default ``result.plant``), e.g. one corner of the uncertainty box: its
        torque is evaluated along the simulated path of ``result`` (the error is small, so the path
        barely depends on it).
    model : RobotPlant, optional
        The controller's model (default ``result.design.plant``), e.g. a corrected one.

    Returns
    -------
    ModelErrorPrediction or None
        None when the design is not a model-based joint-space law with a model that differs from
        the plant, or the run is not finite.
    """
    if not _model_based(result):
        return None
    path = _run_path(result.simulation)
    if path is None:
        return None
    t, q, qd, qdd, err = path
    plant = result.plant if plant is None else plant
    model = result.design.plant if model is None else model
    n = q.shape[1]
    K1 = np.broadcast_to(np.asarray(result.design.gains["K1"], dtype=float), (n,)).copy()
    torque, predicted = _quasi_static(plant, model, K1, q, qd, qdd)
    static, gravity = static_model_error(plant, model, K1, q[-1])
    return ModelErrorPrediction(time=t - float(np.asarray(result.simulation.time)[0]), torque=torque,
                                predicted=predicted, measured=err, static_error=static, gravity_error=gravity)


def _differences(plant: Any, model: Any) -> list[str]:
    """``"m6 2.59 (model 2.09)"`` for every parameter on which the model differs from the plant, and friction."""
    out = []
    for p in plant.parameters:
        try:
            believed = model.parameter(p.name).value
        except Exception:  # noqa: BLE001 -- a parameter the model does not have
            continue
        if believed != p.value:
            out.append(f"{p.name} = {_q(p.value, p.unit)} (model {fmt_number(believed)})")
    if plant.robot.friction != model.robot.friction:
        out.append("friction " + ("left out of the model" if plant.robot.friction else "assumed by the model only"))
    return out


def _payload_words(plant: Any, model: Any) -> str:
    """``"the plant carries a 2.5 kg payload on link 6, the model assumes 2 kg"``, ``""`` when the payloads agree."""
    true, believed = getattr(plant, "payload", None), getattr(model, "payload", None)
    if true == believed or true is None:
        return ""
    mass, link = true
    assumed = (f"the model assumes {_q(believed[0], 'kg')}" + (f" on link {believed[1]}" if believed[1] != link
                                                                 else "")) if believed else "the model none"
    return f"the plant carries a {_q(mass, 'kg')} payload on link {link}, {assumed}"


def _joint_unit(plant: Any, j: int, what: str = "position") -> str:
    unit = plant.inputs[j].unit
    return ("m" if what == "position" else "N") if unit == "N" else ("rad" if what == "position" else "N*m")


def _corrected_model(result: Any) -> tuple[Any, str] | None:
    """The controller's model with the true payload (or the true parameter values) and the spec text that gives it."""
    plant, model = result.plant, result.design.plant
    true, believed = getattr(plant, "payload", None), getattr(model, "payload", None)
    if true is not None and true != believed and hasattr(model, "with_payload"):
        try:
            fixed = model.with_payload(*true)
        except Exception:  # noqa: BLE001 -- a payload the model cannot carry: no such fix
            return None
        return fixed, f"controller.model.payload: {{mass: {fmt_number(true[0])}, link: {true[1]}}}"
    changed = {p.name: p.value for p in plant.parameters if model.parameter(p.name).value != p.value}
    if changed:
        try:
            fixed = model.with_params(**changed)
        except Exception:  # noqa: BLE001
            return None
        return fixed, "controller.model.parameters: {" + ", ".join(
            f"{k}: {fmt_number(v)}" for k, v in changed.items()) + "}"
    return None


def _gain_fix(result: Any, predicted: float, limit: float, what: str, unit: str = "rad") -> str:
    """Raise K1 (and K2 at the same damping) so that ``predicted`` (scaling as 1/K1, in ``unit``) meets ``limit``."""
    if not (math.isfinite(predicted) and predicted > limit > 0):
        return ""
    factor = predicted / limit
    K1 = np.atleast_1d(np.asarray(result.design.gains["K1"], dtype=float))
    poles = np.abs(np.asarray(result.design.poles, dtype=complex))
    k1 = f"{_q(float(K1[0]) * factor, '1/s²')}" if np.all(K1[0] == K1) else \
        "(" + ", ".join(fmt_number(float(k) * factor) for k in K1) + ") 1/s²"
    lo, hi = float(np.min(poles)), float(np.max(poles))
    old = _q(lo, "1/s") if math.isclose(lo, hi) else f"{fmt_number(lo)} to {_q(hi, '1/s')}"
    new = _q(lo * math.sqrt(factor), "1/s") if math.isclose(lo, hi) else \
        f"{fmt_number(lo * math.sqrt(factor))} to {_q(hi * math.sqrt(factor), '1/s')}"
    return (f"raise K1 by a factor {fmt_number(factor, 3)} or more (K1 = {k1}; K2 by √{fmt_number(factor, 3)} to keep "
            f"the damping): for a fixed model-error torque the error scales as 1/K1, so the predicted "
            f"{_q(predicted, unit)} {what} falls to the {_q(limit, unit)} limit; the error poles move from "
            f"|p| = {old} to |p| = {new}, and the commanded torques grow with the gains")


def _mismatch_text(result: Any, check: Any) -> tuple[str, str]:
    """Cause and fix of a tracking check failing under a model mismatch ("" when it does not apply)."""
    pred = model_error_prediction(result)
    if pred is None:
        return "", ""
    plant, model = result.plant, result.design.plant
    sim = result.simulation
    j = pred.joint
    k = int(np.argmax(pred.measured[:, j]))
    unit = _joint_unit(plant, j)
    tq_unit = _joint_unit(plant, j, "torque")
    kt = np.unravel_index(int(np.argmax(np.abs(pred.torque))), pred.torque.shape)
    payload = _payload_words(plant, model)
    diffs = _differences(plant, model)
    what = payload or ("; ".join(diffs) if diffs else "same parameters")
    names = sim.coordinate_names
    jn = names[j] if len(names) > j else f"q{j + 1}"
    predicted_j = float(np.max(np.abs(pred.predicted[:, j])))
    gap = _rel(predicted_j, pred.measured_peak)
    cause = (f"the controller's model differs from the true plant ({what}); the model-error torque "
             f"τ_plant − τ_model it leaves uncancelled reaches {_q(float(np.abs(pred.torque[kt])), tq_unit)} at joint "
             f"{kt[1] + 1} ({_t(float(pred.time[kt[0]]))}) and drives ë + K2 ė + K1 e = M̂⁻¹(τ_plant − τ_model); "
             f"its quasi-static response (M̂ K1)⁻¹(τ_plant − τ_model) predicts a peak |e| of "
             f"{_q(predicted_j, unit)} at joint {j + 1} against the measured {_q(pred.measured_peak, unit)} "
             f"(|{jn} − {jn}D| at {_t(float(pred.time[k]))}; {gap}); at rest at the final configuration it is "
             f"(M̂ K1)⁻¹(g − ĝ) = {_q(float(abs(pred.static_error[j])), unit)} at joint {j + 1} "
             f"(g − ĝ = {_q(float(pred.gravity_error[j]), tq_unit)} there)")
    explained = pred.measured_peak > 0 and abs(predicted_j / pred.measured_peak - 1) <= PREDICTION_AGREEMENT
    limit = _check_limit(check)
    predicted, what_error = pred.predicted_peak, "error"
    if check.name == "tracking_bounds":
        corner = _corner_prediction(result, check)
        if corner is None:
            return cause, ""
        peaks, j, bound, at, kind = corner
        unit = _joint_unit(plant, j)
        cause += (f"; the worst run of the uncertainty box is at {kind} ({at}; "
                  f"{check.certificate.get('runs', '?')} runs): {_q(bound, unit)} at joint {j + 1}"
                  f"{_worst_instant(check, j)}, where the "
                  f"model-error torque of that plant along this run predicts {_q(float(peaks[j]), unit)} "
                  f"({_rel(float(peaks[j]), bound)})")
        explained = bound > 0 and abs(float(peaks[j]) / bound - 1) <= PREDICTION_AGREEMENT
        predicted, what_error = float(np.max(peaks)), f"error at {at}"
    if not explained or limit is None:
        return cause, ""
    fixes = [f for f in (_gain_fix(result, predicted, limit, what_error, unit),) if f]
    corrected = _corrected_model(result)
    if corrected is not None:
        fixed, setting = corrected
        if check.name == "tracking_bounds":
            after_corner = _corner_prediction(result, check, model=fixed)
            after = math.nan if after_corner is None else float(np.max(after_corner[0]))
        else:
            after_pred = model_error_prediction(result, model=fixed)
            after = math.nan if after_pred is None else after_pred.predicted_peak
        text = f"give the controller's model the plant's values ({setting})"
        if not math.isfinite(after):
            return cause, "; or ".join(fixes)
        if after <= 1e-9 * limit:
            text += ": the model-error torque then vanishes and so does the predicted error"
        elif after <= limit:
            text += (f": the predicted {what_error} then falls to {_q(after, unit)}, within the "
                     f"{_q(limit, unit)} limit")
        else:
            text += (f": the predicted {what_error} then falls to {_q(after, unit)}, still above the "
                     f"{_q(limit, unit)} limit, so K1 must then still grow by a factor {fmt_number(after / limit, 3)}")
        fixes.append(text)
    return cause, "; or ".join(fixes)


def _worst_instant(check: Any, j: int) -> str:
    """`` (t = 1.93 s)``: when the worst run's error of joint ``j`` peaks (the check's data), ``""`` if unknown."""
    data = getattr(check, "data", None) or {}
    t, err = data.get("time"), data.get("errors")
    if t is None or err is None:
        return ""
    err = np.abs(np.asarray(err, dtype=float))
    t = np.asarray(t, dtype=float)
    if err.ndim != 2 or err.shape[0] != t.size or j >= err.shape[1] or not np.all(np.isfinite(err[:, j])):
        return ""
    return f" ({_t(float(t[int(np.argmax(err[:, j]))] - t[0]))})"


def _check_limit(check: Any) -> float | None:
    m = _TARGET.match(_unit(check.target or ""))
    return float(m.group(2)) if m is not None and m.group(1) in ("<=", "<", "≤") else None


def _corner_prediction(result: Any, check: Any, model: Any = None
                       ) -> tuple[np.ndarray, int, float, str, str] | None:
    """The quasi-static error at the worst parameters of ``tracking_bounds`` along this run.

    Returns
    -------
    (peaks, joint, bound, at, kind) or None
        Predicted peak ``|e|`` per joint (rad or m) on the plant at the certificate's
        ``worst_parameters`` with the controller's ``model`` (default the design's); the 0-based joint of
        the check's bound and that bound; ``"m6 = 2.84"``; ``"a corner"`` or ``"a sample"``.
    """
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    worst = dict(cert.get("worst_parameters") or {})
    bound = cert.get("bound_per_joint_rad")
    path = _run_path(result.simulation)
    if not worst or bound is None or path is None:
        return None
    try:
        corner = result.plant.with_params(**{k: float(v) for k, v in worst.items()})
    except Exception:  # noqa: BLE001 -- parameters the plant does not take: no prediction
        return None
    box = dict(cert.get("box") or {})
    kind = "a corner" if all(float(v) in tuple(map(float, box.get(k, ()))) for k, v in worst.items()) else "a sample"
    _, q, qd, qdd, _ = path
    n = q.shape[1]
    K1 = np.broadcast_to(np.asarray(result.design.gains["K1"], dtype=float), (n,)).copy()
    _, predicted = _quasi_static(corner, result.design.plant if model is None else model, K1, q, qd, qdd)
    bounds = np.asarray(bound, dtype=float)
    j = int(np.argmax(bounds))
    at = ", ".join(f"{k} = {fmt_number(v)}" for k, v in worst.items())
    return np.max(np.abs(predicted), axis=0), j, float(bounds[j]), at, kind


# ----------------------------------------------------------------------------- singular configurations


def damping_for_condition(sigma_min: float, condition: float, max_condition: float) -> float:
    """The damped-least-squares ``lambda`` (units of ``J``'s singular values) whose gain bound ``1/(2 lambda)``
    equals the ``1/sigma_min`` the exact inverse has at the allowed condition number.

    At the worst point ``sigma_max = condition * sigma_min``; with the condition number at
    ``max_condition`` the smallest singular value would be ``sigma_max / max_condition``, so
    ``lambda = sigma_max / (2 max_condition)`` bounds the resolution's gain
    ``max sigma / (sigma^2 + lambda^2) = 1/(2 lambda)`` by that amplification.

    Parameters
    ----------
    sigma_min : float
        Smallest singular value of ``J`` at the worst point (``J`` mixes m/rad and 1 rows: no single unit).
    condition : float
        Condition number of ``J`` there.
    max_condition : float
        The design's limit on the condition number.

    Returns
    -------
    float
        ``lambda`` (same scale as ``J``'s singular values).
    """
    return condition * sigma_min / (2.0 * max_condition)


def _singular_joint(result: Any, q: np.ndarray) -> tuple[int, float] | None:
    """The joint whose motion raises ``1/kappa`` of ``J`` fastest at ``q``, and ``d(1/kappa)/dq`` (1/rad)."""
    task = (result.design.extra or {}).get("task")
    if not task or "rows" not in task:
        return None
    import casadi as ca

    from designkit.models.task import TaskSpace, task_functions

    model = result.design.plant
    try:
        fns = task_functions(model.robot, model.model_parameters(),
                             TaskSpace(tuple(task["rows"]), tuple(task["orientation_target"])))
    except Exception:  # noqa: BLE001 -- no task functions: no joint named
        return None

    def inv_kappa(x: np.ndarray) -> float:
        s = np.linalg.svd(np.asarray(fns.jacobian(ca.DM(x)), dtype=float), compute_uv=False)
        return float(s[-1] / s[0])

    h = 1e-6
    grad = np.array([(inv_kappa(q + h * e) - inv_kappa(q - h * e)) / (2 * h) for e in np.eye(q.size)])
    j = int(np.argmax(np.abs(grad)))
    return j, float(grad[j])


def _singularity_text(result: Any, check: Any) -> tuple[str, str]:
    """Cause and fix of a failing ``singularity`` check, from its certificate."""
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    need = ("worst_condition", "sigma_min_at_worst", "max_condition_allowed", "worst_configuration", "worst_at_s")
    if any(cert.get(k) is None for k in need):
        return "", ""
    kappa, s_min = float(cert["worst_condition"]), float(cert["sigma_min_at_worst"])
    limit = float(cert["max_condition_allowed"])
    q = np.asarray(cert["worst_configuration"], dtype=float)
    config = "q = (" + ", ".join(fmt_number(v if abs(v) > 1e-12 else 0.0, 3) for v in q) + ") rad"
    stretch = cert.get("near_singular_interval_s")
    cause = (f"the path passes near a singular configuration of J: condition number {fmt_number(kappa)} at "
             f"{_t(float(cert['worst_at_s']))} ({config}), {fmt_number(kappa / limit, 3)} times the "
             f"{fmt_number(limit)} allowed; σ_min = {fmt_number(s_min)}, so J⁻¹ amplifies task accelerations by "
             f"1/σ_min = {fmt_number(1 / s_min)} there")
    if stretch:
        share = cert.get("near_singular_fraction")
        cause += f" (above the limit over {stretch}" + (
            f", {fmt_number(100 * float(share), 3)} % of the path)" if share is not None else ")")
    joint = _singular_joint(result, q)
    move = ""
    if joint is not None and joint[1] != 0:
        j, grad = joint
        cause += (f"; the smallest singular value is set by joint {j + 1} (q{j + 1} = {fmt_number(q[j], 3)} rad; "
                  f"d(1/κ)/dq{j + 1} = {fmt_number(grad, 3)} 1/rad, the largest of the joints)")
        step = (1.0 / limit - 1.0 / kappa) / abs(grad)
        target = q[j] + math.copysign(step, grad)
        move = (f"; or move the path away from it: to first order the condition number falls to {fmt_number(limit)} "
                f"about {fmt_number(step, 3)} rad further along joint {j + 1} (q{j + 1} ≈ {fmt_number(target, 3)} "
                "rad at that point)")
    if cert.get("damping") is not None:
        return cause, ""
    lam = damping_for_condition(s_min, kappa, limit)
    shown = float(f"{lam * (1 + 5e-4):.3g}")  # rounded up: still within the bound
    gain = s_min**2 / (s_min**2 + shown**2)
    fix = (f"resolve with damped least squares (controller.damped_least_squares: {{damping: {fmt_number(shown, 3)}}}): "
           f"λ ≥ σ_max/(2 κ_max) = {fmt_number(kappa * s_min)}/(2 × {fmt_number(limit)}) = {fmt_number(lam)} "
           f"bounds "
           f"the resolution's gain by 1/(2λ) = {fmt_number(1 / (2 * shown))}, what J⁻¹ has at condition number "
           f"{fmt_number(limit)}, instead of {fmt_number(1 / s_min)}; the price is a task gain of "
           f"{fmt_number(gain, 3)} along the weakest direction at the worst point") + move
    return cause, fix


# ----------------------------------------------------------------------------- the diagnosis


@dataclass(frozen=True)
class _Context:
    """What the run shows, computed once."""

    divergence: Divergence | None
    divergence_text: str
    divergence_fix: str
    limit_cycle: LimitCycle | None
    cycle_fix: str
    unstable: str
    settling_fix: str


def _spec_nonlinearity(sim: Any) -> dict[str, Any]:
    return dict(dict(sim.settings).get("nonlinearity", {}) or {}) if sim is not None else {}


def _anti_windup(sim: Any) -> str | None:
    """The anti-windup kind (``"none"`` when the controller integrates without one, None when not applicable)."""
    ctrl = dict(dict(sim.settings).get("controller", {}) or {})
    aw = ctrl.get("anti_windup")
    if aw is None:
        return None
    return str(dict(aw).get("kind", "none"))


def _link_parameters(plant: Any) -> tuple[float, float] | None:
    if plant is None or getattr(plant, "kind", None) != "link":
        return None
    try:
        return float(plant.parameter("Km").value), float(plant.parameter("tau").value)
    except Exception:  # noqa: BLE001 -- a link without these parameters: no bound
        return None


def _limits(nl: dict[str, Any], key: str, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(nl.get(key), dtype=float), (n,))


def _saturation_text(result: Any, div: Divergence) -> tuple[str, str]:
    """Sentence on the saturation and windup, and the anti-windup fix ("" when there is no saturation)."""
    sim = result.simulation
    nl = _spec_nonlinearity(sim)
    if nl.get("kind") != "saturation":
        return "", ""
    t = np.asarray(sim.time, float)
    uc = np.asarray(sim.u_command, float).reshape(t.size, -1)
    ua = np.asarray(sim.u_applied, float).reshape(t.size, -1)
    lim = _limits(nl, "limit", uc.shape[1])
    with np.errstate(invalid="ignore"):
        sat = np.any(np.abs(uc) > lim[None, :] * (1 + 1e-12), axis=1)
    if not sat.any():
        return "", ""
    t_sat = float(t[int(np.flatnonzero(sat)[0])] - t[0])
    share = 100.0 * float(np.mean(sat))
    lim_text = "±" + _q(float(lim[0]), "N*m") if np.all(lim == lim[0]) else \
        "±(" + ", ".join(fmt_number(x) for x in lim) + ") N·m"
    text = f"the command saturates at {lim_text} from {_t(t_sat)} ({fmt_number(share, 3)} % of the run)"
    # saturation gain against the loop's lower gain margin
    try:
        from designkit.verification.loop import loop_margins

        margins = loop_margins(result.design)
    except Exception:  # noqa: BLE001 -- no loop transfer: no gain-margin argument
        margins = None
    if margins is not None and math.isfinite(margins.gain_margin) and margins.gain_margin < 1 and uc.shape[1] == 1:
        with np.errstate(divide="ignore", invalid="ignore"):
            gain = np.where(np.abs(uc[:, 0]) > 0, np.abs(ua[:, 0] / uc[:, 0]), 1.0)
        below = gain < margins.gain_margin
        if below.any() and below[-1]:
            k = int(np.flatnonzero(~below)[-1]) + 1 if (~below).any() else 0
            text += (f"; the loop is only conditionally stable (it goes unstable when its gain drops below "
                     f"{fmt_number(margins.gain_margin, 3)} times the design's) and the saturation's gain "
                     f"|u_applied/u_command| is below that {fmt_number(100.0 * float(np.mean(below)), 3)} % of the "
                     f"run, for good from {_t(float(t[k] - t[0]))}")
    aw = _anti_windup(sim)
    xc = np.asarray(sim.controller_state, float)
    fix = ""
    if aw == "none" and xc.size:
        with np.errstate(invalid="ignore"):
            peak = float(np.nanmax(np.abs(xc)))
        text += f", and the integrator winds up (no anti-windup; |{sim.controller_state_names[0]}| reaches " \
                f"{_q(peak, 'rad*s')})" if len(sim.controller_state_names) == 1 else \
                f", and the integrators wind up (no anti-windup; the largest |integral| reaches {_q(peak, 'rad*s')})"
        fix = _anti_windup_trial(result, float(np.min(lim)))
    elif aw not in (None, "none"):
        text += f" (anti-windup: {aw})"
    return text, fix


def _anti_windup_trial(result: Any, limit: float) -> str:
    """Re-simulate with ``simulation.anti_windup: {kind: saturation, value: limit}`` and say what it gives."""
    from designkit.simulation.run import simulate
    from designkit.spec.sections import AntiWindup

    spec = result.loaded.spec
    setting = f"{{kind: saturation, value: {fmt_number(limit)}}}"
    try:
        sim_spec = spec.simulation.model_copy(update={"anti_windup": AntiWindup(kind="saturation", value=limit)})
        trial = simulate(spec.model_copy(update={"simulation": sim_spec}), result.design, plant=result.plant)
    except Exception as exc:  # noqa: BLE001 -- the trial is advice only: say it could not be run
        return f"an anti-windup could not be tried ({type(exc).__name__})"
    div = divergence_of(trial)
    if div.diverged:
        return (f"an anti-windup alone does not help: re-simulated with simulation.anti_windup: {setting}, the "
                "loop still diverges")
    req = spec.requirements
    band = req.settling_band if req is not None else 0.02
    m = _metrics_of(trial, band)
    parts = []
    if m.overshoot is not None:
        parts.append(f"overshoot {_q(m.overshoot, '%')}")
    parts.append(f"settling time {_q(m.settling_time, 's')}" if m.settling_time is not None else
                 f"no settling within the {_q(m.duration, 's')} run")
    if m.steady_state_error is not None:
        parts.append(f"steady-state error {_q(m.steady_state_error, 'rad', 3)}")
    verdict = "stops the divergence" + (
        "" if m.steady_state_error is None or div.scale <= 0 or m.steady_state_error <= 0.05 * div.scale else
        ", but the loop then stalls short of the command")
    text = (f"an anti-windup (simulation.anti_windup: {setting}, the integral torque clamped at the actuator "
            f"limit) {verdict}: re-simulated with it, " + ", ".join(parts))
    law_gains = dict(dict(trial.settings).get("controller", {}) or {}).get("gains", {})
    if "K3" in law_gains and "K4" in law_gains and verdict.endswith("command"):
        ref = np.asarray(trial.reference, float)[-1, 0, 0]
        need = abs(float(law_gains["K3"]) * float(law_gains["K4"]) * ref)
        text += (f" (at rest the integral must cancel the reference feedforward K3 K4 xD = {_q(need, 'N*m')}, "
                 "more than the clamp allows)")
    return text


def _divergence_text(result: Any, div: Divergence) -> tuple[str, str]:
    sim = result.simulation
    name = sim.coordinate_names[div.joint] if len(sim.coordinate_names) > div.joint else "x1"
    unit = sim.coordinate_units[div.joint] if len(sim.coordinate_units) > div.joint else "rad"
    if div.reason == "non-finite":
        how = f"the simulated state stops being finite at {_t(div.onset or 0.0)}"
    elif div.reason == "integrator":
        how = str(dict(sim.settings).get("integrator_failure"))
    else:
        seq = _rising([p for p in div.peaks if p[1] > 0])[-4:]
        peaks = ", ".join(f"{fmt_number(v)} {_unit(unit)} ({_t(tt)})" for tt, v in seq)
        err = f"|{name} − xD|" if len(sim.coordinate_names) == 1 else f"|{name} − {name}D|"
        what = "step" if sim.kind == "step" else "move"
        how = (f"the error {err} first exceeds the {_q(div.scale, unit)} {what} at {_t(div.onset or 0.0)} "
               f"and its half-cycle peaks grow ({peaks}")
        if div.growth_rate is not None and div.growth_rate > 0:
            how += f"; growth rate {_q(div.growth_rate, '1/s', 3)}"
        how += (f"), reaching {fmt_number(div.tail_error / div.scale, 3)} times the {what} over the last "
                f"{fmt_number(100 * TAIL_FRACTION, 2)} % of the run")
    sat, fix = _saturation_text(result, div)
    text = "The nonlinear loop diverges: " + how + "." + (f" {sat[0].upper()}{sat[1:]}." if sat else "")
    return text, fix


def _settling_bound(result: Any) -> str:
    """The settling time the actuator limit allows and the limit the required settling time needs ("" if n/a)."""
    sim, spec = result.simulation, result.loaded.spec
    req = spec.requirements
    nl = _spec_nonlinearity(sim)
    plant = result.plant if result.plant is not None else result.design.plant
    link = _link_parameters(plant)
    if sim is None or link is None or sim.kind != "step" or nl.get("kind") != "saturation":
        return ""
    Km, tau = link
    U = float(np.min(_limits(nl, "limit", 1)))
    ref = np.asarray(sim.reference, float)[:, 0, 0]
    step = float(ref[-1] - np.asarray(sim.position, float)[0])
    if step == 0 or Km <= 0 or tau <= 0:
        return ""
    band = req.settling_band if req is not None else 0.02
    t_min = minimum_settling_time(step, Km, tau, U, band)
    text = (f"the ±{_q(U, 'N*m')} limit allows a settling time to the {fmt_number(100 * band, 3)} % band of at least "
            f"{_q(t_min, 's')} for this {_q(abs(step), 'rad')} step (time-optimal bang-bang bound on "
            f"Km/(s(τs+1)), Km = {fmt_number(Km)} rad/(N·m·s), τ = {_q(tau, 's')})")
    if req is not None and req.settling_time is not None:
        if t_min > req.settling_time:
            need = limit_for_settling_time(step, Km, tau, req.settling_time, band)
            text += (f": the {_q(req.settling_time, 's')} requirement cannot be met with this actuator; it needs "
                     f"an actuator limit of at least {_q(need, 'N*m')}, or a settling time of {_q(t_min, 's')} or more")
        else:
            text += f", within the {_q(req.settling_time, 's')} requirement"
    return text


def _limit_cycle(result: Any, div: Divergence) -> tuple[LimitCycle | None, str]:
    sim = result.simulation
    if sim is None or div.diverged:
        return None, ""
    t = np.asarray(sim.time, float)
    pos = np.asarray(sim.tracked_positions, float)
    scale = max(div.scale, 1e-12)
    best, joint = None, 0
    for j in range(pos.shape[1]):
        osc = measure_oscillation(t, pos[:, j], scale=scale)
        if osc is not None and (best is None or osc.amplitude > best.amplitude):
            best, joint = osc, j
    if best is None:
        return None, ""
    unit = sim.coordinate_units[joint]
    name = sim.coordinate_names[joint]
    nl = _spec_nonlinearity(sim)
    pred_a = pred_w = None
    extra, fix = "", ""
    tried = nl.get("kind") == "relay" and pos.shape[1] == 1 and not sim.task_space
    if tried:
        pred, exact = _relay_prediction(result, best, nl)
        if pred is not None:
            pred_a, pred_w = pred
        if exact is not None:
            agree = (abs(exact.output_amplitude / best.amplitude - 1) <= EXACT_AGREEMENT
                     and abs(exact.frequency / best.frequency - 1) <= EXACT_AGREEMENT)
            extra = (f"; the exact periodic solution of the relay loop gives {_q(exact.output_amplitude, unit)} at "
                     f"{_q(exact.frequency, 'rad/s')} ({_rel(exact.output_amplitude, best.amplitude)} and "
                     f"{_rel(exact.frequency, best.frequency)})")
            if agree and pred is not None:
                extra += ", so the gap is the describing function's first-harmonic approximation"
        fix = _relay_fix(result, nl, best.frequency)
    text = (f"a limit cycle: {name} oscillates with amplitude {_q(best.amplitude, unit)} at "
            f"{_q(best.frequency, 'rad/s')} (period {_q(2 * math.pi / best.frequency, 's')}; measured over the last "
            f"{fmt_number(100 * CYCLE_WINDOW, 2)} % of the run, {best.cycles} periods)")
    if pred_a is not None:
        text += (f"; the describing function of the {_relay_words(nl)} predicts {_q(pred_a, unit)} at "
                 f"{_q(pred_w, 'rad/s')} ({_rel(pred_a, best.amplitude)} and {_rel(pred_w, best.frequency)} "
                 "from the measured values)")
    elif tried:
        text += "; harmonic balance with the relay's describing function has no solution on this loop"
    if tried and result.plant is not None and result.plant is not result.design.plant:
        text += " (predictions on the controller's model of the plant)"
    text += extra
    sentence = text[0].upper() + text[1:] + "."
    return LimitCycle(best.amplitude, best.frequency, pred_a, pred_w, sentence), fix


def _relay_words(nl: dict[str, Any]) -> str:
    return f"relay (±{_q(float(np.min(np.atleast_1d(nl['amplitude']))), 'N*m')}, hysteresis " \
           f"{_q(float(np.min(np.atleast_1d(nl['hysteresis']))), 'N*m')})"


def _rel(pred: float, meas: float) -> str:
    return f"{fmt_signed(100 * (pred - meas) / meas, 2)} %".replace("-", "−") if meas else "—"


EXACT_AGREEMENT = 0.05
"""The exact periodic solution "explains" the measured cycle when both its amplitude and frequency are this close."""


def _switching_delay(sim: Any) -> float:
    """Mean delay (s) of a relay evaluated once per integration step: half the step (0 inside the integrator)."""
    settings = dict(sim.settings)
    per_step = "once per step" in str(settings.get("evaluation", ""))
    dt = settings.get("dt")
    return 0.5 * float(dt) if per_step and isinstance(dt, int | float) else 0.0


def _relay_prediction(result: Any, osc: Oscillation, nl: dict[str, Any]
                      ) -> tuple[tuple[float, float] | None, PeriodicSolution | None]:
    """Describing-function ``(position amplitude, frequency)`` and the exact periodic solution (either None)."""
    from designkit.verification.loop import loop_frequency_response, loop_matrices

    design = result.design
    mats = loop_matrices(design)
    if mats is None:
        return None, None
    M = float(np.atleast_1d(nl["amplitude"])[0])
    h = float(np.atleast_1d(nl["hysteresis"])[0])
    A_ol, b, c = mats
    pos_row = np.zeros(A_ol.shape[0])
    pos_row[design.plant.positions[0]] = 1.0

    delay = _switching_delay(result.simulation)

    def loop(w: np.ndarray) -> np.ndarray:
        w = np.asarray(w, float)
        return loop_frequency_response(design, w) * np.exp(-1j * w * delay)

    w_grid = osc.frequency * np.logspace(-2, 2, 2000)
    sols = relay_harmonic_balance(loop, M, h, w_grid)
    pred = None
    if sols:
        a, w = min(sols, key=lambda s: abs(math.log(s[1] / osc.frequency)))
        # position first harmonic: x1 = P(jw) v = (x1 / v)(jw) * first harmonic of v (4 M / pi)
        eye = np.eye(A_ol.shape[0])
        p = complex((pos_row @ np.linalg.solve(1j * w * eye - A_ol, b)).ravel()[0])
        pred = (4.0 * M / math.pi * abs(p), w)
    exact = None
    if h > 0:
        exact = relay_periodic_solution(A_ol, b, c, M, h, pos_row, w_guess=osc.frequency, delay=delay)
    return pred, exact


def _relay_fix(result: Any, nl: dict[str, Any], w_guess: float) -> str:
    """The hysteresis that brings the cycle's mean |x1 - xD| to the steady-state requirement (exact solution)."""
    from scipy.optimize import brentq

    from designkit.verification.loop import loop_matrices

    req = result.loaded.spec.requirements
    mats = loop_matrices(result.design)
    if req is None or req.steady_state_error is None or mats is None or req.steady_state_error <= 0:
        return ""
    A_ol, b, c = mats
    pos_row = np.zeros(A_ol.shape[0])
    pos_row[result.design.plant.positions[0]] = 1.0
    M = float(np.atleast_1d(nl["amplitude"])[0])
    h = float(np.atleast_1d(nl["hysteresis"])[0])
    delay = _switching_delay(result.simulation)
    target = float(req.steady_state_error)
    w_ref = [w_guess]

    def solve(hh: float) -> PeriodicSolution | None:
        sol = relay_periodic_solution(A_ol, b, c, M, hh, pos_row, w_guess=w_ref[0], delay=delay, samples=501)
        if sol is not None:
            w_ref[0] = sol.frequency
        return sol

    def err(hh: float) -> float:
        sol = solve(hh)
        return math.nan if sol is None else sol.output_mean_abs - target

    if h <= 0 or not err(h) > 0:
        return ""
    hi, lo, f_lo = h, h, math.nan
    for _ in range(30):
        hi, lo = lo, 0.5 * lo
        f_lo = err(lo)
        if not math.isfinite(f_lo) or f_lo <= 0:
            break
    if not math.isfinite(f_lo) or f_lo > 0:
        return ""
    w_ref[0] = w_guess
    h_star = float(brentq(err, lo, hi, xtol=1e-6 * h, rtol=1e-6))
    star = solve(h_star)
    text = (f"reduce the relay hysteresis to {_q(h_star, 'N*m')} or less: the exact periodic solution of the relay "
            f"loop then has a mean |x1 − xD| of {_q(target, 'rad')}")
    if star is not None:
        text += f" (cycle at {_q(star.frequency, 'rad/s')})"
    if delay > 0:
        text += f", the simulation step dt = {_q(2 * delay, 's')} counted as a {_q(delay, 's')} switching delay"
    return text + "; or drive the link with a proportional actuator (the ideal linear loop has no limit cycle)"


def _unstable(result: Any) -> str:
    cl = result.design.closed_loop
    if cl is None:
        return ""
    poles = np.asarray(cl.poles, dtype=complex)
    bad = poles[poles.real >= 0]
    if bad.size == 0:
        return ""
    shown = ", ".join(fmt_number(p) for p in sorted(bad, key=lambda z: (-z.real, z.imag))[:4])
    return (f"the linear closed loop is unstable: {bad.size} of its {poles.size} poles have Re ≥ 0 ({shown} 1/s)")


def _solver(check: Any) -> str:
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    status = cert.get("solver_status")
    if status is None or str(status) == "optimal":
        return ""
    solver = cert.get("solver")
    who = f"the solver {solver}" if solver else "the solver"
    return f"{who} did not converge (status {status!s})"


def _context(result: Any) -> _Context:
    sim = result.simulation
    if sim is None:
        return _Context(None, "", "", None, "", _unstable(result), "")
    div = divergence_of(sim)
    dtext = dfix = ""
    if div is not None and div.diverged:
        dtext, dfix = _divergence_text(result, div)
    cycle, cfix = _limit_cycle(result, div)
    return _Context(div, dtext, dfix, cycle, cfix, _unstable(result), _settling_bound(result))


def _specific(result: Any, check: Any) -> tuple[str, str]:
    """Cause and fix read from the check's own certificate and the design: a path near a singular configuration,
    a tracking error under a model mismatch (``""`` when neither applies)."""
    if check.name == "singularity":
        return _singularity_text(result, check)
    if check.name in ("tracking_bounds", "tracking_error"):
        return _mismatch_text(result, check)
    return "", ""


def _sentence(text: str) -> str:
    text = text.strip().rstrip(";")
    return text[0].upper() + text[1:] + ("" if text.endswith(".") else ".") if text else ""


def _finding(check: Any, ctx: _Context, demand: dict[str, Any], specific: tuple[str, str] = ("", "")) -> Finding:
    label = _LABELS.get(check.name, check.name.replace("_", " "))
    target = _unit(check.target or "")
    requirement = f"{label} {target}" if _TARGET.match(target) else f"{label}: {target}" if target else label
    achieved = ""
    if isinstance(check.achieved, int | float) and not isinstance(check.achieved, bool):
        achieved = _q(float(check.achieved), check.unit)
    elif isinstance(check.achieved, str):
        achieved = check.achieved
    absolute, relative = shortfall(check.target, check.margin, check.unit)
    causes: list[str] = []
    fixes: list[str] = []
    solver = _solver(check)
    if solver:
        causes.append(solver)
        fixes.append("rerun with another solver or a scaled problem (numerics section)")
    if check.name in _TIME_DOMAIN:
        if ctx.divergence is not None and ctx.divergence.diverged:
            causes.append(ctx.divergence_text.rstrip("."))
            if ctx.divergence_fix:
                fixes.append(ctx.divergence_fix)
        elif ctx.limit_cycle is not None:
            causes.append(ctx.limit_cycle.sentence.rstrip("."))
            if ctx.cycle_fix and check.name == "steady_state_error":
                fixes.append(ctx.cycle_fix)
        elif ctx.unstable:
            causes.append(ctx.unstable)
        if check.name == "settling_time" and ctx.settling_fix:
            fixes.append(ctx.settling_fix)
        diverged_saturated = ctx.divergence is not None and ctx.divergence.diverged and demand.get("saturation")
        if demand.get("text") and (check.name == "max_control" or diverged_saturated):
            fixes.append(demand["text"])
        if ctx.unstable and ctx.divergence is not None and ctx.divergence.diverged and ctx.unstable not in causes:
            causes.append(ctx.unstable)
    elif check.name in _STABILITY and ctx.unstable:
        causes.append(ctx.unstable)
    if specific[0]:
        causes.append(specific[0])
    if specific[1]:
        fixes.append(specific[1])
    cause = "; ".join(causes)
    if cause:
        cause = cause[0].upper() + cause[1:]
        cause = cause if cause.endswith(".") else cause + "."
    fix = "; ".join(dict.fromkeys(fixes))
    if fix:
        fix = fix[0].upper() + fix[1:] + ("" if fix.endswith(".") else ".")
    parts = tuple(dict.fromkeys(_sentence(f) for f in fixes if f.strip()))
    return Finding(check=check.name, status=check.status, requirement=requirement, achieved=achieved,
                   shortfall=absolute, shortfall_percent=relative, cause=cause, fix=fix, fixes=parts)


def _demand(result: Any, peak: float | None) -> dict[str, Any]:
    """What the ideal linear loop commands against the actuator limit (saturation) or the max_control requirement."""
    sim = result.simulation
    if peak is None or sim is None:
        return {}
    nl = _spec_nonlinearity(sim)
    req = result.loaded.spec.requirements
    saturation = nl.get("kind") == "saturation"
    if saturation:
        limit = float(np.min(np.atleast_1d(nl["limit"])))
    elif req is not None and req.max_control is not None:
        limit = float(np.min(np.atleast_1d(req.max_control)))
    else:
        return {}
    if not peak > limit:
        return {}
    what = "step" if sim.kind == "step" else "motion"
    return {"saturation": saturation,
            "text": (f"the ideal linear loop itself commands {_q(peak, 'N*m')} for this {what}, "
                     f"{fmt_number(peak / limit, 3)} times the {_q(limit, 'N*m')} limit: slower closed-loop poles "
                     f"(or a smaller {what}) are needed to stay within it")}


def diagnose(result: Any) -> Diagnosis:
    """Diagnose a finished run (see the module docstring).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        Its ``checks``, ``simulation`` (may be None), ``design`` and ``plant``.

    Returns
    -------
    Diagnosis
        Findings for the failing or undecided required checks, divergence, limit cycle and the
        linear-versus-nonlinear metrics.
    """
    ctx = _context(result)
    pairs, lin = _compare(result)
    demand = _demand(result, None if lin is None else lin.peak_u_command)
    failing: Sequence[Any] = [c for c in result.checks if c.required and c.passed is not True]
    findings = tuple(_finding(c, ctx, demand, _specific(result, c)) for c in failing)
    div = ctx.divergence
    return Diagnosis(findings=findings, diverged=bool(div is not None and div.diverged),
                     divergence=ctx.divergence_text, limit_cycle=ctx.limit_cycle, linear_vs_nonlinear=pairs)
