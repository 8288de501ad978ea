"""The MRAC's own checks on the feedforward/feedback structure (same names as the coefficient form's,
:mod:`designkit.families.mrac.checks`, which hands these designs over).

``adaptive_stability``: the run is bounded, judged as on the link (:func:`~designkit.families.mrac.runs.assess`:
finite, ``|e| <= 10 x`` the reference's swing, the error's RMS not growing).  No gain boundary is searched on failure.

``adaptation_error``: RMS of ``e = ym - y`` with adaptation against the same scenario with the parameters frozen at
their initial values; required (and adaptation must lower it) when there is something to adapt to -- the initial
parameters are not the ideal ones, the plant changes, a perturbation acts; informational otherwise.

``parameter_convergence``: the final parameters against the ideal ones of the plant the run ends with (the
structure solved again on it), within :data:`~designkit.families.mrac.checks.CONVERGED_REL`; required when the
excitation ``rho = |kp/km| Gm(0) lambda_min(Gamma^1/2 mean(phi phi') Gamma^1/2)`` (the slowest rate of the averaged
rule ``theta~' = -Gamma (kp/km) Gm(0) mean(phi phi') theta~``, 1/s) times the time left is at least
:data:`~designkit.families.mrac.checks.EFOLDS`, informational otherwise.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.mrac.runs import assess, change_in_run, in_run, last_event, rms, simulate
from designkit.families.mrac.structure import matching, monic, plant_transfer
from designkit.verification.check import Check
from designkit.verification.suite import Context

__all__ = ["adaptation_error", "convergence", "final_ideal", "mismatch_reasons", "stability"]


def _f(x: float | None, digits: int = 4) -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def _json(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _list(v: Any) -> list[float | None]:
    return [_json(float(x)) for x in np.asarray(v, dtype=float)]


def final_ideal(design: Any, spec: Any, plant: Any) -> tuple[float, ...] | None:
    """The ideal parameters of the plant the run ends with (after a ``plant_change`` within the run), with the
    design's model and filter; None when that plant cannot be matched (its order or relative degree changed)."""
    change = change_in_run(spec)
    p = plant.with_params(**change.values) if change is not None else plant
    s = design.data.structure
    num, den = plant_transfer(p)
    lam0 = np.polydiv(np.asarray(s.lam), monic(s.model_num)[1])[0]
    try:
        theta, _ = matching(num, den, s.model_num, s.model_den, lam0)
    except (ValueError, ZeroDivisionError):
        return None
    return theta


def mismatch_reasons(design: Any, spec: Any, plant: Any) -> list[str]:
    """Why the loop frozen at the initial parameters is not the model, in words (empty: it is)."""
    x = design.data
    out = []
    start = np.asarray(x.initial, dtype=float)
    ideal = np.asarray(x.structure.ideal, dtype=float)
    if not np.allclose(start, ideal, rtol=1e-9, atol=1e-12):
        out.append("the initial parameters are not the ideal ones")
    if not _same_plant(plant_transfer(plant), x.structure):
        out.append("the true plant is not the nominal one")
    change = change_in_run(spec)
    if change is not None:
        out.append(f"the plant changes at t = {change.time:g} s")
    pert = spec.simulation.perturbation
    if pert is not None and in_run(spec, pert.time):
        out.append(f"a perturbation acts from t = {pert.time:g} s")
    return out


def _same_plant(transfer: tuple[np.ndarray, np.ndarray], s: Any) -> bool:
    a0, den = monic(transfer[1])
    num = np.trim_zeros(np.asarray(transfer[0], dtype=float) / a0, "f")
    return (len(den) == len(s.plant_den) and len(num) == len(s.plant_num) and np.allclose(den, s.plant_den, rtol=1e-12)
            and np.allclose(num, s.plant_num, rtol=1e-12))


