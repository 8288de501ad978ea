"""The variable structure regulator's own checks: theorem 3's conditions on the box, theorem 4's matching, and
what the run shows.

``vsc_conditions`` (order 55) certifies with the condition-certificate core
(:func:`designkit.verification.conditions.certify`) the sets of :func:`~designkit.families.vsc.gains.condition_sets`:

* ``vsc_gains``: ``alpha_i < l_i < beta_i`` for every plant of the box (each cleared by its positive monomial ``M_i``;
  a gain whose cleared form is not multi-affine -- an uncertain ``R1`` or ``R2`` -- is judged on the proven
  enclosure of ``l_i`` instead, ``vsc_gains_enclosed``);
* ``vsc_relay``: ``delta > d_bar sup |cD/cB|`` (``delta > 0`` without a perturbation);
* ``vsc_orientation``: ``cB > 0`` on the box;
* ``vsc_matching`` (informational): theorem 4, ``rank [B D] = rank B``.

``vsc_run`` (order 127) measures the run (:mod:`~designkit.families.vsc.measure`): ``vsc_reaching_time``
(informational), ``vsc_band`` (required: after reaching ``|sigma|`` stays within the hold band),
``vsc_sliding_poles``, ``vsc_chattering`` (the command's switching judged as physics by
:func:`designkit.verification.switching.judge`, the chatter predicted against measured; required with
``requirements.max_chatter_amplitude``, the measured chatter amplitude against it),
``vsc_equivalent_control`` and ``vsc_offset`` (informational).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.families.vsc.data import VscData, bound_json
from designkit.families.vsc.gains import LINEAR, VscGains, condition_sets, rational_forms
from designkit.families.vsc.measure import measure
from designkit.synthesis.state_space import linear_model
from designkit.verification.check import Check
from designkit.verification.conditions import certify
from designkit.verification.suite import CheckRule, Context

__all__ = ["CERTIFICATE_RULE", "RUN_RULE", "gain_shortfalls"]

NAMES = {"gains": "vsc_gains", "relay": "vsc_relay", "orientation": "vsc_orientation"}
POLE_TOLERANCE = 0.05
"""The fitted sliding poles agree with the requested ones within this fraction of their modulus."""
UEQ_FRACTION = 0.99


def gains_of(design: Any) -> VscGains:
    """The design's gains."""
    info: VscData = design.data
    return VscGains(tuple(info.alpha), tuple(info.beta), float(info.delta), tuple(info.c))


def gain_shortfalls(design: Any) -> list[dict[str, Any]]:
    """Per gain that does not bracket its ``l_i``: which, where on the box, by how much, what would do (with
    and without the margin)."""
    info: VscData = design.data
    out = []
    m = float(info.margin)
    for i, (al, be) in enumerate(zip(info.alpha, info.beta, strict=True)):
        b = info.bounds[f"l_{i + 1}"]
        s = float(info.S[i])
        if al >= b.lower:
            out.append({"gain": f"alpha_{i + 1}", "value": al, "bound": b.lower, "relation": "<",
                        "at": b.argmin, "shortfall": al - b.lower, "with_margin": b.lower - m * s})
        if be <= b.upper:
            out.append({"gain": f"beta_{i + 1}", "value": be, "bound": b.upper, "relation": ">",
                        "at": b.argmax, "shortfall": b.upper - be, "with_margin": b.upper + m * s})
    return out


def shortfall_sentence(f: dict[str, Any], margin: float) -> str:
    """``"alpha_1 = 50 is not below min l_1 = 21.2 (at Km = 2.4, ...) by 28.8; alpha_1 <= 12.6 with the 20 %
    margin"``."""
    where = ", ".join(f"{k} = {v:.4g}" for k, v in f["at"].items())
    word, end, rel = ("below", "min", "<=") if f["relation"] == "<" else ("above", "max", ">=")
    return (f"{f['gain']} = {f['value']:.4g} is not {word} {end} {f['gain'].replace('alpha', 'l').replace('beta', 'l')}"
            f" = {f['bound']:.4g} (at {where}) by {f['shortfall']:.3g}; {f['gain']} {rel} {f['with_margin']:.4g} "
            f"with the {100 * margin:g} % margin")


