"""The sliding-mode servo's own checks: its conditions certified on the box, and what the run shows.

``sliding_conditions`` (order 55, between ``robust_box`` and ``robustness``) certifies, with the
condition-certificate core (:func:`designkit.verification.conditions.certify`: affine conditions by LP with a
re-checked dual bound, multi-affine ones at the box's corners re-checked in NumPy), three labelled sets
(:func:`~designkit.families.sliding_mode.conditions.condition_sets`):

* ``sliding_existence``: ``alpha > k > beta`` on the box (the sliding mode exists on the whole line ``s = 0``);
* ``sliding_reaching``: ``alpha > 1/(4 Km tau)`` (the ``alpha`` structure is a focus: every trajectory meets
  the line);
* ``sliding_perturbation``: ``M > sup |xi|``.

A failed set says which condition, where on the box, by how much the gain falls short and which value would do,
with and without the design margin (``certificate["gains_needed"]``).

``sliding_run`` (order 127, before ``time_domain``) measures the run
(:mod:`~designkit.families.sliding_mode.measure`): ``reaching_time`` (informational), ``sliding_band`` (the
invariant: after reaching, ``|s|`` stays within the band the step leaves -- required: it is the run's evidence
that the loop slides), ``sliding_pole`` (the pole fitted on the sliding segment against ``-c``, informational)
and ``chattering`` (informational: the command's switching judged as physics by
:func:`designkit.verification.switching.judge`, with the switching frequency of ``s`` and the command's variation).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from designkit.families.sliding_mode import linear_checks
from designkit.families.sliding_mode.conditions import (
    SlidingGains,
    condition_sets,
    existence_bound,
    focus_bound,
    vertices,
)
from designkit.families.sliding_mode.data import SlidingData
from designkit.families.sliding_mode.linear import LinearSlidingData
from designkit.families.sliding_mode.measure import POLE_FLOOR, POLE_TOLERANCE, measure
from designkit.verification.check import Check
from designkit.verification.conditions import certify
from designkit.verification.suite import CheckRule, Context

__all__ = ["CERTIFICATE_RULE", "RUN_RULE", "gains_needed"]

CERTIFICATE_CHECKS = {"existence": "sliding_existence", "reaching": "sliding_reaching",
                      "perturbation": "sliding_perturbation"}


def gains_of(design: Any) -> SlidingGains:
    """The design's ``(alpha, beta, M, c)``."""
    return SlidingGains(*(float(design.gains[k]) for k in ("alpha", "beta", "M", "c")))


def gains_needed(g: SlidingGains, xi_bar: float, box: Any, margin: float) -> dict[str, dict[str, Any]]:
    """Per gain: the bound it must clear on the box, the corner where that bound is worst, the value the design's
    margin asks for, and the gain's shortfall (positive when the condition fails)."""
    v = vertices(box)
    k = existence_bound(g.c, v[:, 0], v[:, 1])
    f = focus_bound(v[:, 0], v[:, 1])
    size = g.c * (1 + g.c * v[:, 1]) / v[:, 0]
    ia, ib, i_f = int(np.argmax(k)), int(np.argmin(k)), int(np.argmax(f))

    def at(i: int) -> dict[str, float]:
        return {"Km": float(v[i, 0]), "tau": float(v[i, 1])}

    return {
        "alpha_existence": {"gain": "alpha", "value": g.alpha, "bound": float(k[ia]), "relation": ">", "at": at(ia),
                            "with_margin": float(np.max(k + margin * np.abs(k))), "shortfall": float(k[ia] - g.alpha)},
        "beta_existence": {"gain": "beta", "value": g.beta, "bound": float(k[ib]), "relation": "<", "at": at(ib),
                           "with_margin": float(np.min(k - margin * size)), "shortfall": float(g.beta - k[ib])},
        "alpha_focus": {"gain": "alpha", "value": g.alpha, "bound": float(f[i_f]), "relation": ">", "at": at(i_f),
                        "with_margin": float((1 + margin) * f[i_f]), "shortfall": float(f[i_f] - g.alpha)},
        "M_perturbation": {"gain": "M", "value": g.M, "bound": xi_bar, "relation": ">", "at": {},
                           "with_margin": (1 + margin) * xi_bar, "shortfall": xi_bar - g.M},
    }


_WORDS = {
    "alpha_existence": ("alpha", "N*m/rad", "c (1 - c tau)/Km"),
    "beta_existence": ("beta", "N*m/rad", "c (1 - c tau)/Km"),
    "alpha_focus": ("alpha", "N*m/rad", "1/(4 Km tau) = a^2/(4 b)"),
    "M_perturbation": ("M", "N*m", "sup|xi|"),
}
_OF_SET = {"existence": ("alpha_existence", "beta_existence"), "reaching": ("alpha_focus",),
           "perturbation": ("M_perturbation",)}


