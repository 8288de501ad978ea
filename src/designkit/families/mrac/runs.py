"""What the MRAC's checks, studies and figures read off a run, and how they re-simulate a variant.

* :func:`adaptive_variant` -- the adaptive law of a design with other adaptation gains, weighting,
  initial parameters or reference model; :func:`simulate` -- a law in a spec's scenario on a plant
  (:func:`designkit.simulation.run.build`, a second simulator, as the checks compare);
* :func:`model_position`, :func:`sensitivities`, :func:`adapted` -- the run's reference-model output,
  sensitivity matrices ``S = dym/da`` (N x 2 x 2) and adapted parameters (N x 2);
* :func:`final_link` and :func:`matching` -- the true link at the end of the run (after
  ``simulation.plant_change``) and the parameters that put it exactly on the model
  (:func:`~designkit.families.mrac.model.matching_parameters`);
* :func:`assess` -- is the adaptive run bounded?  Finite, its output error ``e = ym - x1`` never beyond
  :data:`BOUND_FACTOR` times the reference's swing, its adapted parameters never beyond
  :data:`PARAMETER_FACTOR` times their initial size, and not growing: the RMS of ``e`` over the last
  window of the run at most :data:`GROWTH_LIMIT` times the RMS over the window before (windows after
  the last change of the plant or perturbation, a whole number of reference periods) -- growth judged only
  when the last window's RMS is above :data:`SETTLED` of the swing (below it the run has converged, and a
  ratio of two such small numbers says nothing);
* :func:`gram` -- the windowed Gram matrix ``mean(S' Q S)`` of the sensitivities, the
  persistent-excitation indicator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from designkit.families.mrac.laws import adaptive_law
from designkit.families.mrac.model import PARAMETERS, SENSITIVITY_NAMES, ReferenceModel, matching_parameters

__all__ = ["BOUND_FACTOR", "GROWTH_LIMIT", "Assessment", "adapted", "adaptive_variant", "assess", "change_in_run",
           "final_link", "gram", "in_run", "last_event", "matching", "model_position", "plant_ratio", "rms",
           "sensitivities", "simulate", "swing", "window_masks"]

BOUND_FACTOR = 10.0
"""A run whose output error exceeds this many times the reference's swing has diverged."""
GROWTH_LIMIT = 1.1
"""A run whose output error's RMS grows by more than this factor from one window to the next is unstable."""
SETTLED = 1e-3
"""An output error whose RMS over the last window is below this fraction of the reference's swing has converged:
its growth from the window before is not judged (two such small RMS values have no meaningful ratio)."""
PARAMETER_FACTOR = 100.0
"""Adapted parameters beyond this many times the size of their initial values have drifted without bound."""


def rms(x: np.ndarray) -> float:
    """Root mean square of the samples (``inf`` when one is not finite; 0 for no sample)."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return 0.0
    if not np.all(np.isfinite(x)):
        return math.inf
    peak = float(np.max(np.abs(x)))  # scaled by the peak: no overflow of x * x for a large finite record
    return peak * float(np.sqrt(np.mean((x / peak) ** 2))) if peak > 0 else 0.0


def adaptive_variant(design: Any, *, gamma_scale: float = 1.0, gamma: Any = None, Q: Any = None, initial: Any = None,
                     model: ReferenceModel | None = None) -> Any:
    """The design's adaptive law with some of its settings replaced (``gamma_scale`` multiplies the gains); its
    modification of the gradient rule (if any) is kept."""
    x = design.data
    g = np.asarray(x.gamma if gamma is None else gamma, dtype=float) * float(gamma_scale)
    return adaptive_law(design.plant, model or ReferenceModel(x.reference_model.a), tuple(g.tolist()),
                        [list(r) for r in (x.Q if Q is None else Q)], tuple(x.initial if initial is None
                                                                            else initial),
                        x.modification)


def simulate(spec: Any, design: Any, plant: Any, law: Any) -> Any:
    """``law`` in the scenario of ``spec`` on ``plant`` (a simulator of its own)."""
    from designkit.simulation.run import build

    return build(spec, design, plant=plant, law=law).run()


def _states(sim: Any, names: tuple[str, ...]) -> np.ndarray:
    cols = [list(sim.controller_state_names).index(n) for n in names]
    return np.asarray(sim.controller_state, dtype=float)[:, cols]


def model_position(sim: Any) -> np.ndarray:
    """The reference model's position ``ym`` along an adaptive run (rad)."""
    return np.asarray(sim.signals["ym"], dtype=float)


