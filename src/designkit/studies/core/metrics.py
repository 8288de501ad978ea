"""The numbers a study measures on a run: the family's own metrics first, then the generic ones.

The generic metrics read only the run's record, the same way for every law: for one step the RMS tracking error,
the overshoot and the settling time; for a square wave or a PRBS the RMS tracking error; for a trajectory the peak,
RMS and final tracking error; for all the peak command.  Several tracked coordinates are taken together: the largest
value over them.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.synthesis.knobs import Metric

__all__ = ["generic_metrics", "metrics_of", "values"]


def _arrays(run: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    sim = run.simulation
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.tracking_errors, dtype=float).reshape(t.size, -1)
    u = np.asarray(sim.u_command, dtype=float).reshape(t.size, -1)
    return t, e, u


def _finite_or_inf(x: float) -> float:
    return float(x) if math.isfinite(x) else math.inf


def _rms(run: Any) -> float | None:
    if run.simulation is None:
        return None
    _, e, _ = _arrays(run)
    if not np.all(np.isfinite(e)):
        return math.inf
    return _finite_or_inf(float(np.max(np.sqrt(np.mean(e**2, axis=0)))))


def _peak(run: Any) -> float | None:
    if run.simulation is None:
        return None
    _, e, _ = _arrays(run)
    return _finite_or_inf(float(np.max(np.abs(e)))) if np.all(np.isfinite(e)) else math.inf


def _final(run: Any) -> float | None:
    if run.simulation is None:
        return None
    _, e, _ = _arrays(run)
    return _finite_or_inf(float(np.max(np.abs(e[-1])))) if np.all(np.isfinite(e[-1])) else math.inf


def _command(run: Any) -> float | None:
    if run.simulation is None:
        return None
    _, _, u = _arrays(run)
    return _finite_or_inf(float(np.max(np.abs(u)))) if np.all(np.isfinite(u)) else math.inf


def _step(run: Any, which: int) -> float | None:
    sim = run.simulation
    if sim is None or sim.kind != "step":
        return None
    from designkit.verification.time_domain import response_metrics

    m = response_metrics(sim)
    value = (m.overshoot, m.settling_time)[which]
    return math.inf if value is None and which == 1 else value


def _units(run: Any) -> tuple[str, str]:
    sim = run.simulation
    coords = set(getattr(sim, "coordinate_units", ()) or ())
    inputs = {s.unit for s in getattr(run.plant if run.plant is not None else run.design.plant, "inputs", ())}
    return (coords.pop() if len(coords) == 1 else ""), (inputs.pop() if len(inputs) == 1 else "")


def generic_metrics(run: Any) -> tuple[Metric, ...]:
    """The generic metrics that apply to ``run`` (module docstring), with the run's units."""
    if run.simulation is None:
        return ()
    pos, cmd = _units(run)
    peak_u = Metric("command_peak", "peak command", cmd, _command, "largest |u| over the run and the inputs")
    if run.simulation.kind == "step" and run.loaded.spec.simulation.trajectory is not None:  # square wave, PRBS
        return (Metric("error_rms", "RMS tracking error", pos, _rms, "RMS of x − xD over the run"), peak_u)
    if run.simulation.kind == "step" and run.loaded.spec.simulation.trajectory is None:  # one step
        return (Metric("error_rms", "RMS tracking error", pos, _rms, "RMS of x − xD over the run"),
                Metric("overshoot", "overshoot", "%", lambda r: _step(r, 0),
                       "largest overshoot of the step response over the tracked coordinates"),
                Metric("settling_time", "settling time", "s", lambda r: _step(r, 1),
                       "time after which every coordinate stays in its settling band (∞: never in the run)"),
                peak_u)
    return (Metric("error_peak", "peak tracking error", pos, _peak, "largest |x − xD| over the run"),
            Metric("error_rms", "RMS tracking error", pos, _rms, "RMS of x − xD over the run"),
            Metric("error_final", "final tracking error", pos, _final, "largest |x − xD| at the end of the run"),
            peak_u)


def metrics_of(run: Any, family: Any) -> tuple[Metric, ...]:
    """The family's metrics, then the generic ones whose key the family does not already use."""
    own = tuple(family.metrics)
    keys = {m.key for m in own}
    return own + tuple(m for m in generic_metrics(run) if m.key not in keys)


def values(run: Any, metrics: tuple[Metric, ...]) -> dict[str, float | None]:
    """Each metric's value on ``run``, by key."""
    with np.errstate(all="ignore"):
        return {m.key: m.value(run) for m in metrics}
