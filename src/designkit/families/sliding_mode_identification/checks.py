"""The identification's own checks, on the recorded signals of the run (the true link is known in simulation).

``switching_condition`` (order 131, required): the observer's condition ``c > max |ah - a|`` and
``d > max |bh - b|`` along the run (the true ``a``, ``b`` at every sample, after ``simulation.plant_change`` the
new ones), and the stated error bounds covering the initial errors.

``identification_lyapunov`` (order 132, required): ``V = (a - ah)^2/ga + (b - bh)^2/gb`` does not increase
(to :data:`V_TOL` of its value at the segment's start) on each segment where the link is fixed; for ``D`` plus
two samples after a change the second time point still sees the old link, and ``V`` is not judged there.

``determinant_condition`` (order 133, required): ``det [x2(t) u(t); x2(t-D) u(t-D)]`` is away from zero
(``|det| >= DET_REL x max |det|``) on at least :data:`DET_FRACTION` of the samples after the first ``D``.

``identification_convergence`` (order 134): ``ah``, ``bh`` at the end within :data:`CONVERGED_REL` of the true
values at the end, with the excitation indicator ``rho = lambda_min(Gamma^1/2 G Gamma^1/2)``,
``G = mean(phi(t) phi(t)' + phi(t-D) phi(t-D)')`` over the last segment (``phi = (-x2, u)``): the slowest rate
(1/s) of the averaged update ``theta~' = -Gamma G theta~``.  Required when ``rho`` times the segment's length is
at least :data:`EFOLDS`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.sliding_mode_identification.data import ArmIdentifierData
from designkit.families.sliding_mode_identification.laws import KIND
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context

__all__ = ["CONVERGED_REL", "DET_FRACTION", "EFOLDS", "RULES", "diagnose", "excitation", "segments",
           "true_parameters", "lyapunov"]

CONVERGED_REL = 0.02
"""Converged: both estimates within this fraction of the true values."""
EFOLDS = 5.0
"""Excitation justifies convergence when the averaged rate times the segment's length is at least this."""
V_TOL = 1e-6
"""V may rise by this fraction of its value at the segment's start (rounding of the sampled update)..."""
V_FLOOR = 1e-9
"""... plus this much (V's units): the reconstructed x2' is the mean over a sample, matched by the mean speed to
O(Ts^2), which leaves an exactly known start (V = 0) drifting by about 1e-11."""
DET_REL = 1e-3
"""A determinant counts as nonzero above this fraction of its largest magnitude."""
DET_FRACTION = 0.1
"""The determinant condition holds when it is nonzero on at least this fraction of the samples."""


def _applies(design: Any, ctx: Context) -> bool:
    return design.kind == KIND and ctx.simulation is not None


def _f(x: float | None, digits: int = 4) -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def _ab(plant: Any) -> tuple[float, float]:
    Km, tau = float(plant.parameter("Km").value), float(plant.parameter("tau").value)
    return 1.0 / tau, Km / tau