def sensitivities(sim: Any) -> np.ndarray:
    """``S[k] = dym/da`` at every instant ``(N, 2, 2)`` (rows ``ym1, ym2``, columns ``a1, a2``)."""
    return _states(sim, SENSITIVITY_NAMES).reshape(-1, 2, 2, order="F")


def adapted(sim: Any) -> np.ndarray:
    """The adapted parameters ``(a1, a2)`` at every instant ``(N, 2)``."""
    return _states(sim, PARAMETERS)


def in_run(spec: Any, time: float) -> bool:
    """Whether the instant ``time`` (s) falls within the run of ``spec`` (at or before ``simulation.duration``)."""
    duration = spec.simulation.duration
    return duration is None or float(time) <= float(duration) * (1 + 1e-12)


def change_in_run(spec: Any) -> Any:
    """``simulation.plant_change`` when it happens within the run, else None."""
    change = spec.simulation.plant_change
    return change if change is not None and in_run(spec, change.time) else None


def final_link(spec: Any, plant: Any) -> tuple[float, float]:
    """``(Km, tau)`` of the true link at the end of the run (after ``simulation.plant_change`` when the run
    reaches it)."""
    change = change_in_run(spec)
    p = plant.with_params(**change.values) if change is not None else plant
    return float(p.parameter("Km").value), float(p.parameter("tau").value)


def matching(design: Any, link: tuple[float, float]) -> tuple[float, float]:
    """The adapted parameters that put the link ``(Km, tau)`` on the design's reference model."""
    x = design.data
    return matching_parameters(x.reference_model.a, x.nominal, link)


def plant_ratio(design: Any, link: tuple[float, float]) -> float:
    """``k = Km tau_n/(Km_n tau)``: how much the link ``(Km, tau)`` scales both closed-loop coefficients' response
    to the adapted parameters (1 on the nominal link)."""
    n = design.data
    return link[0] * n.nominal_tau / (n.nominal_Km * link[1])


def last_event(spec: Any, duration: float) -> float:
    """The last instant (s) within the run at which the scenario changes (plant change, perturbation onset), or 0."""
    sim = spec.simulation
    times = [0.0]
    if sim.plant_change is not None:
        times.append(float(sim.plant_change.time))
    if sim.perturbation is not None:
        times.append(float(sim.perturbation.time))
    return max(t for t in times if t <= duration)


def swing(sim: Any) -> float:
    """Extent of the reference positions, the position before the motion included (rad)."""
    r = np.asarray(sim.reference, dtype=float)[:, 0, 0]
    before = float(np.asarray(sim.state, dtype=float)[0, sim.positions[0]])  # where the run starts
    return float(max(r.max(), before) - min(r.min(), before))


def _period(sim: Any) -> float | None:
    ref = sim.settings.get("reference", {})
    if ref.get("kind") == "square":
        return float(ref["period"])
    if ref.get("kind") == "prbs":
        return float(ref["bit"]) * float(ref["period_bits"])
    return None


def window_masks(sim: Any, start: float) -> tuple[np.ndarray, np.ndarray, float] | None:
    """``(last, previous, width)``: two adjacent windows ending the run after ``start`` (s), each a whole number of
    reference periods (a third of the time left, at least one period); None when there is no room for two."""
    t = np.asarray(sim.time, dtype=float)
    span = float(t[-1]) - start
    period = _period(sim)
    width = span / 3.0
    if period is not None:
        width = period * max(1, math.floor(width / period + 1e-9))
        if 2 * width > span + 1e-9:
            return None
    if width <= 0 or width < 10 * (t[1] - t[0]):
        return None
    end = float(t[-1])
    last = t > end - width - 1e-12
    prev = (t > end - 2 * width - 1e-12) & ~last
    return last, prev, width


@dataclass(frozen=True)
class Assessment:
    """Whether an adaptive run stayed bounded (module docstring).

    Parameters
    ----------
    stable : bool
    finite : bool
        Every state finite and no integrator failure.
    peak : float
        Largest ``|e|`` (rad), ``inf`` when not finite.
    bound : float
        ``BOUND_FACTOR`` times the reference's swing (rad).
    growth : float or None
        RMS of ``e`` over the last window over the previous one (None: not measured).
    window : float or None
        Width of the windows (s).
    diverged_at : float or None
        First instant ``|e|`` exceeds ``bound`` or a sample is not finite (s).
    reason : str
        In words.
    """

    stable: bool
    finite: bool
    peak: float
    bound: float
    growth: float | None
    window: float | None
    diverged_at: float | None
    reason: str


