"""An actuator saturation in the loop: why a saturated loop diverges (windup, a conditionally stable loop's
gain margin), whether an anti-windup helps (re-simulated), and the settling time the limit allows at best.

The settling-time bound is the time-optimal (bang-bang) one on the link ``Km / (s (tau s + 1))`` under
``|u| <= U`` (:func:`minimum_settling_time`), and :func:`limit_for_settling_time` inverts it.  Entry
points: :func:`explain_divergence` (the cause and fix of a diverged run) and :func:`settling_bound`
(the fix of a settling time the actuator cannot reach).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from designkit.display.numbers import at_time, fmt_number, quantity

ELEMENT = "saturation"
"""The element this module explains (``simulation.nonlinearity.kind``)."""

__all__ = [
    "bang_bang_trajectory",
    "explain_divergence",
    "full_thrust_time",
    "limit_for_settling_time",
    "minimum_move_time",
    "minimum_settling_time",
    "settling_bound",
]


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


def explain_divergence(result: Any, div: Any, element: dict[str, Any],
                       measure: Callable[[Any], Any]) -> tuple[str, str] | None:
    """Sentence on the saturation and windup of a diverged run, and the anti-windup fix (None without saturation).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
    div : Divergence
        The run's divergence (its ``scale`` is the error scale of the commanded step or move).
    element : dict
        The simulation's nonlinear element (``kind``, ``limit``).
    measure : callable
        ``measure(simulation) -> Divergence``: how the framework measures divergence, applied to the
        anti-windup re-simulation.
    """
    sim = result.simulation
    nl = element
    if nl.get("kind") != "saturation":
        return None
    t = np.asarray(sim.time, float)
    uc = np.asarray(sim.u_command, float).reshape(t.size, -1)
    ua = np.asarray(sim.u_applied, float).reshape(t.size, -1)
    lim = _limits(nl, "limit", uc.shape[1])
    with np.errstate(invalid="ignore"):
        sat = np.any(np.abs(uc) > lim[None, :] * (1 + 1e-12), axis=1)
    if not sat.any():
        return None
    t_sat = float(t[int(np.flatnonzero(sat)[0])] - t[0])
    share = 100.0 * float(np.mean(sat))
    lim_text = "±" + quantity(float(lim[0]), "N*m") if np.all(lim == lim[0]) else \
        "±(" + ", ".join(fmt_number(x) for x in lim) + ") N·m"
    text = f"the command saturates at {lim_text} from {at_time(t_sat)} ({fmt_number(share, 3)} % of the run)"
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
                     f"{fmt_number(margins.gain_margin, 3)} times the design's) and the saturation's gain, the "
                     f"applied over the commanded control, is below that "
                     f"{fmt_number(100.0 * float(np.mean(below)), 3)} % of the run, for good from "
                     f"{at_time(float(t[k] - t[0]))}")
    aw = _anti_windup(sim)
    xc = np.asarray(sim.controller_state, float)
    fix = ""
    if aw == "none" and xc.size:
        with np.errstate(invalid="ignore"):
            peak = float(np.nanmax(np.abs(xc)))
        text += (f", and the integrator winds up (no anti-windup; |{sim.controller_state_names[0]}| reaches "
                 f"{quantity(peak, 'rad*s')})" if len(sim.controller_state_names) == 1 else
                 ", and the integrators wind up (no anti-windup; the largest |integral| reaches "
                 f"{quantity(peak, 'rad*s')})")
        fix = _anti_windup_trial(result, float(np.min(lim)), measure)
    elif aw not in (None, "none"):
        text += f" (anti-windup: {aw})"
    return text, fix


def _anti_windup_trial(result: Any, limit: float, measure: Callable[[Any], Any]) -> str:
    """Re-simulate with ``simulation.anti_windup: {kind: saturation, value: limit}`` and say what it gives."""
    from designkit.families import synthesize
    from designkit.simulation.run import simulate
    from designkit.spec.sections import AntiWindup
    from designkit.verification.time_domain import response_metrics

    spec = result.loaded.spec
    setting = f"the saturation anti-windup at {quantity(limit, 'N*m')}"
    try:
        sim_spec = spec.simulation.model_copy(update={"anti_windup": AntiWindup(kind="saturation", value=limit)})
        trial_spec = spec.model_copy(update={"simulation": sim_spec})
        # the anti-windup is part of the designed law: the trial's design is synthesized from the trial's spec
        trial = simulate(trial_spec, synthesize(trial_spec, result.plant), plant=result.plant)
    except Exception as exc:  # noqa: BLE001 -- the trial is advice only: say it could not be run
        return f"an anti-windup could not be tried ({type(exc).__name__})"
    div = measure(trial)
    if div.diverged:
        return (f"an anti-windup alone does not help: re-simulated with {setting} (simulation.anti_windup), the "
                "loop still diverges")
    req = spec.requirements
    band = req.settling_band if req is not None else 0.02
    with np.errstate(all="ignore"):
        m = response_metrics(trial, settling_band=band)
    parts = []
    if m.overshoot is not None:
        parts.append(f"overshoot {quantity(m.overshoot, '%')}")
    parts.append(f"settling time {quantity(m.settling_time, 's')}" if m.settling_time is not None else
                 f"no settling within the {quantity(m.duration, 's')} run")
    if m.steady_state_error is not None:
        parts.append(f"steady-state error {quantity(m.steady_state_error, 'rad', 3)}")
    verdict = "stops the divergence" + (
        "" if m.steady_state_error is None or div.scale <= 0 or m.steady_state_error <= 0.05 * div.scale else
        ", but the loop then stalls short of the command")
    text = (f"an anti-windup ({setting}, simulation.anti_windup: the integral torque clamped at the actuator "
            f"limit) {verdict}: re-simulated with it, " + ", ".join(parts))
    law_gains = dict(dict(trial.settings).get("controller", {}) or {}).get("gains", {})
    if "K3" in law_gains and "K4" in law_gains and verdict.endswith("command"):
        ref = np.asarray(trial.reference, float)[-1, 0, 0]
        need = abs(float(law_gains["K3"]) * float(law_gains["K4"]) * ref)
        text += (f" (at rest the integral must cancel the reference feedforward K3 K4 xD = {quantity(need, 'N*m')}, "
                 "more than the clamp allows)")
    return text


def settling_bound(result: Any, element: dict[str, Any]) -> str:
    """The settling time the actuator limit allows and the limit the required settling time needs ("" if n/a:
    not a step on a link plant through a saturation ``element``)."""
    sim, spec = result.simulation, result.loaded.spec
    req = spec.requirements
    nl = element
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
    text = (f"the ±{quantity(U, 'N*m')} limit allows a settling time to the {fmt_number(100 * band, 3)} % band of "
            f"at least {quantity(t_min, 's')} for this {quantity(abs(step), 'rad')} step (time-optimal bang-bang "
            f"bound on Km/(s(τs+1)), Km = {fmt_number(Km)} rad/(N·m·s), τ = {quantity(tau, 's')})")
    if req is not None and req.settling_time is not None:
        if t_min > req.settling_time:
            need = limit_for_settling_time(step, Km, tau, req.settling_time, band)
            text += (f": the {quantity(req.settling_time, 's')} requirement cannot be met with this actuator; it "
                     f"needs an actuator limit of at least {quantity(need, 'N*m')}, or a settling time of "
                     f"{quantity(t_min, 's')} or more")
        else:
            text += f", within the {quantity(req.settling_time, 's')} requirement"
    return text