def true_parameters(spec: Any, plant: Any, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The true ``a = 1/tau`` (1/s) and ``b = Km/tau`` ((rad/s^2)/(N*m)) at the times ``t`` (s)."""
    a0, b0 = _ab(plant)
    a, b = np.full(t.shape, a0), np.full(t.shape, b0)
    change = spec.simulation.plant_change
    if change is not None:
        a1, b1 = _ab(plant.with_params(**change.values))
        after = t >= float(change.time)
        a[after], b[after] = a1, b1
    return a, b


def segments(spec: Any, t: np.ndarray, window: float, Ts: float) -> list[np.ndarray]:
    """Masks of the samples where the link and both time points see one link: ``[0, T)`` and ``[T + D + 2 Ts, end]``."""
    change = spec.simulation.plant_change
    if change is None or float(change.time) > t[-1]:
        return [np.ones(t.shape, dtype=bool)]
    T = float(change.time)
    return [m for m in (t < T, t >= T + window + 2 * Ts) if m.any()]


def lyapunov(design: Any, spec: Any, plant: Any, sim: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(t, V)`` of the run (module docstring)."""
    t = np.asarray(sim.time, dtype=float)
    a, b = true_parameters(spec, plant, t)
    g = design.data.gamma
    ah, bh = (np.asarray(sim.signals[n], dtype=float) for n in ("a_hat", "b_hat"))
    with np.errstate(over="ignore", invalid="ignore"):  # estimates that blew up give V = inf (or NaN): judged so
        return t, (a - ah) ** 2 / g[0] + (b - bh) ** 2 / g[1]


def excitation(design: Any, sim: Any, mask: np.ndarray) -> dict[str, Any]:
    """The Gram matrix ``G`` of the two-point regressors over ``mask``, ``rho`` (1/s) and the determinant's record."""
    x = design.data
    t = np.asarray(sim.time, dtype=float)
    x2 = np.asarray(sim.state, dtype=float)[:, sim.velocities[0]]
    u = np.asarray(sim.u_command, dtype=float)[:, 0]
    N = max(1, int(round(x.window / x.Ts)))
    # regressors as the identifier forms them: mean speed and the command over the last sample, and D earlier
    xm = np.concatenate([[0.0], 0.5 * (x2[1:] + x2[:-1])])
    pu = np.concatenate([[0.0], u[:-1]])
    xD = np.concatenate([np.zeros(N), xm[:-N]])
    uD = np.concatenate([np.zeros(N), pu[:-N]])
    with np.errstate(over="ignore", invalid="ignore"):  # a run that blew up: products inf or NaN, judged so
        det = xm * uD - pu * xD
        m = mask & (t >= t[0] + x.window)
        phi1 = np.stack([-xm[m], pu[m]])
        phi2 = np.stack([-xD[m], uD[m]])
        G = (phi1 @ phi1.T + phi2 @ phi2.T) / max(int(m.sum()), 1)
        root = np.diag(np.sqrt(np.asarray(x.gamma, dtype=float)))
        P = root @ G @ root
    rho = (float(np.linalg.eigvalsh(P)[0]) if np.all(np.isfinite(P)) else math.nan) if m.any() else 0.0
    span = float(t[m][-1] - t[m][0]) if m.any() else 0.0
    return {"gram": G, "rho": rho, "span": span, "det": det, "mask": m, "regressors": (xm, pu, xD, uD)}


def sampled_step(design: Any, sim: Any) -> float:
    """The largest ``Ts lambda_max(Gamma^1/2 Phi Gamma^1/2)`` along the run, ``Phi = phi(t) phi(t)' + phi(t-D)
    phi(t-D)'``: the sampled update ``theta~(k+1) = (I - Ts Gamma Phi) theta~(k)`` changes ``V`` by
    ``-Ts theta~' Phi theta~ (2 - Ts lambda_max)`` at most, so ``V`` does not increase while this stays below 2."""
    x = design.data
    ex = excitation(design, sim, np.ones(len(sim.time), dtype=bool))
    xm, pu, xD, uD = ex["regressors"]
    ga, gb = x.gamma
    with np.errstate(over="ignore", invalid="ignore"):  # a run that blew up: inf or NaN, judged below
        p11 = ga * (xm**2 + xD**2)
        p22 = gb * (pu**2 + uD**2)
        p12 = -math.sqrt(ga * gb) * (xm * pu + xD * uD)
        lam = 0.5 * (p11 + p22) + np.sqrt(0.25 * (p11 - p22) ** 2 + p12**2)
    return float(x.Ts * np.max(lam)) if lam.size and np.all(np.isfinite(lam)) else math.inf


def _switching(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim, x = ctx.simulation, design.data
    t = np.asarray(sim.time, dtype=float)
    a, b = true_parameters(ctx.spec, ctx.true_plant(design), t)
    ea = float(np.max(np.abs(a - np.asarray(sim.signals["a_hat"], dtype=float))))
    eb = float(np.max(np.abs(b - np.asarray(sim.signals["b_hat"], dtype=float))))
    ok = bool(x.c > ea and x.d > eb)
    e0 = (abs(a[0] - x.initial[0]), abs(b[0] - x.initial[1]))
    covered = bool(e0[0] <= x.error_bounds[0] and e0[1] <= x.error_bounds[1])
    ratio = min(x.c / ea if ea > 0 else math.inf, x.d / eb if eb > 0 else math.inf)
    detail = (f"largest estimation errors along the run |a − â| = {_f(ea)} 1/s (c = {_f(x.c)} 1/s) and "
              f"|b − b̂| = {_f(eb)} rad/(s²·N·m) (d = {_f(x.d)} rad/(s²·N·m)); the condition "
              f"{'holds' if ok else 'is violated'}; the least gains the stated error bounds require are "
              f"c = {_f(x.required[0])} 1/s, d = {_f(x.required[1])} rad/(s²·N·m)")
    if not covered:
        detail += (f"; the initial errors ({_f(e0[0])} 1/s, {_f(e0[1])} rad/(s²·N·m)) exceed the stated bounds "
                   f"({_f(x.error_bounds[0])}, {_f(x.error_bounds[1])})")
    cert = {"max_error": [ea, eb], "gains": [x.c, x.d], "required": list(x.required),
            "initial_error": list(e0), "bounds_cover_initial": covered}
    return (Check("switching_condition", ok, "min(c / max|â − a|, d / max|b̂ − b|) > 1", _json(ratio),
                  _json(ratio - 1.0), "1 (ratio)", detail, cert),)


def _json(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _lyapunov(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    t, V = lyapunov(design, ctx.spec, ctx.true_plant(design), sim)
    worst, where = 0.0, None
    for m in segments(ctx.spec, t, design.data.window, design.data.Ts):
        seg = V[m]
        with np.errstate(invalid="ignore"):  # inf - inf of a V that blew up: NaN, and V not finite fails below
            rise = (seg - np.minimum.accumulate(seg) - V_FLOOR) / max(float(seg[0]), 1e-300)
        rise = np.where(np.isnan(rise), -np.inf, rise)
        k = int(np.argmax(rise))
        if rise[k] > worst:
            worst, where = float(rise[k]), float(t[m][k])
    ok = bool(worst <= V_TOL) and bool(np.all(np.isfinite(V)))
    step = sampled_step(design, ctx.simulation)
    detail = (f"V = (a − â)²/γa + (b − b̂)²/γb from {_f(float(V[0]))} to {_f(float(V[-1]))}; its largest rise within "
              f"a segment, beyond {V_FLOOR:g}, is {_f(worst, 3)} of the segment's initial value (tolerance "
              f"{V_TOL:g}); the sampled update's step Ts λmax(Γ½ Φ Γ½) peaks at {_f(step, 3)} "
              "(V decreases at every sample only below 2)")
    if where is not None and not ok:
        detail += f", at t = {where:.4g} s"
    cert = {"V_initial": _json(float(V[0])), "V_final": _json(float(V[-1])), "largest_rise": _json(worst),
            "at_s": where, "sampled_step_peak": _json(step), "sampled_step_limit": 2.0}
    target = f"V non-increasing (rise ≤ {V_TOL:g} V0 + {V_FLOOR:g})"
    return (Check("identification_lyapunov", ok, target, worst, V_TOL - worst, "1 (relative)", detail, cert),)


def _determinant(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    t = np.asarray(sim.time, dtype=float)
    rec = np.asarray(sim.signals["det"], dtype=float)
    m = t >= t[0] + design.data.window
    peak = float(np.max(np.abs(rec[m]))) if m.any() else 0.0
    frac = float(np.mean(np.abs(rec[m]) >= DET_REL * peak)) if peak > 0 else 0.0
    ok = bool(frac >= DET_FRACTION and peak > 0)
    detail = (f"det [x2(t) u(t); x2(t − D) u(t − D)] is away from zero on {_f(100 * frac, 3)} % of the samples after "
              f"the first D = {design.data.window:g} s (largest magnitude {_f(peak)} rad·N·m/s)")
    if not ok:
        detail += ": the input does not excite the two time points independently, a and b cannot be told apart"
    cert = {"fraction": frac, "peak": peak, "threshold_rel": DET_REL}
    return (Check("determinant_condition", ok, f"det ≠ 0 on ≥ {100 * DET_FRACTION:g} % of the samples", frac,
                  frac - DET_FRACTION, "1 (fraction)", detail, cert),)


def _convergence(design: Any, ctx: Context) -> tuple[Check, ...]:
    sim = ctx.simulation
    t = np.asarray(sim.time, dtype=float)
    a, b = true_parameters(ctx.spec, ctx.true_plant(design), t)
    last = segments(ctx.spec, t, design.data.window, design.data.Ts)[-1]
    ex = excitation(design, sim, last)
    efolds = ex["rho"] * ex["span"]
    excited = bool(efolds >= EFOLDS)
    ah, bh = float(sim.signals["a_hat"][-1]), float(sim.signals["b_hat"][-1])
    rel = max(abs(ah - a[-1]) / abs(a[-1]), abs(bh - b[-1]) / abs(b[-1]))
    ok = bool(rel <= CONVERGED_REL)
    detail = (f"â = {_f(ah)} 1/s against a = {_f(float(a[-1]))} 1/s, b̂ = {_f(bh)} rad/(s²·N·m) against "
              f"b = {_f(float(b[-1]))} rad/(s²·N·m) (largest relative error {_f(100 * rel, 3)} %); excitation "
              f"ρ = {_f(ex['rho'], 3)} 1/s over {ex['span']:.4g} s, {_f(efolds, 3)} time constants")
    detail += (f" (≥ {EFOLDS:g}: convergence expected)" if excited else
               f" (< {EFOLDS:g}: the excitation does not justify expecting convergence; reported)")
    cert = {"final": [ah, bh], "true": [float(a[-1]), float(b[-1])], "relative_error": rel, "rho": ex["rho"],
            "efolds": efolds, "excited": excited, "gram": ex["gram"].tolist()}
    return (Check("identification_convergence", ok, f"â, b̂ within {100 * CONVERGED_REL:g} % of a, b", rel,
                  CONVERGED_REL - rel, "1 (relative)", detail, cert, required=excited),)


def diagnose(result: Any, check: Any) -> tuple[str, str] | None:
    """Why an identification check failed, and what would fix it."""
    if check.passed is not False:
        return None
    x = result.design.data
    if isinstance(x, ArmIdentifierData):
        from designkit.families.sliding_mode_identification import arm_checks

        return arm_checks.diagnose(result, check)
    if check.name == "switching_condition":
        need = max(check.certificate["max_error"][0], x.required[0])
        needd = max(check.certificate["max_error"][1], x.required[1])
        return ("The observer's switching gains are below the estimation errors they must dominate, so the sliding "
                "variable leaves zero and the acceleration it reconstructs is wrong: " + check.detail + ".",
                f"Use c > {need:.4g} 1/s and d > {needd:.4g} rad/(s²·N·m) (leave them out to get "
                "1.5 times the least the error bounds require), or state error bounds that cover the initial errors.")
    if check.name == "determinant_condition":
        return ("Most of the time the speed and the command at the two time points are zero or proportional, so "
                "the determinant that tells a from b vanishes and the update cannot separate them: " + check.detail
                + ".",
                "Drive the link with a reference that keeps changing through the whole run: a square wave whose "
                "period is a few times D (2 s with D = 0.25 s identifies this link to 1e-6), or a PRBS.")
    if check.name == "identification_convergence":
        return ("The estimates did not reach the true values although the excitation justifies it: " + check.detail
                + ".", "Raise the adaptation gains or run longer; check the switching condition.")
    if check.name == "identification_lyapunov":
        peak = check.certificate.get("sampled_step_peak")
        scale = f" by at least {peak / 1.8:.3g} times" if peak is not None and peak > 2 else ""
        return ("The Lyapunov function of the estimation error rose: " + check.detail + ".",
                f"Lower the adaptation gains{scale} (or shorten the sampling period) so that the sampled update's "
                "step stays below 2, or drive the link with a smaller command swing.")
    return None


def _form(run: Any, name: str) -> Any:
    """``run`` on the link; on a robot the check of the same name in
    :mod:`~designkit.families.sliding_mode_identification.arm_checks`."""
    def go(design: Any, ctx: Context) -> tuple[Check, ...]:
        if isinstance(design.data, ArmIdentifierData):
            from designkit.families.sliding_mode_identification import arm_checks

            return getattr(arm_checks, name)(design, ctx)
        return run(design, ctx)

    return go


def _rule(name: str, order: int, run: Any, label: str) -> CheckRule:
    return CheckRule(name=name, order=order, applies=_applies, run=_form(run, name), label=label, diagnose=diagnose)


RULES = (
    _rule("switching_condition", 131, _switching, "Observer switching condition"),
    _rule("identification_lyapunov", 132, _lyapunov, "Lyapunov function of the estimation error"),
    _rule("determinant_condition", 133, _determinant, "Determinant condition of the two time points"),
    _rule("identification_convergence", 134, _convergence, "Convergence of the estimates"),
)
"""The family's own check rules, in report order."""
