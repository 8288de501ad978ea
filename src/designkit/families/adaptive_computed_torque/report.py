"""The adaptive computed torque's report section (what was adapted, the SPR condition, tracking, estimates against
the excitation, the Lyapunov function, what the acceleration costs) and its top-level JSON object ``adaptation``.

Both read the family's checks when they ran (else compute what they need: the SPR evidence, the excitation).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table
from designkit.families.adaptive_computed_torque.laws import estimates
from designkit.families.adaptive_computed_torque.words import describe, unit_text

__all__ = ["SHOWN", "json", "section"]

SHOWN = 12
"""Windows of the tracking judgement shown in the report's table (the first two and the last ones beyond)."""


def _num(x: Any) -> float | None:
    return float(x) if x is not None and math.isfinite(float(x)) else None


def _check(result: Any, name: str) -> Any:
    return next((c for c in result.checks if c.name == name), None)


def _spr_rows(result: Any) -> list[dict[str, Any]]:
    check = _check(result, "spr_certificate")
    if check is not None:
        return list(check.certificate["joints"])
    from designkit.families.adaptive_computed_torque.checks import spr_evidence

    return [{"K1": j.K1, "K2": j.K2, "psi": j.psi, "psi_K2_minus_1": j.analytic, "kyp": j.kyp,
             "sweep_min_re_H": j.sweep_min, "sweep_w_rad_s": j.sweep_w, "w2_re_H_top": j.high_frequency,
             "psi_min_s": j.psi_min} for j in spr_evidence(result.design)["joints"]]


def json(result: Any) -> dict[str, Any]:
    """``{"adaptation": {parameters, units, initial, final, true, spr: {margin, psi_min}, excitation, start_warnings,
    gain_matrix}}`` (SI units; ``final`` and ``excitation`` null without a run; ``gain_matrix`` the full ``K``)."""
    d, sim = result.design, result.simulation
    a = d.data.adaptation
    rows = [] if a.scheme == "slotine_li" else _spr_rows(result)
    out: dict[str, Any] = {
        "parameters": list(a.names), "units": list(d.data.units), "initial": list(a.initial),
        "true": list(d.data.true), "acceleration": a.acceleration, "scheme": a.scheme,
        "spr": None if not rows else {"psi_K2_minus_1": [r["psi_K2_minus_1"] for r in rows],
                                      "psi_min_s": [r["psi_min_s"] for r in rows]},
        "final": None, "excitation": None, "start_warnings": list(d.data.start_warnings),
        "gain_matrix": a.K().tolist(),
    }
    if sim is not None:
        out["final"] = [_num(v) for v in estimates(sim, a.names)[-1]]
        check = _check(result, "estimate_convergence")
        if check is not None:
            c = check.certificate
            out["excitation"] = {"rate_1_s": c["rate_1_s"], "efolds": c["efolds"], "alpha_min": c["alpha_min"],
                                 "window_s": c["window_s"], "exciting": c["exciting"]}
    return {"adaptation": out}


def _f(x: Any, digits: int = 4) -> str:
    return "—" if x is None or not math.isfinite(float(x)) else fmt_number(float(x), digits)


def _spr_question(result: Any) -> Question:
    rows = _spr_rows(result)
    table = Table("The error filter of each joint and its SPR condition ψ K2 > 1",
                  ("Joint", "K1 (1/s²)", "K2 (1/s)", "ψ (s)", "ψ K2 − 1", "SPR for ψ above (s)", "KYP certificate",
                   "ω² Re H(jω) at the grid's top", "most negative Re H(jω) (at ω, rad/s)"),
                  tuple((str(k + 1), _f(r["K1"]), _f(r["K2"]), _f(r["psi"]), _f(r["psi_K2_minus_1"], 3),
                         _f(r["psi_min_s"]), {True: "found, re-checked", False: "refuted",
                                              None: "undecided"}[r["kyp"]], _f(r["w2_re_H_top"], 3),
                         f"{_f(r['sweep_min_re_H'], 3)} (at {_f(r['sweep_w_rad_s'], 4)})" if r["sweep_min_re_H"] < 0
                         else "none negative")
                        for k, r in enumerate(rows)))
    bad = [k for k, r in enumerate(rows) if r["psi_K2_minus_1"] <= 0]
    if bad:
        words = "; ".join(f"joint {k + 1}: ψ K2 − 1 = {_f(rows[k]['psi_K2_minus_1'], 3)}, short of zero by "
                          f"{_f(-rows[k]['psi_K2_minus_1'], 3)}; any ψ above {_f(rows[k]['psi_min_s'])} s would do "
                          f"(e.g. {_f(2 * rows[k]['psi_min_s'])} s, margin 1)" for k in bad)
        sentences = ("No. The update law's Lyapunov argument needs H(s) = (1 + ψ s)/(s² + K2 s + K1) strictly "
                     "positive real, which for positive gains holds exactly when ψ K2 > 1. " + words + ".",)
    else:
        sentences = ("Yes, for every joint: a KYP certificate (P ≻ 0, AᵀP + PA ≺ 0, P B = Cᵀ) was found and re-checked "
                     "in NumPy, Re H(jω) is positive on the frequency grid with ω² Re H(jω) tending to ψ K2 − 1 > 0, "
                     "and the analytic condition ψ K2 > 1 holds.",)
    return Question("Is the error filter strictly positive real, and for which ψ?", sentences, (table,))