def stability(design: Any, ctx: Context) -> tuple[Check, ...]:
    """``adaptive_stability`` (module docstring)."""
    names = design.data.structure.names
    theta = np.column_stack([np.asarray(ctx.simulation.signals[n], dtype=float) for n in names])
    a = assess(ctx.simulation, ctx.spec, theta, float(np.max(np.abs(design.data.structure.ideal))))
    cert: dict[str, Any] = {"finite": a.finite, "peak_error": _json(a.peak), "bound": a.bound, "growth": a.growth,
                            "growth_limit": 1.1, "window_s": a.window, "diverged_at_s": a.diverged_at}
    target = "the adaptive run stays bounded (finite, |e| ≤ 10 × the reference swing, error not growing)"
    achieved = a.growth if a.growth is not None else (None if not math.isfinite(a.peak) else a.peak / a.bound)
    if a.stable:
        margin = 1.1 - a.growth if a.growth is not None else 1.0 - a.peak / a.bound
        return (Check("adaptive_stability", True, target, achieved, margin, "1 (ratio)", a.reason, cert),)
    return (Check("adaptive_stability", False, target, achieved, None, "1 (ratio)",
                  f"the adaptation rule lost stability: {a.reason}; lower γ or use the normalized rule", cert),)


def adaptation_error(design: Any, ctx: Context) -> tuple[Check, ...]:
    """``adaptation_error`` (module docstring)."""
    sim = ctx.simulation
    lin = design.linearization
    plant = ctx.true_plant(design)
    fixed = simulate(ctx.spec, design, plant, lin.freeze(lin.initial))
    t, ym = np.asarray(sim.time, dtype=float), np.asarray(sim.signals["ym"], dtype=float)
    tf = np.asarray(fixed.time, dtype=float)
    ym_f = ym if tf.shape == t.shape and np.allclose(tf, t, atol=1e-12) else np.interp(tf, t, ym)
    ea = np.asarray(sim.signals["e"], dtype=float)
    ef = ym_f - np.asarray(fixed.state, dtype=float)[:, fixed.positions[0]]
    ra, rf = rms(ea), rms(ef)
    reasons = mismatch_reasons(design, ctx.spec, plant)
    cert = {"error_rms": {"adaptive": _json(ra), "fixed": _json(rf)}, "reasons": reasons,
            "ratio": ra / rf if rf > 0 and math.isfinite(ra) else None}
    target = "RMS(e) with adaptation < RMS(e) with the parameters frozen at their initial values"
    if not math.isfinite(ra):
        return (Check("adaptation_error", False, target, None, None, "", f"the adaptive run's output error is not "
                      f"finite (the frozen loop's RMS is {_f(rf)})", cert),)
    if reasons:
        ok = bool(ra < rf)
        detail = (f"RMS of e = ym − y over the run: {_f(ra)} with adaptation, {_f(rf)} with the parameters frozen at "
                  f"their initial values, because {'; '.join(reasons)}")
        return (Check("adaptation_error", ok, target, ra, rf - ra, "", detail + ("" if ok else
                      ": adaptation did not lower the error"), cert),)
    ok = bool(ra <= 1.05 * rf + 1e-12 * max(1.0, rf))
    return (Check("adaptation_error", ok, "RMS(e) with adaptation <= 1.05 x without (no mismatch)", ra,
                  1.05 * rf - ra, "", f"nothing to adapt to (the frozen loop is the model): RMS of e = {_f(ra)} with "
                  f"adaptation, {_f(rf)} without; reported", cert, required=False),)