def shortfall_sentence(key: str, need: dict[str, Any], margin: float) -> str:
    """``"M = 0.8 N*m is below sup|xi| = 1 N*m by 0.2 N*m; M >= 1.2 N*m with the 20 % margin"``."""
    name, unit, formula = _WORDS[key]
    where = f" at Km = {need['at']['Km']:.4g}, tau = {need['at']['tau']:.4g}" if need["at"] else ""
    side, rel = ("below", ">=") if need["relation"] == ">" else ("above", "<=")
    return (f"{name} = {need['value']:.4g} {unit} is {side} {formula} = {need['bound']:.4g} {unit}{where} by "
            f"{need['shortfall']:.3g} {unit}; {name} {rel} {need['with_margin']:.4g} {unit} with the "
            f"{100 * margin:g} % margin")


def _certificates(design: Any, ctx: Context) -> tuple[Check, ...]:
    info = design.data
    g = gains_of(design)
    box = {k: tuple(v) for k, v in info.box.items()}
    needs = gains_needed(g, info.xi_bar, box, info.margin)
    out = []
    for key, set_ in condition_sets(g, info.xi_bar).items():
        check = certify(CERTIFICATE_CHECKS[key], set_, box, solver=ctx.solver)
        mine = {n: needs[n] for n in _OF_SET[key]}
        cert = {**dict(check.certificate), "gains_needed": mine, "margin_of_design": info.margin}
        detail = check.detail
        short = [shortfall_sentence(n, need, info.margin) for n, need in mine.items() if need["shortfall"] >= 0]
        if check.passed is False and short:
            cert["shortfall"] = {n: mine[n]["shortfall"] for n in mine if mine[n]["shortfall"] >= 0}
            detail = "; ".join(short) + ". " + detail
        out.append(dataclasses.replace(check, detail=detail, certificate=cert))
    return tuple(out)


def _any_certificates(design: Any, ctx: Context) -> tuple[Check, ...]:
    if isinstance(design.data, LinearSlidingData):
        return linear_checks.conditions(design, ctx)
    return _certificates(design, ctx)


CERTIFICATE_RULE = CheckRule(
    name="sliding_conditions", order=55, applies=lambda d, c: isinstance(d.data, SlidingData | LinearSlidingData),
    run=_any_certificates,
    label="Sliding-mode conditions on the parameter box",
    labels={"sliding_existence": "Sliding mode exists on s = 0 (whole box)",
            "sliding_reaching": "Every trajectory reaches s = 0 (whole box)",
            "sliding_perturbation": "Relay dominates the perturbation", **linear_checks.CERTIFICATE_LABELS},
    glossary=(("s", "the sliding function x2 + c (x1 − xD), rad/s"),
              ("existence", "on s = 0 the equivalent control lies between the two switched controls, so s stays 0"),
              ("reaching", "every trajectory meets s = 0 in finite time"), *linear_checks.CERTIFICATE_GLOSSARY),
)