def _enclosed(design: Any) -> Check | None:
    info: VscData = design.data
    rows = []
    ok: bool | None = True
    for i, (al, be) in enumerate(zip(info.alpha, info.beta, strict=True)):
        b = info.bounds[f"l_{i + 1}"]
        if b.method != "enclosure":
            continue
        if al >= b.min_value or be <= b.max_value:  # violated at an evaluated point of the box
            ok = False
        elif not (al < b.lower and be > b.upper) and ok is not False:  # between the bound and the value
            ok = None
        rows.append(f"alpha_{i + 1} = {al:.4g} {'<' if al < b.lower else '>='} {b.lower:.6g} <= l_{i + 1} <= "
                    f"{b.upper:.6g} {'<' if be > b.upper else '>='} beta_{i + 1} = {be:.4g}")
    if not rows:
        return None
    return Check("vsc_gains_enclosed", ok, "alpha_i < l_i < beta_i on the whole box (proven enclosure of l_i)",
                 None, None, "", "proven ranges of l_i over the box (ball arithmetic, branch and bound; the cleared "
                 "condition is not multi-affine; a gain inside the enclosure's gap is undecided, one beyond a value "
                 "attained at a point of the box fails): " + "; ".join(rows),
                 {"bounds": {k: bound_json(b) for k, b in info.bounds.items()}})


def _linear_enclosed(info: VscData, made: set[str]) -> list[Check]:
    """On a linear plant whose ``cB`` or rest mismatch is not multi-affine in the box's parameters: the orientation
    ``cB > 0`` and the relay ``delta > d_bar + sup |c (A x* + B u*) X / cB|`` judged on their proven ranges (a
    bound beyond a value attained on the box fails, one inside the enclosure's gap is undecided)."""
    out = []
    if NAMES["orientation"] not in made:
        b = info.bounds["cB"]
        ok = True if b.lower > 0 else (False if (b.min_value or 0.0) <= 0 else None)
        out.append(Check(NAMES["orientation"], ok, "cB > 0 on the whole box (proven range of cB)", b.lower, b.lower,
                         "", f"cB in [{b.lower:.6g}, {b.upper:.6g}] over the box (proven enclosure; ball arithmetic, "
                         "branch and bound): alpha_i < l_i < beta_i turns sigma' against sigma",
                         {"cB": bound_json(b)}))
    if NAMES["relay"] not in made:
        r = info.bounds["rest"]
        proven = float(info.d_bar) + max(abs(r.lower), abs(r.upper))
        seen = float(info.d_bar) + max(abs(r.min_value or 0.0), abs(r.max_value or 0.0))
        ok = True if info.delta > proven else (False if info.delta <= seen else None)
        out.append(Check(NAMES["relay"], ok, "delta > d_bar + sup |c (A x* + B u*) X / cB| on the whole box",
                         info.delta, info.delta - proven, "",
                         f"delta = {info.delta:.6g} against d_bar = {info.d_bar:.6g} plus the rest mismatch's share "
                         f"of sigma' over cB in [{r.lower:.6g}, {r.upper:.6g}] (proven enclosure, |xD| <= "
                         f"{info.reference_max:g})", {"rest": bound_json(r)}))
    return out


def _certificates(design: Any, ctx: Context) -> tuple[Check, ...]:
    info: VscData = design.data
    g = gains_of(design)
    plant = design.plant
    model = linear_model(plant)
    box = {k: tuple(v) for k, v in info.box.items()}
    bounds = dict(info.bounds)
    rest = (info.rest_direction, info.u_rest) if info.plant_kind in LINEAR else None
    forms = rational_forms(info.plant_kind, g.c, model, rest, info.reference_max)
    out = []
    short = gain_shortfalls(design)
    for key, cs in condition_sets(g, forms, model, box, bounds, float(info.d_bar)).items():
        if not cs.conditions:
            continue
        check = certify(NAMES[key], cs, box, solver=ctx.solver)
        if key == "gains" and check.passed is False and short:
            import dataclasses

            check = dataclasses.replace(
                check, detail="; ".join(shortfall_sentence(f, info.margin) for f in short) + ". " + check.detail,
                certificate={**dict(check.certificate), "shortfalls": short})
        out.append(check)
    made = {c.name for c in out}
    if info.plant_kind in LINEAR:
        out.extend(_linear_enclosed(info, made))
    enc = _enclosed(design)
    if enc is not None:
        out.append(enc)
    A, B, D = (np.asarray(m, float) for m in info.nominal_model)
    matched = bool(np.linalg.matrix_rank(np.column_stack([B, D])) == np.linalg.matrix_rank(B))
    where = "enters with the input" if matched else "does not enter where the input does"
    out.append(Check(
        "vsc_matching", matched, "theorem 4: the disturbance's input columns D in the range of B",
        None, None, "", f"D = {np.round(D.ravel(), 6).tolist()}, B = {np.round(B.ravel(), 6).tolist()}: the "
        f"disturbance {where} (rank [B D] = {np.linalg.matrix_rank(np.column_stack([B, D]))}, rank B = "
        f"{np.linalg.matrix_rank(B)}). " + ("The sliding motion is invariant to it: the relay cancels it on "
                                            "sigma = 0." if matched else
                                            "The sliding mode can still be kept (delta dominates cD d in sigma'), "
                                            "but the motion on sigma = 0 is driven by d and is not invariant to it: "
                                            "a constant load leaves a static offset [informational]"),
        {"matched": matched, "D": D.tolist(), "B": B.tolist()}, required=False))
    return tuple(out)