def convergence(design: Any, ctx: Context, converged_rel: float, efolds_needed: float) -> tuple[Check, ...]:
    """``parameter_convergence`` (module docstring)."""
    sim, spec = ctx.simulation, ctx.spec
    x = design.data
    names = x.structure.names
    theta = np.column_stack([np.asarray(sim.signals[n], dtype=float) for n in names])
    final = theta[-1]
    want = final_ideal(design, spec, ctx.true_plant(design))
    target = f"parameters within {100 * converged_rel:g} % of the ideal ones"
    if want is None:
        return (Check("parameter_convergence", None, target, None, None, "1 (relative)", "the plant the run ends "
                      "with cannot be matched by this structure: no ideal parameters", {}, required=False),)
    want = np.asarray(want, dtype=float)
    rel = np.abs(final - want) / np.maximum(np.abs(want), 1e-12 * max(1.0, float(np.max(np.abs(want)))))
    worst = float(np.max(rel)) if np.all(np.isfinite(rel)) else math.inf
    converged = bool(worst <= converged_rel)
    t = np.asarray(sim.time, dtype=float)
    t0 = last_event(spec, float(t[-1]))
    span = float(t[-1]) - t0
    rate = _excitation(design, sim, t >= t0 - 1e-12)
    efolds = rate * span
    excited = bool(math.isfinite(efolds) and efolds >= efolds_needed)
    cert = {"final": _list(final), "matching": want.tolist(), "relative_error": _list(rel), "rate_per_s": _json(rate),
            "efolds": _json(efolds), "window_s": [t0, float(t[-1])], "excited": excited}
    words = (f"{', '.join(names)} end at {', '.join(_f(v) for v in final)}; the ideal values are "
             f"{', '.join(f'{v:.4g}' for v in want)} (largest relative error {_f(100 * worst, 3)} %)")
    pe = (f"excitation after t = {t0:g} s: slowest averaged rate ρ = {_f(rate, 3)} 1/s, {_f(efolds, 3)} time "
          f"constants in the {span:.4g} s left")
    if excited:
        detail = f"{words}; {pe} (≥ {efolds_needed:g}: convergence expected)"
        if not converged:
            detail += ": they did not converge although the excitation justifies it"
        return (Check("parameter_convergence", converged, target, _json(worst), _json(converged_rel - worst),
                      "1 (relative)", detail, cert),)
    detail = (f"{words}; {pe} (< {efolds_needed:g}: the excitation does not justify expecting convergence; reported, "
              f"{'converged anyway' if converged else 'not converged'})")
    return (Check("parameter_convergence", converged, target, _json(worst), _json(converged_rel - worst),
                  "1 (relative)", detail, cert, required=False),)


def _excitation(design: Any, sim: Any, mask: np.ndarray) -> float:
    """``rho`` (module docstring) from the recorded regressor (the sensitivity filters' outputs, or ``omega``)."""
    x = design.data
    s = x.structure
    phi = _regressor(design, sim)[mask]
    if phi.size == 0 or not np.all(np.isfinite(phi)):
        return math.nan
    weights = 1.0 / (x.normalization + np.sum(phi * phi, axis=1)) if x.rule == "normalized" else np.ones(len(phi))
    G = (phi * weights[:, None]).T @ phi / len(phi)
    root = np.diag(np.sqrt(np.asarray(x.gamma, dtype=float)))
    kp, km = s.plant_num[0], s.model_num[0]
    scale = abs(kp / km) * (abs(s.static_gain) if x.rule != "lyapunov" else 1.0)
    return float(scale * np.linalg.eigvalsh(root @ G @ root)[0])


def _regressor(design: Any, sim: Any) -> np.ndarray:
    """``phi`` along the run (N x p): the sensitivity filters' outputs (rules mit, normalized) or ``omega``."""
    x = design.data
    s = x.structure
    names = list(sim.controller_state_names)
    xc = np.asarray(sim.controller_state, dtype=float)
    n, nm = s.order, len(s.model_den) - 1
    y = np.asarray(sim.state, dtype=float)[:, sim.positions[0]]
    uc = np.asarray(sim.reference, dtype=float)[:, 0, 0]
    wy = [xc[:, names.index(f"wy{k + 1}")] for k in range(n - 1)]
    wu = [xc[:, names.index(f"wu{k + 1}")] for k in range(n - 1)]
    omega = np.column_stack([uc, -y, *[-w for w in reversed(wy)], *[-w for w in reversed(wu)]])
    if x.rule == "lyapunov":
        return omega
    b = np.zeros(nm + 1)
    b[nm + 1 - len(s.model_num):] = s.model_num
    asc = b[::-1][:nm] / s.static_gain
    return np.column_stack([sum(asc[k] * xc[:, names.index(f"phi{i + 1}_{k + 1}")] for k in range(nm))
                            for i in range(2 * n)])
