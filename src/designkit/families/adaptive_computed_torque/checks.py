"""The adaptive computed torque's own checks.

``spr_certificate`` (order 15, required): ``H_j(s) = (1 + psi_j s)/(s^2 + K2_j s + K1_j)`` strictly positive
real for every joint, by the KYP lemma on the certificate core (per joint and for the block-diagonal
``2n``-state system), cross-checked by a frequency sweep of ``Re H(jw)`` and the analytic condition
``psi K2 > 1`` (:mod:`.spr`).  It reads only the gains: it is not a check of a linearization.  When the
routes disagree the check is undecided.

``tracking_convergence`` (order 126, required): the tracking error goes to zero as the theorem says, asymptotically,
not by a given time: per joint, the running maximum of ``|e_j|`` over trailing windows of ``W`` (aligned to the run's
end; ``controller.convergence.window``, default the reference's period when it is a sine and the run holds two
periods, else a tenth of the run),
from the window holding the run's peak to the last, decreases -- each window's maximum at most ``1 + tolerance``
times the one before (``controller.convergence.tolerance``, default 0) and the last below the peak -- or the running
maximum falls below ``floor`` (``controller.convergence.floor``, default 1e-6 rad) and stays there
(:func:`window_maxima`, :func:`decreasing`).  A run whose peak lies in its last window shows no decrease and fails.

``adaptive_lyapunov`` (order 127, required): ``V = sum_j x_j' P_j x_j + (P - P^)' K^-1 (P - P^)``
(``x_j = (e_j, e'_j)``, ``P_j`` the closed-form KYP matrix) recorded along the run never rises by more than
the tolerance over its running minimum: :data:`V_TOL_IDEAL` x ``V(0)`` with the ideal accelerometer (the
theorem's setting: ``V' = -sum 2 K1 e^2 + 2 (psi K2 - 1) e'^2`` exactly, so what is left is integration
error), :data:`V_TOL_FILTERED` x ``V(0)`` with the filtered derivative (where the theorem does not hold
exactly; the check then measures what the filter costs).

``estimate_convergence`` (order 128): the final estimates against the true values (within
:data:`CONVERGED_REL`), judged against the excitation indicator (:mod:`.excitation`): required when the
trajectory is exciting, informational otherwise (the Lyapunov argument promises ``e -> 0`` only).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.adaptive_computed_torque.excitation import EFOLDS, excitation
from designkit.families.adaptive_computed_torque.laws import KIND, estimates
from designkit.families.adaptive_computed_torque.spr import joint_spr, stacked_realisation
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context

__all__ = ["CONVERGED_REL", "RULES", "TAIL", "V_TOL_FILTERED", "V_TOL_IDEAL", "decreasing", "lyapunov_rise",
           "spr_evidence", "tracking_window", "window_maxima"]

TAIL = 0.1
"""The default window of the tracking judgement, without a periodic reference: this fraction of the run."""
V_TOL_IDEAL = 1e-6
"""Largest rise of ``V`` over its running minimum, relative to ``V(0)``, with the ideal accelerometer."""
V_TOL_FILTERED = 1e-2
"""The same with the filtered velocity derivative."""
CONVERGED_REL = 0.05
"""Converged: every estimate within this fraction of its true value."""


def _craig(design: Any, ctx: Context) -> bool:
    return design.kind == KIND and design.data.adaptation.scheme == "craig"


def _run(design: Any, ctx: Context) -> bool:
    return design.kind == KIND and ctx.simulation is not None


def spr_evidence(design: Any, solver: str = "CLARABEL") -> dict[str, Any]:
    """Per-joint :class:`~.spr.JointSpr` and the block-diagonal KYP verdict of a design's gains."""
    from designkit.verification.kyp import positive_real

    a = design.data.adaptation
    joints = [joint_spr(k1, k2, psi, solver=solver) for k1, k2, psi in zip(a.K1, a.K2, a.psi, strict=True)]
    stacked = positive_real(*stacked_realisation(a.K1, a.K2, a.psi), solver=solver)
    return {"joints": joints, "stacked": stacked}