CERTIFICATE_RULE = CheckRule(
    name="vsc_conditions", order=55, applies=lambda d, c: isinstance(d.data, VscData), run=_certificates,
    label="Theorem 3's conditions on the parameter box",
    labels={"vsc_gains": "Switching gains bracket l_i (whole box)", "vsc_relay": "Relay dominates the perturbation",
            "vsc_orientation": "Orientation cB > 0 (whole box)", "vsc_gains_enclosed": "Gains bracket l_i (proven "
            "enclosure)", "vsc_matching": "Disturbance matched to the input (theorem 4)"},
    glossary=(("σ", "the switching function c x̃"), ("l_i", "the equivalent-control gains −(cA)_i/(cB)")),
)


def _poles(poles: list[complex]) -> str:
    return ", ".join(f"{z.real:.4g}" + (f"{z.imag:+.3g}j" if z.imag else "") for z in poles)


def _run_checks(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    info: VscData = design.data
    run = measure(design, sim)
    cert = {"hold": run.hold, "reaching_time": run.reaching_time}
    if run.reach is None:
        reach = Check("vsc_reaching_time", False, "reported: first |sigma| <= hold band", None, None, "s",
                      "sigma never entered the hold band [informational]", cert, required=False)
        band = Check("vsc_band", False, "|sigma| <= hold band after reaching", None, None, "1",
                     "the run never reached the hold band: it does not slide", cert)
        from designkit.verification.chatter_prediction import limit_of

        limit = limit_of(ctx.spec)
        if limit is None:
            return reach, band
        return reach, band, Check("vsc_chattering", False, f"chatter amplitude <= {limit:g}", None, None, "",
                                  "no sliding phase to measure the chatter amplitude on", {**cert, "limit": limit})
    reach = Check("vsc_reaching_time", True, "reported: first |sigma| <= hold band", run.reaching_time, None, "s",
                  f"sigma entered the hold band after {run.reaching_time:.4g} s [informational]", cert, required=False)
    ok = run.worst_ratio <= 1 + 1e-9
    band = Check("vsc_band", ok, "|sigma| <= h S(x~) after reaching", run.worst_ratio, 1 - run.worst_ratio, "1",
                 f"after reaching, the largest |sigma| relative to the hold band is {run.worst_ratio:.3g} (at t = "
                 f"{run.worst_at:.4g} s); " + ("it stays within the band" if ok else "it leaves the band") + (
                     "" if info.boundary_layer is None else
                     f"; the layer |sigma| <= {info.boundary_layer:.4g} leaves the controlled position within "
                     f"{abs(run.sigma_gain) * info.boundary_layer:.3g} rad of the sliding motion's rest"), cert)
    out = [reach, band]
    req = list(design.poles)
    want = sorted(run.expected_poles or req, key=lambda z: (z.real, z.imag))
    at = "" if all(min(abs(w - r) for r in req) <= 1e-9 * abs(w) for w in want) else (
        f" (the reduced system's poles at the run's plant; requested at the nominal plant: {_poles(req)} 1/s)")
    if run.poles is None:
        out.append(Check("vsc_sliding_poles", None, "the sliding motion's poles", None, None, "1/s",
                         f"too few sliding samples ({run.fit_samples}) to fit [informational]", cert, required=False))
    else:
        got = sorted(run.poles, key=lambda z: (z.real, z.imag))
        err = max(abs(a - b) / abs(b) for a, b in zip(got, want, strict=True))
        out.append(Check("vsc_sliding_poles", bool(err <= POLE_TOLERANCE), f"the sliding motion's poles within "
                         f"{100 * POLE_TOLERANCE:g} %", err, POLE_TOLERANCE - err, "1",
                         f"least squares z' = F z + k sigma + g d on {run.fit_samples} sliding samples (z the error "
                         f"state without the driven state: the reduced-order system): eig F = {_poles(got)} 1/s "
                         f"against {_poles(want)} 1/s{at} ({100 * err:.3g} % off) [informational]",
                         {**cert, "poles": [[z.real, z.imag] for z in got],
                          "expected": [[z.real, z.imag] for z in want]}, required=False))
    from designkit.families.vsc.chatter import chatter
    from designkit.verification.chatter_prediction import ChatterMeasured, limit_of, verdict
    from designkit.verification.switching import input_unit, judge_run

    calm, words, physics = judge_run(design, ctx.simulation, ctx.spec)
    cycle_words, cycle = chatter(design, ctx.simulation, ctx.spec, run)
    seen = (f"after reaching sigma changes sign {run.switches} times in {run.sliding_time:.4g} s "
            f"({run.switching_frequency or 0:.4g} per s); total variation of u {run.total_variation:.4g}")
    cert_c = {"switches": run.switches, "total_variation": run.total_variation, "switching": physics,
              "limit_cycle": cycle}
    limit = limit_of(ctx.spec)
    if limit is None:
        out.append(Check("vsc_chattering", calm, "switching part within the equivalent control, rate not set by the "
                         "step", run.switching_frequency, None, "1/s",
                         f"{words}; {seen}; {cycle_words} [informational]", cert_c, required=False))
    else:
        unit = input_unit(design, 0) or "N*m"
        ok, achieved, said = verdict(ChatterMeasured.from_dict(cycle["measured"]), limit,
                                     unit.replace("N*m", "N·m"))
        out.append(Check("vsc_chattering", ok, f"chatter amplitude <= {limit:g} {unit}", achieved,
                         None if achieved is None else limit - achieved, unit,
                         f"{said}; {cycle_words}; {words}; {seen}", {**cert_c, "limit": limit}))
    if run.ueq_fraction is not None:
        okf = run.ueq_fraction >= UEQ_FRACTION
        out.append(Check("vsc_equivalent_control", okf, f"u_eq in [min(u+, u-), max(u+, u-)] on at least "
                         f"{100 * UEQ_FRACTION:g} % of the sliding phase", run.ueq_fraction,
                         run.ueq_fraction - UEQ_FRACTION, "1",
                         f"theorem 1: the equivalent control -(cB)^-1 (cA x~ + cD d) of the run's plant lies between "
                         f"the two switched controls on {100 * run.ueq_fraction:.4g} % of the sliding samples "
                         "[informational]", {"fraction": run.ueq_fraction}, required=False))
    diff = abs(run.final_offset - run.predicted_offset)
    out.append(Check("vsc_offset", bool(diff <= run.offset_tolerance), "final error of the controlled position = "
                     f"the sliding motion's offset under the final disturbance, within {run.offset_tolerance:.3g} rad",
                     run.final_offset, run.offset_tolerance - diff, "rad",
                     f"{'matched' if run.matched else 'unmatched'} disturbance: the sliding motion predicts a final "
                     f"error {run.predicted_offset:.4g} rad of the controlled position, the run ends at "
                     f"{run.final_offset:.4g} rad [informational]",
                     {"predicted": run.predicted_offset, "final": run.final_offset, "matched": run.matched},
                     required=False))
    return tuple(out)


RUN_RULE = CheckRule(
    name="vsc_run", order=127,
    applies=lambda d, c: c.simulation is not None and isinstance(d.data, VscData) and "sigma" in c.simulation.signals,
    run=_run_checks, label="Variable structure control in the simulated run",
    labels={"vsc_reaching_time": "Reaching time (measured)", "vsc_band": "The run stays in the hold band",
            "vsc_sliding_poles": "Sliding poles (measured)", "vsc_chattering": "Chattering (measured)",
            "vsc_equivalent_control": "Equivalent control between the switched controls (theorem 1)",
            "vsc_offset": "Offset left by the disturbance (theorem 4)"},
    reads=("requirements.max_chatter_amplitude",),
    glossary=(("hold band", "h S(x̃): how far one held step can move σ"),),
)
