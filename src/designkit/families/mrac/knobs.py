"""What a study may vary of an MRAC design, and what it measures: the adaptation gain and the reference model's
speed, against the error from the reference model and the adapted parameters' distance from their matching
values; and the ad hoc modifications of the gradient rule a study may run (:data:`VARIANTS`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.mrac.runs import adapted, final_link, matching, rms, swing
from designkit.synthesis.knobs import Knob, Metric, Variant

__all__ = ["KNOBS", "METRICS", "VARIANTS"]

GAMMA_SEARCH = (1.0, 1e8)
"""The adaptation gains a study searches (the search is centred on the value in use when wider than 8 decades)."""


def _e(run: Any) -> np.ndarray:
    return np.asarray(run.simulation.signals["e"], dtype=float)


def _model_error(run: Any) -> float | None:
    return rms(_e(run)) if run.simulation is not None else None


def _late_model_error(run: Any) -> float | None:
    """RMS of ``e`` over the last quarter of the run (after the adaptation has had three quarters to act)."""
    if run.simulation is None:
        return None
    t = np.asarray(run.simulation.time, dtype=float)
    return rms(_e(run)[t >= t[0] + 0.75 * (t[-1] - t[0])])


def _parameter_error(run: Any) -> float | None:
    """Largest relative distance of the final adapted parameters from the values that put the final link on the
    model (1: as far as the values themselves)."""
    if run.simulation is None:
        return None
    final = adapted(run.simulation)[-1]
    plant = run.plant if run.plant is not None else run.design.plant
    target = np.asarray(matching(run.design, final_link(run.loaded.spec, plant)), dtype=float)
    if not np.all(np.isfinite(final)):
        return math.inf
    return float(np.max(np.abs(final - target) / np.abs(target)))


def _parameter_drift(run: Any) -> float | None:
    """Largest relative distance of the adapted parameters from the values that put the link of that instant on the
    model, over the last quarter of the run (the plant change moves those values)."""
    if run.simulation is None:
        return None
    sim, spec = run.simulation, run.loaded.spec
    t = np.asarray(sim.time, dtype=float)
    a = adapted(sim)
    plant = run.plant if run.plant is not None else run.design.plant
    link = (float(plant.parameter("Km").value), float(plant.parameter("tau").value))
    before = np.asarray(matching(run.design, link), dtype=float)
    after = np.asarray(matching(run.design, final_link(spec, plant)), dtype=float)
    change = spec.simulation.plant_change
    moved = t >= float(change.time) if change is not None else np.zeros(t.size, dtype=bool)
    target = np.where(moved[:, None], after[None, :], before[None, :])
    last = t >= t[0] + 0.75 * (t[-1] - t[0])
    if not np.all(np.isfinite(a[last])):
        return math.inf
    return float(np.max(np.abs(a[last] - target[last]) / np.abs(target[last])))


KNOBS = (
    Knob("gamma", "1/(s^5*rad^2)", "adaptation gain of the gradient rule", GAMMA_SEARCH[0], GAMMA_SEARCH[1],
         path="controller.gamma", role="adaptation", boundary=True),
    Knob("poles", "1/s", "poles of the nominal loop (the default reference model): its speed", 1e-3, 1e4,
         path="controller.poles"),
)
"""The MRAC's knobs: the adaptation gain (with its boundary) and the speed of the loop it adapts towards."""

METRICS = (
    Metric("model_error_rms", "RMS error against the reference model", "rad", _model_error,
           "RMS of e = ym − x1 over the run"),
    Metric("model_error_late", "RMS error against the reference model over the last quarter", "rad",
           _late_model_error, "RMS of e = ym − x1 over the last quarter of the run"),
    Metric("parameter_error", "distance of the adapted parameters from matching", "", _parameter_error,
           "largest |α − α*| / |α*| at the end of the run, α* the values that put the final link on the model"),
    Metric("parameter_drift", "largest distance of the adapted parameters from matching over the last quarter", "",
           _parameter_drift, "largest |α(t) − α*(t)| / |α*(t)| over the last quarter of the run, α*(t) the values "
           "that put the link of that instant on the model"),
)
"""The MRAC's metrics, the error against the reference model first."""


def _modification(kind: str, settings: Any) -> Any:
    """``run -> changes`` setting ``controller.modification`` to ``kind`` with ``settings(run)`` (none when the
    spec already has that modification)."""

    def changes(run: Any) -> tuple[tuple[str, Any], ...]:
        current = run.loaded.spec.controller.modification
        if current is not None and current.kind == kind:
            return ()
        return (("controller.modification", {"kind": kind, **settings(run)}),)

    return changes


def _box(run: Any) -> dict[str, list[float]]:
    initial = [float(v) for v in run.design.data.initial]
    return {"low": [v / BOX_FACTOR for v in initial], "high": [v * BOX_FACTOR for v in initial]}


def _plain(run: Any) -> tuple[tuple[str, Any], ...]:
    return (("controller.modification", None),) if run.loaded.spec.controller.modification is not None else ()


DEAD_ZONE_SHARE = 0.01
"""The dead zone a study tries: this fraction of the reference's swing (the comparisons' re-convergence band)."""
BOX_FACTOR = 4.0
"""The projection box a study tries: this factor either side of the initial parameters."""

VARIANTS = (
    Variant("normalized", "normalised gradient rule",
            "α' = Γ Sᵀ Q e / (1 + φᵀφ), φᵀφ = tr(Γ Sᵀ Q S)/ν, ν the reference model's natural frequency",
            _modification("normalized", lambda run: {})),
    Variant("dead_zone", "dead zone on the error",
            f"no adaptation while |ym − x1| ≤ d, d = {100 * DEAD_ZONE_SHARE:g} % of the reference's swing",
            _modification("dead_zone", lambda run: {"width": DEAD_ZONE_SHARE * swing(run.simulation)})),
    Variant("projection", "projection on a box",
            f"α kept in [α0/{BOX_FACTOR:g}, {BOX_FACTOR:g} α0], α0 the initial parameters, a box that holds a1's "
            f"matching value for the links whose gain ratio k = Km τn/(Kmn τ) lies between 1/{BOX_FACTOR:g} and "
            f"{BOX_FACTOR:g}", _modification("projection", _box)),
    Variant("plain", "plain gradient rule", "α' = Γ Sᵀ Q e, no modification", _plain),
)
"""The ad hoc modifications of the gradient rule (:mod:`~designkit.families.mrac.modification`), sized from the run
varied, and the plain rule for a spec that has one."""