def _spr(design: Any, ctx: Context) -> tuple[Check, ...]:
    ev = spr_evidence(design, ctx.solver)
    joints, stacked = ev["joints"], ev["stacked"]
    cert = {"joints": [{"K1": j.K1, "K2": j.K2, "psi": j.psi, "psi_K2_minus_1": j.analytic, "kyp": j.kyp,
                        "kyp_margin": j.kyp_margin, "sweep_min_re_H": j.sweep_min, "sweep_w_rad_s": j.sweep_w,
                        "w2_re_H_top": j.high_frequency, "psi_min_s": j.psi_min} for j in joints],
            "stacked_kyp": stacked.passed, "stacked_detail": stacked.detail}
    worst = min(range(len(joints)), key=lambda k: joints[k].analytic)
    w = joints[worst]
    target = "ψ K2 > 1 per joint (KYP: P ≻ 0, AᵀP + PA ≺ 0, P B = Cᵀ; sweep of Re H(jω); analytic)"
    agree = all(j.agree for j in joints) and stacked.passed == (w.analytic > 0)
    if not agree:
        return (Check("spr_certificate", None, target, w.analytic, w.analytic, "1",
                      "undecided: the KYP certificate, the frequency sweep and the analytic condition disagree "
                      f"(joint {worst + 1}: KYP {w.kyp}, sweep {'positive' if w.sweep_positive else 'not positive'}, "
                      f"ψ K2 − 1 = {w.analytic:.4g})", cert),)
    if w.analytic > 0:
        detail = (f"H(s) = (1 + ψ s)/(s² + K2 s + K1) is strictly positive real for every joint: KYP certificate "
                  f"found and re-checked per joint and for the stacked system; smallest ψ K2 − 1 = {w.analytic:.4g} "
                  f"(joint {worst + 1}); admissible ψ per joint: "
                  + ", ".join(f"ψ{k + 1} > {j.psi_min:.4g} s" for k, j in enumerate(joints)))
        return (Check("spr_certificate", True, target, w.analytic, w.analytic, "1", detail, cert),)
    bad = [k for k, j in enumerate(joints) if j.analytic <= 0]
    detail = ("not SPR: " + "; ".join(
        f"joint {k + 1}: ψ K2 − 1 = {joints[k].analytic:.4g} (ψ = {joints[k].psi:.4g} s, needs ψ > 1/K2 = "
        f"{joints[k].psi_min:.4g} s, e.g. ψ = {2 * joints[k].psi_min:.4g} s), Re H(jω) reaches "
        f"{joints[k].sweep_min:.4g} at ω = {joints[k].sweep_w:.4g} rad/s" for k in bad))
    return (Check("spr_certificate", False, target, w.analytic, w.analytic, "1", detail, cert),)


def _errors(sim: Any) -> np.ndarray:
    ref = np.asarray(sim.reference, dtype=float)[:, :, 0]
    pos = np.asarray(sim.state, dtype=float)[:, list(sim.positions)]
    return ref - pos


def tracking_window(sim: Any, window: float | None) -> tuple[float, str]:
    """The window ``W`` (s) of the tracking judgement and where it came from: the spec's, else the reference's
    period when it is a sine and the run holds two periods or more, else :data:`TAIL` of the run."""
    t = np.asarray(sim.time, dtype=float)
    if window is not None:
        return float(window), "controller.convergence.window"
    ref = dict(dict(getattr(sim, "settings", None) or {}).get("reference") or {})
    span = float(t[-1] - t[0])
    if ref.get("kind") == "sine" and float(ref.get("frequency", 0.0)) > 0 and 2.0 / float(ref["frequency"]) <= span:
        return 1.0 / float(ref["frequency"]), "the reference's period"
    return TAIL * span, "a tenth of the run"


def window_maxima(t: np.ndarray, e: np.ndarray, window: float) -> tuple[np.ndarray, np.ndarray]:
    """``(ends, maxima)``: the largest ``|e|`` (per column of ``e``, shape (N, n)) over consecutive windows of
    ``window`` s ending at the run's end, oldest first (a first window shorter than ``window`` is dropped, its
    samples joined to the next one)."""
    t = np.asarray(t, dtype=float)
    e = np.abs(np.asarray(e, dtype=float)).reshape(len(t), -1)
    count = max(int(np.floor((t[-1] - t[0]) / window * (1 + 1e-12))), 1)
    ends = t[-1] - window * np.arange(count)[::-1]
    starts = np.concatenate([[t[0] - 1.0], ends[:-1]])
    maxima = np.array([np.max(e[(t > a) & (t <= b)], axis=0) for a, b in zip(starts, ends, strict=True)])
    return ends, maxima