def _tracking_question(result: Any) -> Question:
    check = _check(result, "tracking_convergence")
    if check is None:
        return Question("Does the tracking error go to zero?", ("The run was not judged.",))
    c = check.certificate
    if "window_maxima_rad" not in c:  # a run that diverged: the check says when
        return Question("Does the tracking error go to zero?", (f"No: {check.detail}.",))
    theorem = ("The Lyapunov argument promises e → 0 as t → ∞, not a size by a given time, so the error is judged by "
               f"a bound that decreases: the running maximum of |e| over trailing windows of {_f(c['window_s'], 4)} s "
               f"({c['window_from']}), from the window of the run's peak to the last, must decrease (each at most "
               f"1 + {_f(c['tolerance'], 3)} times the one before, the last below the peak), or stay below "
               f"{_f(c['floor_rad'], 3)} rad.")
    ends = list(c["window_ends_s"])
    shown = list(range(len(ends))) if len(ends) <= SHOWN else [*range(2), *range(len(ends) - (SHOWN - 2), len(ends))]
    title = "The largest |e| over each window, oldest first (rad)" + (
        "" if len(ends) <= SHOWN else f": the first 2 and the last {SHOWN - 2} of {len(ends)} windows")
    table = Table(title, ("Joint", *(f"to {_f(ends[k], 4)} s" for k in shown), "judged"),
                  tuple((str(j + 1), *(_f(row[k], 3) for k in shown), c["joints"][j]["why"])
                        for j, row in enumerate(c["window_maxima_rad"])))
    words = ", ".join(f"joint {k + 1}: {_f(b, 3)} rad at most over the run, {_f(a, 3)} rad over the last window"
                      for k, (a, b) in enumerate(zip(c["last_window_rad"], c["peak_rad"], strict=True)))
    return Question("Does the tracking error go to zero?",
                    (("Yes, it is decreasing" if check.passed else "Not shown within the run") + f": {words}.",
                     theorem), (table,))


def _estimates_question(result: Any) -> Question:
    d, sim = result.design, result.simulation
    a = d.data.adaptation
    check = _check(result, "estimate_convergence")
    final = estimates(sim, a.names)[-1]
    true = np.asarray(d.data.true, dtype=float)
    rows = tuple((describe(x), unit_text(u), _f(i), _f(f), _f(t), _f(100 * abs(f - t) / abs(t) if t else abs(f), 3))
                 for x, u, i, f, t in zip(a.names, d.data.units, a.initial, final, true, strict=True))
    table = Table("Adapted parameters: the initial estimate, the run's final estimate and the true value",
                  ("Parameter", "Unit", "Initial", "Final", "True", "Final error (%)"), rows)
    c = check.certificate if check is not None else {}
    ex = (f"The desired trajectory's excitation: over {_f(c.get('window_s'), 3)} s windows the smallest eigenvalue "
          f"of ∫WₐᵀWₐ dt is at least {_f(c.get('alpha_min'), 3)}, and the averaged update removes "
          f"{_f(c.get('efolds'), 3)} e-folds of a parameter error in the run (3 or more counts as exciting).")
    if check is None:
        verdict = "The estimates were not judged."
    elif c["exciting"] and check.passed:
        verdict = "Yes: the trajectory is exciting and every estimate ends within 5 % of its true value."
    elif c["exciting"]:
        verdict = "No, although the trajectory is exciting: the estimates did not reach their true values in the run."
    elif check.passed:
        verdict = "Yes, although the excitation indicator did not promise it."
    else:
        verdict = ("No, and none was promised: the trajectory does not excite the adapted parameters enough. The "
                   "Lyapunov argument guarantees only that the tracking error goes to zero; the estimates settle on "
                   "values that reproduce the torques this trajectory needs, not on the true parameters. This is "
                   "reported and does not fail the design.")
    return Question("Do the estimates converge to the true values?", (verdict, ex), (table,))