def assess(sim: Any, spec: Any, parameters: np.ndarray | None = None, size: float = 0.0) -> Assessment:
    """Is the adaptive run ``sim`` (in the scenario of ``spec``) bounded?  See the module docstring.

    ``parameters`` (N x p) are the adapted parameters along the run (default the coefficient form's ``a1, a2``);
    they have drifted beyond :data:`PARAMETER_FACTOR` times the larger of their initial size and ``size``."""
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.signals["e"], dtype=float)
    states = np.hstack([np.asarray(sim.state, dtype=float), np.asarray(sim.controller_state, dtype=float)])
    bound = BOUND_FACTOR * max(swing(sim), 1e-12)
    not_finite = ~np.all(np.isfinite(states), axis=1) | ~np.isfinite(e)
    beyond = np.abs(np.where(np.isfinite(e), e, 0.0)) > bound
    alpha = adapted(sim) if parameters is None else np.asarray(parameters, dtype=float)
    limit = PARAMETER_FACTOR * max(float(np.max(np.abs(alpha[0]))), float(size), 1e-12)
    drifted = np.max(np.abs(np.where(np.isfinite(alpha), alpha, 0.0)), axis=1) > limit
    finite = bool(not not_finite.any() and "integrator_failure" not in sim.settings)
    first = np.flatnonzero(not_finite | beyond | drifted)
    diverged_at = float(t[first[0]]) if first.size else None
    peak = float(np.max(np.abs(e))) if np.all(np.isfinite(e)) else math.inf
    if not finite or diverged_at is not None:
        parts = []
        if beyond.any():
            parts.append(f"exceeded {bound:.3g} rad ({BOUND_FACTOR:g} times the reference swing) at "
                         f"t = {t[beyond][0]:.4g} s")
        if drifted.any():
            parts.append(f"left the adapted parameters beyond {limit:.3g} ({PARAMETER_FACTOR:g} times their initial "
                         f"size) at t = {t[drifted][0]:.4g} s")
        if not_finite.any():
            parts.append(f"stopped being finite at t = {t[not_finite][0]:.4g} s")
        elif not finite:
            parts.append("stopped being finite (the integrator failed)")
        return Assessment(False, finite, peak, bound, None, None, diverged_at,
                          "the output error " + " and ".join(parts))
    masks = window_masks(sim, last_event(spec, float(t[-1])))
    if masks is None:
        return Assessment(True, True, peak, bound, None, None, None,
                          f"finite, peak |e| = {peak:.3g} rad within {bound:.3g} rad (the run leaves no room for two "
                          "windows after the last change: growth not measured)")
    last, prev, width = masks
    r_last, r_prev = rms(e[last]), rms(e[prev])
    settled = SETTLED * swing(sim)
    growth = r_last / r_prev if r_prev > 0 else (math.inf if r_last > settled else 1.0)
    stable = bool(growth <= GROWTH_LIMIT or r_last <= settled)
    words = (f"peak |e| = {peak:.3g} rad within {bound:.3g} rad; RMS of e over the last {width:.4g} s is {growth:.3g} "
             f"times the RMS over the {width:.4g} s before")
    if r_last <= settled:
        words += (f" (the last window's RMS, {r_last:.3g} rad, is below {settled:.3g} rad, {SETTLED:g} of the swing: "
                  "converged, growth not judged)")
    elif not stable:
        words += f" (more than {GROWTH_LIMIT:g}: the error grows)"
    return Assessment(stable, True, peak, bound, float(growth), float(width), None, words)


def gram(sim: Any, Q: Any, start: float) -> np.ndarray:
    """``mean(S' Q S)`` over the samples at or after ``start`` (s): 2 x 2, in the parameters' space."""
    t = np.asarray(sim.time, dtype=float)
    S = sensitivities(sim)[t >= start - 1e-12]
    Qm = np.asarray(Q, dtype=float)
    if S.shape[0] == 0:
        return np.zeros((2, 2))
    return np.einsum("nji,jk,nkl->il", S, Qm, S) / S.shape[0]


def with_gamma(design: Any, scale: float) -> Any:
    """``design`` with its adaptive law's gains scaled (the frozen loop is unchanged)."""
    return replace(design, law=adaptive_variant(design, gamma_scale=scale))