def decreasing(maxima: np.ndarray, tolerance: float, floor: float) -> tuple[bool, str]:
    """Whether one joint's window maxima (oldest first) decrease from the peak's window on (module docstring), and
    why not."""
    m = np.asarray(maxima, dtype=float)
    k0 = int(np.argmax(m))
    after = m[k0:]
    below = np.flatnonzero(after <= floor)
    if below.size and np.all(after[below[0]:] <= floor):
        return True, f"below the floor {floor:g} rad from window {k0 + below[0] + 1} of {len(m)} on"
    if len(after) < 2:
        return False, "its peak lies in the last window: no decrease seen within the run"
    for k in range(1, len(after)):
        if after[k] > (1.0 + tolerance) * after[k - 1]:
            return False, (f"window {k0 + k + 1} of {len(m)} reaches {after[k]:.3g} rad, above window {k0 + k}'s "
                           f"{after[k - 1]:.3g} rad" + (f" × (1 + {tolerance:g})" if tolerance else ""))
    if not after[-1] < after[0]:
        return False, f"the last window's {after[-1]:.3g} rad is not below the peak {after[0]:.3g} rad"
    return True, f"decreasing from {after[0]:.3g} to {after[-1]:.3g} rad"


def _chain(m: np.ndarray) -> str:
    """Window maxima as ``a → b → …`` (the first two and the last eight beyond twelve)."""
    words = [f"{x:.3g}" for x in m]
    if len(words) > 12:
        words = [*words[:2], f"… ({len(words) - 10} windows) …", *words[-8:]]
    return " → ".join(words)


