"""The PID/sliding-mode controller's own checks: its conditions certified on the box, and what the run shows.

``pid_sm_conditions`` (order 55) certifies with the condition-certificate core
(:func:`designkit.verification.conditions.certify`) three labelled sets:

* ``pid_sm_dynamics``: ``-p3 > 0`` (``slm' = p3 slm + ...`` decays), ``a1 > 0`` and ``a2 > 0`` (the sliding
  motion ``1/(1 + a1 s + a2 s^2)`` is stable) and ``a2 Km > 0`` on the box (the relay's gain
  ``g = a2 Km/tau`` is positive, so ``-M sign(slm)`` turns ``slm'`` against ``slm``);
* ``pid_sm_relay``: ``M > sup|xi_p| + xi_e`` (:func:`~designkit.families.pid_sliding_mode.bound.relay_set`);
* ``pid_sm_band`` (a switching band or a dead zone): ``(M - sup|xi|) a2 Km - |p3| band tau > 0``, i.e. the band is
  inside the strip ``|slm| < g (M - sup|xi|)/|p3|`` where ``slm slm' < 0`` for either held sign, so it is invariant
  once entered.

``pid_sm_run`` (order 127) measures the run (:mod:`~designkit.families.pid_sliding_mode.measure`):
``pid_sm_in_band`` (required: after reaching, ``|slm|`` stays in the band), ``pid_sm_precision`` and
``pid_sm_chattering`` (informational: the command's switching judged as physics by
:func:`designkit.verification.switching.judge`, the chatter predicted against measured; required with
``requirements.max_chatter_amplitude``, the measured chatter amplitude against it).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from designkit.families.pid_sliding_mode.bound import PARAMETERS, relay_set
from designkit.families.pid_sliding_mode.data import LinkSlidingData
from designkit.families.pid_sliding_mode.measure import measure
from designkit.families.pid_sliding_mode.spec import CHATTERING, IN_BAND, PRECISION
from designkit.verification.check import Check
from designkit.verification.conditions import Condition, ConditionSet, certify
from designkit.verification.suite import CheckRule, Context

__all__ = ["CERTIFICATE_RULE", "RUN_RULE", "condition_sets", "shortfall"]


def condition_sets(info: LinkSlidingData) -> dict[str, ConditionSet]:
    """The labelled sets the certificate checks (module docstring)."""
    a1, a2, p3, M = info.a1, info.a2, info.p3, info.M
    bound = info.perturbation
    Km0, tau0 = info.nominal
    sets = {
        "pid_sm_dynamics": ConditionSet(
            title="the sliding variable's dynamics and the sliding motion", parameters=PARAMETERS,
            conditions=(
                Condition(f"-p3 > 0 (p3 = {p3:.6g} 1/s)", lambda p: -p3 + 0.0 * p["Km"], "1/s",
                          "slm' = p3 slm + g (du + xi): without the relay slm decays"),
                Condition(f"a1 > 0 (a1 = {a1:.6g} s)", lambda p: a1 + 0.0 * p["Km"], "s",
                          "the sliding motion 1/(1 + a1 s + a2 s^2) is stable"),
                Condition(f"a2 > 0 (a2 = {a2:.6g} s^2)", lambda p: a2 + 0.0 * p["Km"], "s^2",
                          "the sliding motion 1/(1 + a1 s + a2 s^2) is stable"),
                Condition(f"a2 Km > 0 (g = a2 Km/tau, a2 = {a2:.6g} s^2)", lambda p: a2 * p["Km"], "s^2 (rad/s)/(N*m)",
                          "the relay's gain on slm' is positive: -M sign(slm) turns slm' against slm"),
            )),
        "pid_sm_relay": relay_set(M, bound, Km0, tau0),
    }
    band = info.band_certified
    if band is not None:
        xi = info.xi_total
        sets["pid_sm_band"] = ConditionSet(
            title="the band inside the strip where slm slm' < 0", parameters=PARAMETERS,
            conditions=(Condition(
                f"(M - sup|xi|) a2 Km - |p3| band tau > 0 (band = {band:.4g} rad*s)",
                lambda p: (M - xi) * a2 * p["Km"] - abs(p3) * band * p["tau"], "rad",
                "either held sign of the relay turns slm' against slm within the band: it is invariant"),))
    return sets


def shortfall(info: LinkSlidingData) -> str:
    """``"M = 0.8 N*m is below sup|xi| = 1.2 N*m by 0.4 N*m; M >= 1.44 N*m with the 20 % margin"``."""
    M, xi, m = info.M, info.xi_total, info.margin
    xb = info.perturbation
    return (f"M = {M:.4g} N*m is below sup|ξ| = {xi:.4g} N*m (parameter change {xb.parameter:.4g} N*m, "
            f"external {xb.external:.4g} N*m) by {xi - M:.3g} N*m; any M above {xi:.4g} N*m meets the "
            f"condition, M = {(1 + m) * xi:.4g} N*m keeps the {100 * m:g} % margin")


def _certificates(design: Any, ctx: Context) -> tuple[Check, ...]:
    info: LinkSlidingData = design.data
    xb = info.perturbation
    box = {k: tuple(v) for k, v in info.box.items()}
    out = []
    for name, set_ in condition_sets(info).items():
        check = certify(name, set_, box, solver=ctx.solver)
        if name == "pid_sm_relay":
            cert = {**dict(check.certificate), "M": info.M, "sup_xi": info.xi_total,
                    "sup_xi_parameter": xb.parameter, "sup_xi_external": xb.external,
                    "worst_corner": list(xb.corner), "worst_time": xb.at, "shortfall": info.xi_total - info.M}
            detail = check.detail
            if check.passed is False:
                detail = shortfall(info) + ". " + detail[:1].upper() + detail[1:]
            check = dataclasses.replace(check, detail=detail, certificate=cert)
        out.append(check)
    return tuple(out)


CERTIFICATE_RULE = CheckRule(
    name="pid_sm_conditions", order=55, applies=lambda d, c: isinstance(d.data, LinkSlidingData), run=_certificates,
    label="PID/sliding-mode conditions on the parameter box",
    labels={"pid_sm_dynamics": "Sliding variable and sliding motion stable (whole box)",
            "pid_sm_relay": "Relay dominates the input-equivalent perturbation (whole box)",
            "pid_sm_band": "Band invariant around slm = 0 (whole box)"},
    glossary=(("slm", "the sliding variable a1 x1 + a2 x2 + x3, rad·s"),
              ("ξ", "the input-equivalent perturbation: the load plus the parameter change of notes §5.4, N·m")),
)


def _run_checks(design: Any, ctx: Context) -> tuple[Check, ...]:
    info: LinkSlidingData = design.data
    run = measure(design, ctx.simulation)
    cert = {"band": run.band, "hold": run.hold, "reaching_time": run.reaching_time, "max_abs_slm": run.slm_max}
    what = {None: "the band the relay held over a step leaves",
            "saturation": "the boundary layer ε", "dead_zone": "the dead zone ε plus one held step"}[
        None if info.epsilon is None else info.layer]
    if run.reach is None:
        band = Check(IN_BAND, False, f"|slm| <= {run.band:.4g} rad*s after reaching", None, None, "rad*s",
                     f"|slm| never entered {what} ({run.band:.4g} rad*s): the loop does not slide", cert)
        from designkit.verification.chatter_prediction import limit_of

        limit = limit_of(ctx.spec)
        if limit is None:
            return (band,)
        return band, Check(CHATTERING, False, f"chatter amplitude <= {limit:g} N*m", None, None, "N*m",
                           "no sliding phase to measure the chatter amplitude on", {**cert, "limit": limit})
    ok = run.worst <= run.band * (1 + 1e-9)
    how = ("stays within it" if ok else f"leaves it: |slm| = {run.worst:.4g} rad*s at t = {run.worst_at:.4g} s, "
           f"{run.worst / run.band:.3g} times the band")
    band = Check(IN_BAND, ok, f"|slm| <= {run.band:.4g} rad*s after reaching", run.worst,
                 run.band - run.worst, "rad*s", f"|slm| entered {what} ({run.band:.4g} rad*s) after "
                 f"{run.reaching_time:.4g} s and {how}; largest |slm| after reaching {run.worst:.4g} rad*s", cert)
    dev_ok = run.deviation <= run.deviation_bound * (1 + 1e-3) + 1e-12
    precision = Check(
        PRECISION, dev_ok, "|x1 − x1 of the sliding motion| <= ||s/N||₁ max|slm|", run.deviation,
        run.deviation_bound - run.deviation, "rad",
        f"the position stays within {run.deviation:.4g} rad of the plant-independent sliding motion, against the "
        f"bound ||s/N||₁ max|slm| = {info.l1:.4g} 1/s × {run.slm_max:.4g} rad*s = {run.deviation_bound:.4g} rad "
        f"and ||s/N||₁ × band = {run.deviation_at_band:.4g} rad [informational]",
        {**cert, "deviation": run.deviation, "bound": run.deviation_bound, "bound_at_band": run.deviation_at_band,
         "l1": info.l1}, required=False)
    from designkit.families.pid_sliding_mode.chatter import chatter as chatter_of
    from designkit.verification.chatter_prediction import ChatterMeasured, limit_of, verdict
    from designkit.verification.switching import judge_run

    freq = run.switching_frequency
    calm, words, physics = judge_run(design, ctx.simulation, ctx.spec, "N*m")
    cycle_words, cycle = chatter_of(design, ctx.simulation, ctx.spec, run)
    seen = (f"after reaching slm changes sign {run.switches} times in {run.sliding_time:.4g} s "
            f"({0.0 if freq is None else freq:.4g} per s); total variation of u {run.total_variation:.4g} N*m, of the "
            f"switching part {run.relay_variation:.4g} N*m; the switching part's peak-to-peak over the last tenth of "
            f"the run {run.relay_ptp_tail:.4g} N*m")
    cert_c = {**cert, "switches": run.switches, "sliding_time": run.sliding_time, "total_variation_u":
              run.total_variation, "total_variation_relay": run.relay_variation, "relay_ptp_tail": run.relay_ptp_tail,
              "switching": physics, "limit_cycle": cycle}
    limit = limit_of(ctx.spec)
    if limit is None:
        chatter = Check(CHATTERING, calm if ok else None, "switching part within the equivalent control, rate not "
                        "set by the step", freq, None, "1/s", f"{words}; {seen}; {cycle_words} [informational]",
                        cert_c, required=False)
        return band, precision, chatter
    fine, achieved, said = verdict(ChatterMeasured.from_dict(cycle["measured"]), limit, "N·m")
    prefix = "" if ok else "the run leaves the band, so this is not only chattering: "
    chatter = Check(CHATTERING, fine, f"chatter amplitude <= {limit:g} N*m", achieved,
                    None if achieved is None else limit - achieved, "N*m",
                    f"{prefix}{said}; {cycle_words}; {words}; {seen}", {**cert_c, "limit": limit})
    return band, precision, chatter


RUN_RULE = CheckRule(
    name="pid_sm_run", order=127,
    applies=lambda d, c: (c.simulation is not None and isinstance(d.data, LinkSlidingData)
                          and "slm" in c.simulation.signals),
    run=_run_checks, label="Sliding mode in the simulated run",
    labels={IN_BAND: "The run stays in the band around slm = 0",
            PRECISION: "Distance from the sliding motion (measured)",
            CHATTERING: "Chattering (measured)"},
    glossary=(("band", "|slm| ≤ δ: the boundary layer, or how far the relay held over a step can leave slm"),
              ("chatter amplitude", "half the peak-to-peak command over the last tenth of the run after reaching")),
    reads=("requirements.max_chatter_amplitude",),
)
