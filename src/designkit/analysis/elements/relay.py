"""A relay with hysteresis in the loop: its describing function, harmonic balance, the exact periodic solution
of the relay loop (Tsypkin/Hamel), the limit-cycle prediction and the hysteresis that fixes the cycle.

Entry point: :func:`predict_cycle` (the prediction of a measured limit cycle and the fix).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import quantity, relative_gap

ELEMENT = "relay"
"""The element this module explains (``simulation.nonlinearity.kind``)."""

__all__ = [
    "EXACT_AGREEMENT",
    "CyclePrediction",
    "PeriodicSolution",
    "predict_cycle",
    "relay_describing_function",
    "relay_harmonic_balance",
    "relay_periodic_solution",
]

EXACT_AGREEMENT = 0.05
"""The exact periodic solution "explains" the measured cycle when both its amplitude and frequency are this close."""


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


def _relay_words(nl: dict[str, Any]) -> str:
    return f"relay (±{quantity(float(np.min(np.atleast_1d(nl['amplitude']))), 'N*m')}, hysteresis " \
           f"{quantity(float(np.min(np.atleast_1d(nl['hysteresis']))), 'N*m')})"


def _switching_delay(sim: Any) -> float:
    """Mean delay (s) of a relay evaluated once per integration step: half the step (0 inside the integrator)."""
    settings = dict(sim.settings)
    per_step = "once per step" in str(settings.get("evaluation", ""))
    dt = settings.get("dt")
    return 0.5 * float(dt) if per_step and isinstance(dt, int | float) else 0.0


def _relay_prediction(result: Any, frequency: float, nl: dict[str, Any]
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

    w_grid = frequency * np.logspace(-2, 2, 2000)
    sols = relay_harmonic_balance(loop, M, h, w_grid)
    pred = None
    if sols:
        a, w = min(sols, key=lambda s: abs(math.log(s[1] / frequency)))
        # position first harmonic: x1 = P(jw) v = (x1 / v)(jw) * first harmonic of v (4 M / pi)
        eye = np.eye(A_ol.shape[0])
        p = complex((pos_row @ np.linalg.solve(1j * w * eye - A_ol, b)).ravel()[0])
        pred = (4.0 * M / math.pi * abs(p), w)
    exact = None
    if h > 0:
        exact = relay_periodic_solution(A_ol, b, c, M, h, pos_row, w_guess=frequency, delay=delay)
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
    text = (f"reduce the relay hysteresis to {quantity(h_star, 'N*m')} or less: the exact periodic solution of the "
            f"relay loop then has a mean |x1 − xD| of {quantity(target, 'rad')}")
    if star is not None:
        text += f" (cycle at {quantity(star.frequency, 'rad/s')})"
    if delay > 0:
        text += (f", the simulation step dt = {quantity(2 * delay, 's')} counted as a {quantity(delay, 's')} "
                 "switching delay")
    return text + "; or drive the link with a proportional actuator (the ideal linear loop has no limit cycle)"


@dataclass(frozen=True)
class CyclePrediction:
    """What the relay's analysis adds to a measured limit cycle.

    Parameters
    ----------
    text : str
        The words that follow the measurement in the limit-cycle sentence (``"; the describing function of
        the relay ... predicts ..."``, the exact periodic solution), starting with ``"; "``.
    fix : str
        The hysteresis that brings the cycle to the steady-state requirement (``""`` when none is computed).
    amplitude, frequency : float or None
        Describing-function prediction of the position's first-harmonic amplitude and frequency (rad/s).
    """

    text: str
    fix: str
    amplitude: float | None
    frequency: float | None


def predict_cycle(result: Any, amplitude: float, frequency: float, element: dict[str, Any],
                  unit: str) -> CyclePrediction | None:
    """The relay's prediction of a limit cycle measured with ``amplitude`` (in ``unit``) at ``frequency``
    (rad/s), and its fix; None unless ``element`` is a relay on a single joint-space coordinate."""
    sim = result.simulation
    nl = element
    if nl.get("kind") != "relay" or np.asarray(sim.tracked_positions).shape[1] != 1 or sim.task_space:
        return None
    pred_a = pred_w = None
    extra = ""
    pred, exact = _relay_prediction(result, frequency, nl)
    if pred is not None:
        pred_a, pred_w = pred
    if exact is not None:
        agree = (abs(exact.output_amplitude / amplitude - 1) <= EXACT_AGREEMENT
                 and abs(exact.frequency / frequency - 1) <= EXACT_AGREEMENT)
        extra = (f"; the exact periodic solution of the relay loop gives {quantity(exact.output_amplitude, unit)} at "
                 f"{quantity(exact.frequency, 'rad/s')} ({relative_gap(exact.output_amplitude, amplitude)} and "
                 f"{relative_gap(exact.frequency, frequency)})")
        if agree and pred is not None:
            extra += ", so the gap is the describing function's first-harmonic approximation"
    fix = _relay_fix(result, nl, frequency)
    if pred_a is not None:
        text = (f"; the describing function of the {_relay_words(nl)} predicts {quantity(pred_a, unit)} at "
                f"{quantity(pred_w, 'rad/s')} ({relative_gap(pred_a, amplitude)} and {relative_gap(pred_w, frequency)} "
                "from the measured values)")
    else:
        text = "; harmonic balance with the relay's describing function has no solution on this loop"
    if result.plant is not None and result.plant is not result.design.plant:
        text += " (predictions on the controller's model of the plant)"
    return CyclePrediction(text + extra, fix, pred_a, pred_w)