def _lyapunov_question(result: Any) -> Question:
    check = _check(result, "adaptive_lyapunov")
    if check is None:
        return Question("Is the Lyapunov function of the adaptive loop non-increasing?", ("The run was not judged.",))
    c = check.certificate
    if "V0" not in c:  # a run that diverged: the check says when
        return Question("Is the Lyapunov function of the adaptive loop non-increasing?", (f"No: {check.detail}.",))
    if result.design.data.adaptation.scheme == "slotine_li":
        what = "V = ½ sᵀD(q)s + ½ (P − P̂)ᵀK⁻¹(P − P̂), with s = ė + Λe and the true inertia D(q),"
    else:
        what = ("V = Σⱼ xⱼᵀPⱼxⱼ + (P − P̂)ᵀK⁻¹(P − P̂), with xⱼ = (eⱼ, ėⱼ) and the closed-form KYP matrix "
                "Pⱼ = [[K2 + ψK1, 1], [1, ψ]],")
    sentences = (f"{what} was computed along the run with the true parameters: from "
                 f"{_f(c['V0'])} to {_f(c['V_end'], 3)}, rising at most {_f(c['relative_rise'], 3)} × V(0) over its "
                 f"running minimum (tolerance {_f(c['tolerance'], 3)} × V(0)) — "
                 + ("non-increasing." if check.passed else "it is not a Lyapunov function of this loop."),)
    return Question("Is the Lyapunov function of the adaptive loop non-increasing?", sentences)


def _acceleration_question(result: Any) -> Question:
    a = result.design.data.adaptation
    if a.scheme == "slotine_li":
        words = ("It needs none: the Slotine–Li law's regressor Y(q, q̇, q̇r, q̈r) uses the reference velocity and "
                 "acceleration q̇r = q̇D + Λe, q̈r = q̈D + Λė, and its update K Yₐᵀ s no inverse of the estimated "
                 "inertia. The price is the Christoffel-consistent Coriolis matrix in the regressor, a larger "
                 "expression than the computed torque's.")
    elif a.acceleration == "ideal":
        words = ("An ideal accelerometer: the update reads the arm's own acceleration, which the law can evaluate in "
                 "the simulation because the command does not depend on it (the torque uses the desired acceleration "
                 "and the error feedback only), so there is no algebraic loop. The cost is one forward-dynamics "
                 "evaluation per step, and a sensor a real arm may not have: with the filtered derivative instead, "
                 "the update sees the acceleration late and the proof holds only approximately.")
    else:
        words = (f"The measured velocity differentiated through a first-order filter of bandwidth {_f(a.bandwidth)} "
                 f"rad/s: {len(result.design.plant.positions)} more controller states, an integration step bounded by "
                 "that pole, and an acceleration that lags the arm's by about one filter time constant, so the "
                 "Lyapunov function's decrease holds only approximately (the check's tolerance says how much).")
    return Question("How does the law obtain the acceleration the update needs, and at what cost?", (words,))


def section(result: Any) -> ReportSection | None:
    """The family's section (module docstring)."""
    from designkit.families.adaptive_computed_torque.laws import KIND

    if result.design.kind != KIND:
        return None
    slotine = result.design.data.adaptation.scheme == "slotine_li"
    questions = [] if slotine else [_spr_question(result)]
    if result.simulation is not None:
        questions += [_tracking_question(result), _estimates_question(result), _lyapunov_question(result)]
    questions.append(_acceleration_question(result))
    a = result.design.data.adaptation
    adapted = "; ".join(describe(x) for x in a.names)
    intro = ("Craig's adaptive computed torque (notes section 4.4). Adapted: " + adapted
             + ". Every other parameter of the arm's regressor is taken as known, at its true value. The answers are "
               "computed from the design's gains and from the run.")
    return ReportSection("adaptive-ct", "Adaptive computed torque: SPR condition, convergence and excitation", intro,
                         tuple(questions))
