"""Why a PID/sliding-mode design failed, from its relay condition (``Family.diagnoses``).

The sliding variable obeys ``slm' = p3 slm + g (du + xi)`` (``g = a2 Km/tau > 0`` on the link; ``a2/D^_i`` per
joint on a robot), so with ``du = -M sign(slm)``::

    slm slm' = p3 slm^2 - g (M - xi sign(slm)) |slm|,

negative for every ``slm != 0`` only when ``M > |xi|``.  Where the perturbation opposes the relay by more than
``M``, ``slm`` is pushed off 0 and the response is no longer the plant-independent sliding motion.

* Link (notes section 5.4): ``pid_sm_relay`` failed (``M`` below ``sup|xi|`` over the parameter box), and
  ``pid_sm_in_band`` failing with it: the input-equivalent perturbation of the run's parameter change,
  ``xi_p = (tau/Km)[(1/tau0 - 1/tau) x2 + (Km/tau - Km0/tau0) u0]`` evaluated on the run (:func:`run_xi`), against
  ``M``.
* Robot (the hierarchy of control): ``pid_sm_hierarchy`` failed (some ``M_i`` below its proven ``sup|xi_i|``), and
  ``pid_sm_robot_xi`` / ``pid_sm_robot_in_band`` failing with it: the ``|xi_i|`` the run meets inside the box.

* Link, ``pid_sm_chattering`` over ``requirements.max_chatter_amplitude``: the relay switches the command by
  ``M`` whatever the equivalent control; the fix is the boundary layer ``sat(slm/epsilon)`` whose gain ``M/epsilon``
  is half the smallest critical gain of ``g/(p - p3)`` over the box's corners held as the run holds the command
  (:func:`~designkit.verification.chatter_prediction.layer_fix`), ``controller.epsilon``, re-simulated.

The relay's fix, declared as changes of the spec (:class:`~designkit.synthesis.spec_change.SpecChange`): ``M`` at
``(1 + margin) sup|xi|`` (the largest over the joints on a robot, whose spec gives one ``M``), the value the design
chooses without an ``M``; and, on a robot, ``M`` left out so that the design chooses it per joint.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, quantity
from designkit.families.pid_sliding_mode.data import LinkSlidingData, RobotSlidingData
from designkit.families.pid_sliding_mode.spec import CHATTERING, IN_BAND
from designkit.synthesis.spec_change import SpecChange

__all__ = ["diagnose", "run_xi"]

LINK = ("pid_sm_relay", IN_BAND)
ROBOT = ("pid_sm_hierarchy", "pid_sm_robot_xi", "pid_sm_robot_in_band")


def _up(x: float) -> float:
    """``x`` rounded up to four significant digits (a relay amplitude that keeps at least the margin asked)."""
    e = math.floor(math.log10(abs(x))) - 3
    return float(f"{math.ceil(x / 10.0 ** e - 1e-9) * 10.0 ** e:.4g}")


def run_xi(info: LinkSlidingData, sim: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """``(t, xi_p)``: the input-equivalent perturbation (N*m) of the run's parameter change along the run (zero
    before the change), None without a ``simulation.plant_change`` of ``Km`` or ``tau``."""
    change = (getattr(sim, "settings", None) or {}).get("plant_change") or {}
    values = change.get("values") or {}
    if change.get("time_applied") is None or not {"Km", "tau"} & set(values):
        return None
    Km0, tau0 = (float(v) for v in info.nominal)
    Km, tau = float(values.get("Km", Km0)), float(values.get("tau", tau0))
    t = np.asarray(sim.time, dtype=float)
    x2 = np.asarray(sim.state, dtype=float)[:, sim.velocities[0]]
    u0 = np.asarray(sim.signals["u0"], dtype=float)
    xi = (tau / Km) * ((1.0 / tau0 - 1.0 / tau) * x2 + (Km / tau - Km0 / tau0) * u0)
    return t, np.where(t >= float(change["time_applied"]), xi, 0.0)


def _link_fix(info: LinkSlidingData) -> tuple[str, tuple[SpecChange, ...]]:
    xi, m = float(info.xi_total), float(info.margin)
    value = _up((1.0 + m) * xi)
    text = (f"Give the relay M above sup|ξ| = {quantity(xi, 'N*m')}: M = {quantity(value, 'N*m')} keeps the "
            f"{fmt_number(100 * m)} % margin, the value the design chooses when the spec gives no M.")
    return text, (SpecChange(f"a relay M = {quantity(value, 'N*m')}", (("controller.M", value),)),)


def _link_condition(info: LinkSlidingData) -> str:
    M, xi = float(info.M), float(info.xi_total)
    box = info.box
    xb = info.perturbation
    Km, tau = xb.corner
    return (f"the relay M = {quantity(M, 'N*m')} is below sup|ξ| = {quantity(xi, 'N*m')} over the parameter box "
            f"(Km from {fmt_number(box['Km'][0])} to {fmt_number(box['Km'][1])} (rad/s)/(N·m), τ from "
            f"{quantity(box['tau'][0], 's')} to {quantity(box['tau'][1], 's')}) by {quantity(xi - M, 'N*m')}: the "
            f"parameter change contributes {quantity(float(xb.parameter), 'N*m')} (at Km = {fmt_number(Km)}, "
            f"τ = {quantity(tau, 's')}) and the external perturbation {quantity(float(xb.external), 'N*m')}")


def _link(result: Any, check: Any, info: LinkSlidingData) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    M, xi = float(info.M), float(info.xi_total)
    if xi <= M:
        return None
    consequence = ("where ξ opposes the relay by more than M, slm slm' = p3 slm² − g (M − ξ sign(slm)) |slm| is no "
                   "longer negative, so slm is pushed off 0 and the response is no longer the plant-independent "
                   "sliding motion 1/(1 + a1 s + a2 s²)")
    if check.name == "pid_sm_relay":
        cause = _link_condition(info)[0].upper() + _link_condition(info)[1:] + "; " + consequence + "."
        return (cause, *_link_fix(info))
    from designkit.families.pid_sliding_mode.measure import measure

    sim = result.simulation
    if sim is None:
        return None
    run = measure(result.design, sim)
    cause = (f"|slm| leaves its band: {quantity(run.worst, 'rad*s')} at t = {quantity(run.worst_at, 's')}, "
             f"{fmt_number(run.worst / run.band, 3)} times the {quantity(run.band, 'rad*s')} band, because the relay "
             f"M = {quantity(M, 'N*m')} is below sup|ξ| = {quantity(xi, 'N*m')} on the parameter box (the relay "
             "condition fails); " + consequence)
    found = run_xi(info, sim)
    if found is not None:
        t, xi_run = found
        above = np.abs(xi_run) > M
        if above.any():
            k = int(np.argmax(np.abs(xi_run)))
            dt = float(np.sum(np.diff(t)[above[:-1]]))
            cause += (f". In this run the parameter change's ξ reaches {quantity(float(abs(xi_run[k])), 'N*m')} at "
                      f"t = {quantity(float(t[k]), 's')} and exceeds M for {quantity(dt, 's')} in all, from "
                      f"t = {quantity(float(t[np.argmax(above)]), 's')}")
    return (cause + ".", *_link_fix(info))


def _robot_fix(info: RobotSlidingData) -> tuple[str, tuple[SpecChange, ...]]:
    bound, m = np.asarray(info.bound, dtype=float), float(info.margin)
    per_joint = [_up((1.0 + m) * b) for b in bound]
    value = max(per_joint)
    worst = int(np.argmax(bound))
    text = (f"Give M above the largest proven bound, sup|ξ{worst + 1}| = {quantity(float(bound[worst]), 'N*m')} (the "
            f"spec's M is one value for every joint): M = {quantity(value, 'N*m')} keeps the {fmt_number(100 * m)} % "
            "margin on every joint; or leave M out of the spec, for the design to choose M_i = (1 + margin) sup|ξ_i| "
            "per joint (" + ", ".join(quantity(v, "N*m") for v in per_joint) + ").")
    return text, (SpecChange(f"a relay M = {quantity(value, 'N*m')} on every joint", (("controller.M", value),)),
                  SpecChange("M left out of the spec, for the design to choose per joint", (("controller.M", None),)))


def _robot(result: Any, check: Any, info: RobotSlidingData) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    M, bound, sampled = (np.asarray(v, dtype=float) for v in (info.M, info.bound, info.sampled))
    short = [i for i in range(M.size) if not M[i] > bound[i]]
    if not short:
        return None
    words = "; ".join(
        f"joint {i + 1}'s relay M = {quantity(float(M[i]), 'N*m')} is below its proven sup|ξ{i + 1}| = "
        f"{quantity(float(bound[i]), 'N*m')} by {quantity(float(bound[i] - M[i]), 'N*m')}"
        + (f" and below the {quantity(float(sampled[i]), 'N*m')} attained in its box, so it certainly does not "
           "dominate ξ there" if M[i] < sampled[i] else "") for i in short)
    rule = ("the hierarchy of control needs M_i > sup|ξ_i| on every joint: where ξ_i opposes the relay by more than "
            "M_i, slm_i is pushed off 0 and joint i no longer follows its sliding motion")
    if check.name == "pid_sm_hierarchy":
        return (words[0].upper() + words[1:] + "; " + rule + ".", *_robot_fix(info))
    short_words = ("the relays are below the proven bounds (the hierarchy condition fails: "
                   + ", ".join(f"M{i + 1} = {quantity(float(M[i]), 'N*m')} against sup|ξ{i + 1}| = "
                               f"{quantity(float(bound[i]), 'N*m')}" for i in short) + ")")
    met = next((c for c in result.checks if c.name == "pid_sm_robot_xi"), None)
    peak = np.asarray((met.certificate or {}).get("peak_xi_inside", ()), dtype=float) if met is not None else ()
    over = [i for i in range(len(peak)) if peak[i] > M[i]]
    run = "; ".join(f"inside joint {i + 1}'s box the run meets |ξ{i + 1}| = {quantity(float(peak[i]), 'N*m')}, above "
                    f"M{i + 1} = {quantity(float(M[i]), 'N*m')}" for i in over)
    cause = (run + ", as " if run else "") + short_words + (": the relay is overpowered there" if run else "")
    if check.name == "pid_sm_robot_in_band":
        cert = check.certificate or {}
        band, worst = cert.get("band", ()), cert.get("worst", ())
        out = [f"joint {i + 1}'s |slm| reaches {quantity(float(worst[i]), 'rad*s')}, "
               f"{fmt_number(float(worst[i]) / float(band[i]), 3)} times its {quantity(float(band[i]), 'rad*s')} "
               "band" for i in range(min(len(band), len(worst))) if worst[i] > band[i]]
        cause = "; ".join(out) + (": " if out else "") + cause
    cause += "; where ξ_i opposes the relay by more than M_i, slm_i is pushed off 0."
    return (cause[0].upper() + cause[1:], *_robot_fix(info))


def _chattering(result: Any, check: Any, info: LinkSlidingData) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    """The boundary layer that removes the chatter the requirement refuses."""
    import itertools

    from designkit.families.pid_sliding_mode.chatter import loop_of
    from designkit.verification.chatter_prediction import layer_fix, layer_words, timing_of

    sim, limit = result.simulation, check.certificate.get("limit")
    if sim is None or limit is None or check.achieved is None or info.epsilon is not None:
        return None
    m, box = float(info.M), info.box
    loops = [loop_of(float(info.p3), float(info.a2) * km / tau) for km, tau in itertools.product(box["Km"], box["tau"])]
    timing = timing_of(result.loaded.spec, sim)
    fix = layer_fix(loops, m, timing)
    if fix is None:
        return None
    eps, k_c = fix
    cause = (f"The relay M = {quantity(m, 'N*m')} switches the command by ±M whatever the equivalent control: "
             f"measured ±{quantity(float(check.achieved), 'N*m')} against the limit {quantity(float(limit), 'N*m')}; "
             "a sign(slm) relay cannot chatter less.")
    fix_words = (f"A boundary layer ε = {eps:.4g} rad·s (controller.epsilon, sat(slm/ε)): "
                 + layer_words(m, eps, k_c, timing, "rad·s", "N·m", "g/(p − p3) over the box's corners") + ".")
    change = SpecChange(f"a boundary layer ε = {eps:.4g} rad·s",
                        (("controller.epsilon", float(f"{eps:.4g}")), ("controller.layer", "saturation"),
                         ("controller.switching_band", None)))
    return cause, fix_words, (change,)


def diagnose(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    """``(cause, fix, changes)`` for a failed relay condition of a PID/sliding-mode design and the run checks that
    fail with it (module docstring), else None."""
    if check.passed is not False:
        return None
    data = result.design.data
    if check.name == CHATTERING and isinstance(data, LinkSlidingData):
        return _chattering(result, check, data)
    if check.name in LINK and isinstance(data, LinkSlidingData):
        return _link(result, check, data)
    if check.name in ROBOT and isinstance(data, RobotSlidingData):
        return _robot(result, check, data)
    return None