def _tracking(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    t = np.asarray(sim.time, dtype=float)
    e = np.abs(_errors(sim))
    if not np.all(np.isfinite(e)):
        at = float(t[np.flatnonzero(~np.all(np.isfinite(e), axis=1))[0]])
        return (Check("tracking_convergence", False, "finite error", None, None, "rad",
                      f"the tracking error stopped being finite at t = {at:.6g} s: the run diverged",
                      {"diverged_at_s": at}),)
    conv = design.data.convergence
    window, source = tracking_window(sim, conv.window)
    ends, maxima = window_maxima(t, e, window)
    verdicts = [decreasing(maxima[:, j], conv.tolerance, conv.floor) for j in range(e.shape[1])]
    ok = all(v for v, _ in verdicts)
    peak = np.max(e, axis=0)
    last = maxima[-1]
    ratio = last / np.where(peak > 0, peak, 1.0)
    worst = int(np.argmax(ratio))
    cert = {"window_s": window, "window_from": source, "tolerance": conv.tolerance, "floor_rad": conv.floor,
            "window_ends_s": ends.tolist(), "window_maxima_rad": maxima.T.tolist(), "peak_rad": peak.tolist(),
            "last_window_rad": last.tolist(), "ratio": ratio.tolist(),
            "joints": [{"decreasing": v, "why": w} for v, w in verdicts]}
    detail = (f"running maximum of |e| over {len(ends)} trailing windows of {window:.4g} s ({source}), per joint: "
              + "; ".join(f"joint {j + 1}: " + _chain(maxima[:, j]) + f" rad ({w})"
                          for j, (_, w) in enumerate(verdicts)))
    target = (f"window maxima decreasing from the peak on (each ≤ (1 + {conv.tolerance:g}) × the previous, the last "
              f"below the peak) or below {conv.floor:g} rad")
    return (Check("tracking_convergence", ok, target, float(ratio[worst]), None, "1 (last window / peak)", detail,
                  cert, data={"time": t, "error": _errors(sim)}),)


def lyapunov_rise(V: np.ndarray) -> tuple[float, int]:
    """Largest ``V_k - min_{j <= k} V_j`` and its index (0 for a non-increasing sequence)."""
    V = np.asarray(V, dtype=float)
    rise = V - np.minimum.accumulate(V)
    k = int(np.argmax(rise))
    return float(rise[k]), k


def _lyapunov(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    t = np.asarray(sim.time, dtype=float)
    V = np.asarray(sim.signals["V"], dtype=float)
    Vdot = np.asarray(sim.signals["Vdot_bound"], dtype=float)
    slotine = design.data.adaptation.scheme == "slotine_li"
    filtered = design.data.adaptation.acceleration == "filtered" and not slotine
    tol = V_TOL_FILTERED if filtered else V_TOL_IDEAL
    if not np.all(np.isfinite(V)):
        at = float(t[np.flatnonzero(~np.isfinite(V))[0]])
        return (Check("adaptive_lyapunov", False, "finite V", None, None, "",
                      f"V stopped being finite at t = {at:.6g} s: the run diverged", {"diverged_at_s": at}),)
    rise, k = lyapunov_rise(V)
    rel = rise / V[0] if V[0] > 0 else rise
    predicted = float(np.sum(0.5 * (Vdot[1:] + Vdot[:-1]) * np.diff(t)))
    cert = {"V0": float(V[0]), "V_end": float(V[-1]), "largest_rise": rise, "relative_rise": rel,
            "at_s": float(t[k]), "tolerance": tol, "integral_of_Vdot": predicted,
            "V_end_minus_V0": float(V[-1] - V[0]), "acceleration": design.data.adaptation.acceleration}
    setting = ("filtered velocity derivative: the theorem's V' = −xᵀQ1x holds only up to the filter's error"
               if filtered else "Slotine–Li: V = ½ sᵀDs + ½ P̃ᵀK⁻¹P̃, V' = −sᵀ KD s exactly" if slotine
               else "ideal accelerometer: V' = −Σ 2K1 e² + 2(ψK2 − 1) ė² exactly, ≤ 0 when ψK2 ≥ 1")
    detail = (f"V from {V[0]:.4g} to {V[-1]:.4g}; largest rise over its running minimum {rel:.3g} × V(0) at "
              f"t = {t[k]:.3g} s (tolerance {tol:g} × V(0), {setting}); ∫V' dt on the error equation "
              f"{predicted:.4g} against V(T) − V(0) = {V[-1] - V[0]:.4g}")
    return (Check("adaptive_lyapunov", bool(rel <= tol), f"V non-increasing within {tol:g} × V(0)", rel, tol - rel,
                  "1 (relative)", detail, cert, data={"time": t, "V": V}),)


def run_excitation(design: Any, sim: Any) -> Any:
    """The excitation indicators of the run's desired trajectory."""
    a = design.data.adaptation
    if a.scheme == "slotine_li":
        return excitation(design.plant, a.names, a.KD, a.K(), np.asarray(sim.time), np.asarray(sim.reference),
                          scheme="slotine_li")
    return excitation(design.plant, a.names, a.K1, a.K(), np.asarray(sim.time), np.asarray(sim.reference))


def _estimates(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    a = design.data.adaptation
    names, true = list(a.names), np.asarray(design.data.true, dtype=float)
    final = estimates(sim, names)[-1]
    rel = np.abs(final - true) / np.where(np.abs(true) > 0, np.abs(true), 1.0)
    start = np.abs(np.asarray(a.initial) - true) / np.where(np.abs(true) > 0, np.abs(true), 1.0)
    worst = int(np.argmax(rel)) if rel.size else 0
    ex = run_excitation(design, sim)
    ok = bool(np.all(rel <= CONVERGED_REL)) if np.all(np.isfinite(rel)) else False
    words = ", ".join(f"{n}: {f:.4g} (true {t:.4g}, from {s * 100:.3g} % to {r * 100:.3g} % off)"
                      for n, f, t, s, r in zip(names, final, true, start, rel, strict=True))
    pe = (f"excitation: averaged convergence rate {ex.rate:.3g} 1/s × {ex.duration:.3g} s = {ex.efolds:.3g} e-folds; "
          f"smallest eigenvalue of ∫Wᵀ W dt over {ex.window:.3g} s windows {ex.alpha_min:.3g}")
    cert = {"final": final.tolist(), "true": true.tolist(), "relative_error": rel.tolist(), "rate_1_s": ex.rate,
            "efolds": ex.efolds, "alpha_min": ex.alpha_min, "window_s": ex.window, "exciting": ex.exciting}
    target = f"every estimate within {CONVERGED_REL * 100:g} % of the true value"
    margin = float(CONVERGED_REL - rel[worst]) if math.isfinite(rel[worst]) else None
    warned = tuple(design.data.start_warnings)
    cert["start_warnings"] = list(warned)
    if ex.exciting:
        return (Check("estimate_convergence", ok, target, float(rel[worst]), margin, "1 (relative)",
                      f"{words}; {pe} (≥ {EFOLDS:g}: convergence expected)", cert,
                      data={"excitation": ex}, warnings=warned),)
    return (Check("estimate_convergence", ok, target, float(rel[worst]), margin, "1 (relative)",
                  f"{words}; {pe} (< {EFOLDS:g}: the trajectory does not excite the parameters enough to expect "
                  f"convergence; reported, {'converged anyway' if ok else 'not converged'})", cert, required=False,
                  data={"excitation": ex}, warnings=warned),)


RULES = (
    CheckRule("spr_certificate", 15, _craig, _spr, label="Error filter strictly positive real (KYP, sweep, analytic)",
              glossary=(("H(s)", "the map from the parameter-error torque u to e1 = e + ψ ė"),
                        ("SPR", "strictly positive real: the condition of the update law's Lyapunov argument"))),
    CheckRule("tracking_convergence", 126, _run, _tracking, label="Tracking error converging"),
    CheckRule("adaptive_lyapunov", 127, _run, _lyapunov, label="Lyapunov function of the adaptive loop non-increasing"),
    CheckRule("estimate_convergence", 128, _run, _estimates,
              label="Parameter estimates against the true values (with the excitation indicator)"),
)
"""The family's own check rules."""
