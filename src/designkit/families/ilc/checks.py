"""The learning family's own checks: the contraction certificate, and the trials against it.

``ilc_convergence`` (order 75): ``rho = ||I - Q H||_2 < 1`` on the lifted model of the trial's grid, decided on a
proved bracket ``lower <= rho <= upper`` (:class:`~designkit.families.ilc.operators.Contraction`): PASS when
``upper < 1`` (monotone convergence of ``||d - d_k||`` and ``||e_k||``), FAIL when ``lower > 1`` (by how much,
and which ``alpha`` converges), undecided between, or when the Lanczos estimate and the independent power
iteration disagree by more than :data:`RECHECK_REL`.  Beside it, informational, ``ilc_spectral_radius``: the
spectral radius of ``I - Q H`` below 1 (asymptotic convergence only).

``ilc_error_decrease`` (order 128, two trials or more): the inequality the certificate implies on the exact
model, ``e_{k+1} = (I - H Q) e_k`` hence

    ||e_{k+1}|| <= rho ||e_k|| + FLOOR_REL ||e_0||          for every trial k,

``e`` the lifted error (samples 1 .. N-1, every joint, as the learning measures it) and ``rho`` the proved upper
bound; without a certificate (``rho >= 1``) the inequality tested is plain decrease, ``rho`` replaced by 1.  (It
implies the notes' form ``||e_k|| <= ||H|| rho^k ||d - d_0||``, since ``||e_0|| <= ||H|| ||d - d_0||``.)
Beside it, informational, ``ilc_lifted_model``: how much of each trial-to-trial change the lifted model does
not explain, ``mu_k = ||e_{k+1} - e_k + H (d_{k+1} - d_k)|| / ||H (d_{k+1} - d_k)||`` -- rounding on the exact
model, the coupling through ``M^-1 M^`` and the motion-dependent perturbation otherwise; below 1 the actual change
has a positive component along the predicted one (the learning goes the right way).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from designkit.families.ilc.learning import IlcData, lifted_errors, lifted_of, operator_of
from designkit.families.ilc.lifted import LiftedModel
from designkit.families.ilc.operators import Contraction, contraction
from designkit.verification.bracket import bracket_verdict
from designkit.verification.certificate import to_json
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context

__all__ = ["CERTIFICATE_RULE", "FLOOR_REL", "RECHECK_REL", "TRIALS_RULE", "TrialAnalysis", "analyse",
           "near_one", "trial_analysis"]

RECHECK_REL = 1e-3
"""Largest relative difference between the Lanczos and power-iteration values of each norm.  The power iteration
(at most 300 steps from a smooth start) converges slowly where the top singular values cluster -- to 1e-13 for
``H`` on the examples, 2e-4 for ``I - gamma H`` -- so the tolerance is loose; what it catches is a Lanczos run that
missed the top of the spectrum, which the power iteration, a lower bound, then exceeds (by more than
:data:`ABOVE_REL`)."""
ABOVE_REL = 1e-9
"""The power iteration may exceed the Lanczos value by this much, relatively (rounding)."""
FLOOR_REL = 1e-9
"""The error-decrease inequality allows this fraction of the first trial's error norm: the simulation's
precision (the exact-model runs agree with the lifted model to 1e-11 relative)."""


def near_one(value: float, margin: float) -> str:
    """``value`` written so that its distance to 1 shows: ``1 − 6.9e-15`` when it is that close."""
    if abs(margin) < 1e-4:
        return f"1 {'−' if margin > 0 else '+'} {abs(margin):.2g}"
    return f"{value:.6g}"


def _recheck(c: Contraction) -> tuple[bool, float]:
    """Whether every norm's Lanczos estimate and power iteration agree (and lie in their bracket), and the worst
    relative difference."""
    worst = 0.0
    ok = True
    for joint in c.per_joint:
        for key in ("sigma_max", "sigma_min", "norm"):
            if key not in joint:
                continue
            n = joint[key]
            scale = max(abs(n["lanczos"]), 1e-300)
            diff = abs(n["lanczos"] - n["power_iteration"]) / scale
            worst = max(worst, diff)
            inside = n["lower_bound"] * (1 - 1e-12) <= n["lanczos"] <= n["upper_bound"] * (1 + 1e-12)
            below = key == "sigma_min" or n["power_iteration"] <= n["lanczos"] * (1 + ABOVE_REL)
            ok = ok and diff <= RECHECK_REL and inside and below
    return ok, worst


def _certificate_checks(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    lifted = lifted_of(design, None if sim is None else sim.time)
    c = contraction(lifted, operator_of(design))
    ok, diff = _recheck(c)
    cert = {**c.to_dict(), "samples": lifted.samples, "lifted_size_per_joint": lifted.L, "dt": lifted.dt,
            "integrator": lifted.integrator, "h0": [float(h) for h in lifted.markov[:, 0]],
            "zeros": [[complex(z).real if abs(complex(z).imag) == 0 else [complex(z).real, complex(z).imag]
                       for z in lifted.zeros(j)] for j in range(lifted.n)], "shift": lifted.shift,
            "recheck_relative_difference": diff,
            "method": "sigma by ARPACK Lanczos (svds) on FFT Toeplitz products, re-checked by power iteration; "
                      "proved bracket: Rayleigh quotients below, min(l1, symbol sup on an FFT grid + slack) above"}
    words = _words(c, _units(design))
    verdict = bracket_verdict(c.margin, c.excess, routes_agree=ok)
    passed, verdict_reason = verdict.passed, verdict.reason
    routes = (f"; the two routes to the norms disagree by {diff:.2g} (relative, more than {RECHECK_REL:g}), which "
              "does not weigh against the proved bound" if not ok else "")
    if not np.isfinite(c.rho):
        passed, verdict_reason = None, "not_computed"
    if verdict_reason == "not_computed":
        detail = ("the learning operator's coefficients are not finite over the trial (an unstable filter): ρ is not "
                  "computed, not decided; " + words["range"])
    elif verdict.reason == "proved":
        detail = words["pass"]
    elif verdict.reason == "proved_false":
        detail = words["fail"] + routes
    elif verdict.reason == "routes":
        detail = (f"the two routes to the norms disagree by {diff:.2g} (relative, more than {RECHECK_REL:g}): ρ is "
                  f"not decided ({words['rho']})")
    else:
        detail = (f"ρ lies between {near_one(c.lower, -c.excess)} and {near_one(c.upper, c.margin)}: "
                  f"{verdict.explanation}, not decided; "
                  + words["range"])
    cert["verdict_reason"] = verdict_reason
    cert["boundary_tolerance"] = verdict.tolerance
    rho = Check(name="ilc_convergence", passed=passed, target="ρ = ‖I − Q H‖₂ < 1",
                achieved=c.rho if np.isfinite(c.rho) else None,
                margin=c.margin if c.margin > 0 else -c.excess if c.excess > 0 else 0.0, unit="",
                detail=detail, certificate=to_json(cert))
    spectral = Check(name="ilc_spectral_radius", passed=c.asymptotic, target="spectral radius of I − Q H < 1",
                     achieved=c.spectral_radius, margin=c.spectral_margin, unit="", required=False,
                     detail=words["spectral"], certificate={"spectral_radius": c.spectral_radius,
                                                            "spectral_margin": c.spectral_margin})
    return rho, spectral


def _units(design: Any) -> dict[str, str]:
    """The units the sentences write: of ``alpha``, ``gamma``, ``H`` and the error."""
    info = design.data
    if info.sampled is None:
        return {"alpha": "1/s⁴", "gamma": "1/s²", "H": "s²", "e": "rad", "robot": "yes"}
    u, y = info.units
    gamma, h = ratio(u, y), ratio(y, u)
    return {"alpha": f"({gamma})²" if gamma else "", "gamma": gamma, "H": h, "e": y, "robot": ""}


def ratio(num: str, den: str) -> str:
    """``num/den`` written plainly (``""`` when both are 1, ``1/den`` or ``num`` when one is)."""
    if den in ("1", ""):
        return "" if num in ("1", "") else num
    return f"{'1' if num in ('1', '') else num}/{den}"


def _words(c: Contraction, units: dict[str, str] | None = None) -> dict[str, str]:
    """The sentences of the certificate."""
    units = units or {"alpha": "1/s⁴", "gamma": "1/s²", "H": "s²", "e": "rad", "robot": "yes"}
    ua, ug, uh = units["alpha"], units["gamma"], units["H"]
    r = c.alpha_range
    rho = near_one(c.rho, 1 - c.rho if abs(1 - c.rho) >= 1e-4 else c.margin if c.margin > 0 else -c.excess)
    if c.kind == "adjoint":
        rng = (f"0 < α < 2/σ_max(H)² = {r['alpha_max']:.6g} {ua} converges monotonically (proved for α < "
               f"{r['alpha_max_proved']:.6g}); ρ is smallest, {near_one(r['rho_optimal'], r['rho_optimal_margin'])}, "
               f"at α* = 2/(σ_max² + σ_min²) = {r['alpha_optimal']:.6g} {ua}, and α = 1/σ_max² = "
               f"{r['alpha_one_trial']:.6g} {ua} removes the largest singular direction in one trial")
        sig = f"σ_max(H) = {r['sigma_max']:.6g} {uh}, σ_min(H) = {r['sigma_min']:.3g} {uh}"
        what = f"ρ = ‖I − α Hᵀ H‖₂ = max(|1 − α σ_max²|, |1 − α σ_min²|) with α = {c.value:.6g} {ua} ({sig})"
        fail = (f"{what} = {c.rho:.6g} > 1 by {c.rho - 1:.3g} (proved ρ ≥ {c.lower:.6g}): the learning does not "
                f"converge in norm and its largest singular direction grows by {c.rho:.3g} per trial; {rng}")
        spectral = (f"I − α Hᵀ H is symmetric: its spectral radius is ρ = {rho}; "
                    + ("below 1" if c.asymptotic else "not below 1"))
    else:
        if c.kind == "p_type":
            name, top = "γ", f"0 < γ < 2/h₀ = {r['gamma_asymptotic_max']:.6g} {ug}"
            what = f"ρ = ‖I − γ H‖₂ with γ = {c.value:.6g} {ug}"
            diag = "1 − γ h₀"
        else:
            name, top = "F₀", f"F₀ between 0 and 2/h₀ = {r['q0_asymptotic_max']:.6g} {ug}"
            what = f"ρ = ‖I − F H‖₂ with the filter F (F₀ = {c.value:.6g} {ug})"
            diag = "1 − F₀ h₀"
        monotone = ("; ‖I − γ H‖₂ ≥ sup|1 − γ a(ω)| > 1 wherever Re a(ω) < 0 (above the error loop's natural "
                    "frequency), so no γ converges monotonically: the adjoint update Q = α Hᵀ with 0 < α < "
                    "2/σ_max(H)² does" if units["robot"] and c.kind == "p_type" else
                    f"; monotone convergence needs ρ < 1, and ρ ≥ sup|1 − {name} a(ω)| on the symbol a of H: "
                    "the learning must keep every frequency within the unit disc about 1; the adjoint update "
                    "Q = α Hᵀ converges monotonically for 0 < α < 2/σ_max(H)²")
        rng = f"the spectral radius |{diag}| < 1 for {top} (asymptotic only){monotone}"
        fail = (f"{what} = {c.rho:.6g} > 1 by {c.rho - 1:.3g} (proved ρ ≥ {c.lower:.6g}): no monotone "
                f"convergence, the error may grow for many trials; {rng}")
        radius = near_one(c.spectral_radius, c.spectral_margin)
        spectral = (f"I − Q H is lower triangular with diagonal {diag}: spectral radius {radius} "
                    + ("< 1, asymptotic convergence (after a transient that ρ bounds only by ρ^k)" if c.asymptotic
                       else "≥ 1: no convergence"))
    return {
        "rho": what,
        "range": rng,
        "pass": (f"{what} = {rho}, proved ≤ {near_one(c.upper, c.margin)}: ‖d − d_k‖ and ‖e_k‖ shrink at "
                 "least by the factor ρ every trial (monotone convergence) on the lifted model of the controller's "
                 "error system; "
                 + rng),
        "fail": fail,
        "spectral": spectral,
    }


CERTIFICATE_RULE = CheckRule(
    name="ilc_convergence", order=75, applies=lambda d, c: isinstance(d.data, IlcData), run=_certificate_checks,
    label="Learning contraction ‖I − Q H‖₂ < 1",
    labels={"ilc_spectral_radius": "Learning spectral radius < 1 (asymptotic convergence)"},
    glossary=(("ρ", "‖I − Q H‖₂: ‖d − d_k‖ and the error norm shrink at least by this factor every trial"),
              ("H", "the lifted error system: lower-triangular Toeplitz matrix of the sampled impulse response of "
                    "1/(s² + K2 s + K1) per joint"),
              ("σ_max, σ_min", "largest and smallest singular values of H (s²)")),
)


# ----------------------------------------------------------------------------- the trials


@dataclass(frozen=True, eq=False)
class TrialAnalysis:
    """What the trials measured against the lifted model.

    Attributes
    ----------
    norms : ndarray
        ``||e_k||`` of the lifted errors (rad), one per trial.
    ratios : ndarray
        ``||e_{k+1}|| / ||e_k||``.
    factor : float
        The tested factor: ``rho``'s proved upper bound when ``rho < 1`` is proved, else 1.
    allowed : ndarray
        ``factor ||e_k|| + FLOOR_REL ||e_0||``, the bound on ``||e_{k+1}||``.
    unexplained : ndarray
        ``mu_k`` (see the module docstring).
    predicted : ndarray
        ``||(I - H Q)^k e_0||`` (rad): the lifted model's prediction from the first trial.
    """

    contraction: Contraction
    norms: np.ndarray
    ratios: np.ndarray
    factor: float
    allowed: np.ndarray
    unexplained: np.ndarray
    predicted: np.ndarray


@lru_cache(maxsize=2)
def analyse(lifted: LiftedModel, operator: Any, trials: Any) -> TrialAnalysis:
    """The :class:`TrialAnalysis` of ``trials`` (cached: the check, the figures and the diagnoses share it)."""
    with np.errstate(all="ignore"):  # a diverged run: its non-finite numbers are what the checks report
        return _analyse(lifted, operator, trials)


def _analyse(lifted: LiftedModel, operator: Any, trials: Any) -> TrialAnalysis:
    c = contraction(lifted, operator)
    E = [lifted_errors(r, lifted.shift) for r in trials.results]
    D = [np.asarray(f, dtype=float).T[:, :lifted.L] for f in trials.feedforward]
    norms = np.array([float(np.linalg.norm(e)) for e in E])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = norms[1:] / norms[:-1]
    factor = c.upper if c.monotone else 1.0
    allowed = factor * norms[:-1] + FLOOR_REL * norms[0]
    mu = []
    for k in range(len(E) - 1):
        change = lifted.apply(D[k + 1] - D[k])
        size = float(np.linalg.norm(change))
        mu.append(float(np.linalg.norm(E[k + 1] - E[k] + change)) / size if size > 0 else
                  0.0 if size == 0 else float("nan"))  # a diverged trial explains nothing
    predicted, e = [norms[0]], E[0]
    for _ in range(len(E) - 1):
        e = e - lifted.apply(operator.apply(lifted, e))
        predicted.append(float(np.linalg.norm(e)))
    return TrialAnalysis(c, norms, ratios, float(factor), allowed, np.array(mu), np.array(predicted))


def trial_analysis(result: Any) -> TrialAnalysis | None:
    """:func:`analyse` of a pipeline result (None without trials)."""
    trials = result.trials
    if trials is None or len(trials.results) < 2:
        return None
    return analyse(lifted_of(result.design, trials.results[0].time), operator_of(result.design), trials)


def _trial_checks(design: Any, ctx: Context) -> tuple[Check, ...]:
    trials = ctx.trials
    a = analyse(lifted_of(design, trials.results[0].time), operator_of(design), trials)
    K = a.norms.size
    finite = bool(np.all(np.isfinite(a.norms)))
    excess = a.norms[1:] - a.allowed
    grew = np.flatnonzero(~(excess <= 0))
    k = int(grew[0]) if grew.size else 0
    big = int(np.nanargmax(np.where(np.isfinite(excess), excess, np.inf))) if excess.size else 0
    margin = float(np.min((a.allowed - a.norms[1:]) / np.where(a.norms[:-1] > 0, a.norms[:-1], 1.0)))
    c = a.contraction
    ue = _units(design)["e"]
    factor = (f"ρ ≤ {near_one(a.factor, c.margin)} (the certificate)" if c.monotone else
              "1 (no certificate: ρ ≥ 1, the decrease itself is tested)")
    fell = (f"the error norm went from {a.norms[0]:.4g} {ue} (trial 0, d = 0) to {a.norms[-1]:.4g} {ue} "
            f"(trial {K - 1}): ×{a.norms[-1] / a.norms[0]:.3g}")
    ok = finite and bool(np.all(excess <= 0))
    worst = int(np.nanargmax(a.ratios)) if a.ratios.size and np.any(np.isfinite(a.ratios)) else 0
    if ok:
        detail = (f"{fell}; every trial's ‖e_(k+1)‖/‖e_k‖ ≤ {np.max(a.ratios):.4g} (largest from trial {worst} to "
                  f"{worst + 1}) against {factor}")
    elif not finite:
        detail = f"a trial's error is not finite (diverged): {fell}"
    else:
        most = "" if big == k else (f", most from trial {big} to {big + 1} (×{a.ratios[big]:.4g}, "
                                    f"{excess[big]:.3g} {ue} above)")
        detail = (f"the error norm grew in {grew.size} of {K - 1} trials, first from trial {k} to {k + 1}: "
                  f"{a.norms[k]:.4g} → {a.norms[k + 1]:.4g} {ue} (×{a.ratios[k]:.4g}, above the allowed "
                  f"{a.allowed[k]:.4g} {ue} by {excess[k]:.3g} {ue}){most}, against {factor}; {fell}")
    cert = {"error_norms": a.norms.tolist(), "ratios": a.ratios.tolist(), "factor": a.factor,
            "floor": FLOOR_REL * float(a.norms[0]), "inequality": "‖e_(k+1)‖ ≤ ρ ‖e_k‖ + 1e-9 ‖e_0‖",
            "lifted_model_prediction": a.predicted.tolist(), "errors": "measured qD − q at samples 1 .. N−1"}
    decrease = Check(name="ilc_error_decrease", passed=ok if finite else False, target="‖e_(k+1)‖ ≤ ρ ‖e_k‖",
                     achieved=float(np.max(a.ratios)) if finite else None, margin=margin if finite else None,
                     unit="", detail=detail, certificate=to_json(cert),
                     data={"norms": a.norms, "allowed": a.allowed, "predicted": a.predicted})
    mu = a.unexplained
    j = int(np.nanargmax(mu)) if mu.size and np.any(np.isfinite(mu)) else 0
    gap = abs(a.predicted[-1] - a.norms[-1]) / a.norms[-1] if a.norms[-1] > 0 else 0.0
    explained = bool(np.all(np.isfinite(mu)) and np.max(mu) < 1.0)
    model = Check(name="ilc_lifted_model", passed=explained, target="μ_k < 1",
                  achieved=float(np.max(mu)) if explained or np.all(np.isfinite(mu)) else None,
                  margin=float(1.0 - np.max(mu)) if np.all(np.isfinite(mu)) else None, unit="", required=False,
                  detail=(f"the lifted model leaves {100 * np.max(mu):.3g} % of a trial-to-trial change of the error "
                          f"unexplained (largest from trial {j} to {j + 1}; median {100 * np.median(mu):.3g} %): "
                          f"{_source(design)}; iterated from trial 0 it predicts the last trial's error norm "
                          f"{a.predicted[-1]:.4g} {ue} against {a.norms[-1]:.4g} measured ({100 * gap:.3g} %)"),
                  certificate=to_json({"unexplained": mu.tolist(), "predicted_last": float(a.predicted[-1]),
                                       "measured_last": float(a.norms[-1])}))
    return decrease, model


def _source(design: Any) -> str:
    if design.data.sampled is not None:
        return ("the model mismatch (the controller's model of the plant differs from the true plant)"
                if design.data.model_differs else "rounding (the trials run the plant's own sampled difference "
                "equation, of which the lifted model is exact)")
    if design.data.model_differs:
        return ("the model mismatch (the learned signal reaches the error through M⁻¹M̂, coupled between joints, "
                "and what the model misses changes with each trial's motion)")
    return "rounding, and a perturbation M⁻¹f that changes with each trial's motion"


TRIALS_RULE = CheckRule(
    name="ilc_error_decrease", order=128,
    applies=lambda d, c: isinstance(d.data, IlcData) and c.trials is not None and len(c.trials.results) >= 2,
    run=_trial_checks, label="Error norm falls every trial as certified",
    labels={"ilc_lifted_model": "Lifted model predicts the trial-to-trial change (μ < 1)"},
    glossary=(("e_k", "the lifted tracking error qD − q of trial k, every joint, samples 1 .. N−1"),
              ("μ_k", "share of the change e_(k+1) − e_k the lifted model does not explain")),
)
