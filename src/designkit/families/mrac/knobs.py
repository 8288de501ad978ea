"""What a study may vary of an MRAC design, and what it measures: the adaptation gain and the reference model's
speed, against the error from the reference model and the adapted parameters' distance from their matching
values."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.families.mrac.runs import adapted, final_link, matching, rms
from designkit.synthesis.knobs import Knob, Metric

__all__ = ["KNOBS", "METRICS"]

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
)
"""The MRAC's metrics, the error against the reference model first."""