def _run_checks(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    info = design.data
    c = float(info.c)
    run = measure(design, sim)
    n_seg = len(run.segments)
    segs = f" (the longest over {n_seg} reference segments)" if n_seg > 1 else ""
    band_words = (f"the boundary layer epsilon = {run.band:.4g} rad/s" if info.boundary_layer is not None else
                  f"the band the held command leaves, hold x sdot_max = {run.hold:.4g} s x "
                  f"{run.band / run.hold:.4g} rad/s^2 = {run.band:.4g} rad/s (target {run.design_band:.4g} rad/s)")
    cert = {"band": run.band, "hold": run.hold, "design_band": run.design_band, "e_bound": run.e_seen,
            "segments": [list(s) for s in run.segments], "reaching_times": list(run.reaching_times),
            "last_segment_cut": run.cut}
    if run.reached:
        reach = Check("reaching_time", True, "reported: first |s| <= band after each reference jump",
                      run.reaching_time, None, "s", f"|s| entered {band_words} after {run.reaching_time:.4g} s{segs} "
                      "[informational]", cert, required=False)
    else:
        k = run.reach.index(None)
        reach = Check("reaching_time", False, "reported: first |s| <= band after each reference jump", None, None,
                      "s", f"|s| never entered the band {run.band:.4g} rad/s in segment {k + 1} of {n_seg} "
                      f"(from t = {float(sim.time[run.segments[k][0]]):.4g} s) [informational]", cert, required=False)
    if not run.reached:
        band = Check("sliding_band", False, f"|s| <= {run.band:.4g} rad/s after reaching", None, None, "rad/s",
                     f"the run never reached the band {run.band:.4g} rad/s after a reference jump: it does not slide",
                     cert)
    else:
        worst = float(run.worst_excursion)
        ok = worst <= run.band * (1 + 1e-9)
        how = ("stays within it" if ok else
               f"leaves it: |s| = {worst:.4g} rad/s at t = {run.worst_at:.4g} s, {worst / run.band:.3g} times the "
               f"band ({worst - run.band:.3g} rad/s beyond)")
        band = Check("sliding_band", ok, f"|s| <= {run.band:.4g} rad/s after reaching", worst, run.band - worst,
                     "rad/s", f"after reaching {band_words}, |s| {how}; largest |s| {worst:.4g} rad/s", cert)
    if run.pole is None:
        pole = Check("sliding_pole", None, f"-c = {-c:g} 1/s within {100 * POLE_TOLERANCE:g} %", None, None, "1/s",
                     f"no sliding segment with |e| above {POLE_FLOOR:g} band/c and {run.fit_samples} < 20 samples "
                     "to fit e' = p e on [informational]", cert, required=False)
    else:
        err = abs(run.pole + c)
        pole = Check("sliding_pole", bool(err <= POLE_TOLERANCE * c), f"-c = {-c:g} 1/s within "
                     f"{100 * POLE_TOLERANCE:g} %", run.pole, POLE_TOLERANCE * c - err, "1/s",
                     f"least squares e' = p e on {run.fit_samples} sliding samples: p = {run.pole:.5g} 1/s against "
                     f"-c = {-c:g} 1/s ({100 * err / c:.3g} % off) [informational]",
                     {**cert, "pole": run.pole, "requested": -c, "relative_error": err / c,
                      "fit_samples": run.fit_samples}, required=False)
    chatter = _chatter_check(design, ctx, run, cert, band.passed is True)
    return reach, band, pole, chatter


def _chatter_check(design: Any, ctx: Context, run: Any, cert: dict[str, Any], sliding: bool) -> Check:
    """``chattering``: the command's switching judged as physics, the chatter predicted against measured
    (:mod:`~designkit.families.sliding_mode.chatter`) and, with ``requirements.max_chatter_amplitude``, the
    measured chatter amplitude against it (then required)."""
    from designkit.families.sliding_mode.chatter import chatter as chatter_of
    from designkit.verification.chatter_prediction import limit_of, verdict
    from designkit.verification.switching import judge_run

    limit = limit_of(ctx.spec)
    sim = ctx.simulation
    if run.switching_frequency is None:
        return Check("chattering", False if limit is not None else None, "reported" if limit is None else
                     f"chatter amplitude <= {limit:g} N*m", None, None, "1/s" if limit is None else "N*m",
                     "no sliding phase to measure" + ("" if limit is not None else " [informational]"), cert,
                     required=limit is not None)
    amp = run.amplitude if run.amplitude is not None else 0.0
    calm, words, physics = judge_run(design, sim, ctx.spec, "N*m")
    cyc = chatter_of(design, sim, ctx.spec, run)
    measured = (f"after reaching s changes sign {run.switches} times in {run.sliding_time:.4g} s "
                f"({run.switching_frequency:.4g} per s); chattering amplitude max|s| = {amp:.4g} rad/s (error at "
                f"most {amp / float(design.data.c):.3g} rad), total variation of u {run.total_variation:.4g} N*m "
                f"({run.total_variation / run.sliding_time:.4g} N*m/s), u peak-to-peak over the last tenth of the "
                f"sliding time {run.u_ptp_tail or 0.0:.4g} N*m")
    full = {**cert, "switches": run.switches, "sliding_time": run.sliding_time, "step_rate": 1 / run.hold,
            "amplitude": amp, "error_band": amp / float(design.data.c), "total_variation": run.total_variation,
            "u_peak_to_peak_tail": run.u_ptp_tail, "switching": physics, "limit_cycle": cyc.to_dict()}
    prefix = "" if sliding else "the run leaves the band, so this is not only chattering: "
    if limit is None:
        return Check("chattering", calm if sliding else None, "switching part within the equivalent control, rate "
                     "not set by the step", run.switching_frequency, None, "1/s",
                     f"{prefix}{words}; {measured}; {cyc.sentence} [informational]", full, required=False)
    ok, achieved, said = verdict(cyc.measured, float(limit), "N·m")
    return Check("chattering", ok, f"chatter amplitude <= {float(limit):g} N*m", achieved,
                 None if achieved is None else float(limit) - achieved, "N*m",
                 f"{prefix}{said}; {cyc.sentence}; {words}; {measured}", {**full, "limit": float(limit)})


def _any_run_checks(design: Any, ctx: Context) -> tuple[Check, ...]:
    if isinstance(design.data, LinearSlidingData):
        return linear_checks.run_checks(design, ctx)
    return _run_checks(design, ctx)


RUN_RULE = CheckRule(
    name="sliding_run", order=127,
    applies=lambda d, c: (c.simulation is not None and isinstance(d.data, SlidingData | LinearSlidingData)
                          and "s" in c.simulation.signals),
    run=_any_run_checks, label="Sliding mode in the simulated run",
    labels={"reaching_time": "Reaching time (measured)", "sliding_band": "The run stays in the chattering band",
            "sliding_pole": "Pole on the sliding line (measured)", "chattering": "Chattering (measured)",
            **linear_checks.RUN_LABELS},
    glossary=(("band", "|s| ≤ δ: how far from s = 0 the command held over a step can leave s"),
              ("chatter amplitude", "half the peak-to-peak command over the last tenth of the sliding time"),
              *linear_checks.RUN_GLOSSARY),
    reads=("requirements.max_chatter_amplitude",),
)
