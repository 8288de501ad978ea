"""The metrics of a comparison, computed from one simulated run (the same definitions for every controller).

Every metric reads the run's arrays only: the tracking error ``e = xD - x`` of the tracked coordinates
(:attr:`~designkit.simulation.result.SimulationResult.tracking_errors`; with several coordinates its
Euclidean norm at each instant), the command ``u`` before the actuator's nonlinearity (``u_command``; with
several inputs the largest magnitude at each instant) and the time grid.  The plant change splits the run
into *before* ``[0, tc)`` and *after* ``[tc, T]``; without one, *before* is the whole run and the *after*
metrics are not defined (None).

Deviation caused by the change
    Each controller is also run on the unchanged plant (the same spec without ``plant_change``,
    :func:`baseline_simulation`); ``d(t) = x(t) - x0(t)`` is how far the change moves its output from the
    response it would otherwise have had (zero before the change).  Its RMS and largest value after the change
    say how much the change disturbs the loop, and the **re-convergence time** is the time after the change
    after which ``|d|`` stays below :data:`REBAND` (1 %) of the reference's range ``max xD - min xD``
    (``inf``: still above it at the end of the run).
Overshoot and settling time
    Only where the reference is a step (no ``simulation.trajectory``): the largest excursion beyond the
    step's amplitude in percent of it, and the last time the error leaves the 2 % band of the amplitude.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["REBAND", "SETTLING_BAND", "baseline_simulation", "compute_metrics", "deviation", "error_norm",
           "reconvergence_time"]

REBAND = 0.01
"""Re-convergence: the deviation from the unchanged plant's run back below this fraction of the reference's range."""
SETTLING_BAND = 0.02
"""Settling: the error within this fraction of the step's amplitude."""


def error_norm(sim: Any) -> np.ndarray:
    """``|e(t)|`` (rad or m), shape (N,): the Euclidean norm of the tracking errors of the tracked coordinates."""
    e = np.asarray(sim.tracking_errors, dtype=float)
    return np.sqrt(np.sum(e * e, axis=1)) if e.ndim == 2 else np.abs(e)


def command_norm(sim: Any) -> np.ndarray:
    """``|u(t)|``, shape (N,): the largest magnitude over the inputs of the command at each instant."""
    u = np.asarray(sim.u_command, dtype=float)
    return np.max(np.abs(u), axis=1) if u.ndim == 2 else np.abs(u)


def _rms(x: np.ndarray) -> float | None:
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.sqrt(np.mean(x * x))) if x.size else None


def _max(x: np.ndarray) -> float | None:
    return float(np.max(x)) if x.size else None


def window_length(spec: Any, t: np.ndarray) -> float:
    """The last window (s): the reference's period (a square wave or sine), else a quarter of the run."""
    period = getattr(spec.simulation.trajectory, "period", None)
    if period is not None and float(period) > 0:
        return float(period)
    return (float(t[-1]) - float(t[0])) / 4.0


def deviation(sim: Any, baseline: Any) -> np.ndarray:
    """``|x(t) - x0(t)|`` (rad or m), shape (N,): the norm of the difference of the tracked coordinates between
    the run and its run on the unchanged plant (the same time grid)."""
    x = np.asarray(sim.tracked_positions, dtype=float).reshape(len(sim.time), -1)
    x0 = np.asarray(baseline.tracked_positions, dtype=float).reshape(len(baseline.time), -1)
    n = min(len(x), len(x0))
    d = x[:n] - x0[:n]
    return np.sqrt(np.sum(d * d, axis=1))


def reconvergence_time(t: np.ndarray, d: np.ndarray, tc: float, band: float) -> float:
    """Time (s) after ``tc`` from which ``d`` stays at or below ``band`` (0 if it never exceeds it; ``inf`` if it
    is above it at the last sample)."""
    after = np.flatnonzero((t[: d.size] >= tc) & ~(d <= band))  # a NaN counts as above
    if after.size == 0:
        return 0.0
    if after[-1] == d.size - 1:
        return math.inf
    return float(t[after[-1] + 1] - tc)


def baseline_simulation(spec: Any, plant: Any) -> Any:
    """The run of ``spec`` on the unchanged plant (``simulation.plant_change`` removed); None for a spec without
    a plant change or a design run in trials (a learning design)."""
    if spec.simulation.plant_change is None:
        return None
    from designkit.families import synthesize
    from designkit.simulation.run import build

    unchanged = spec.model_copy(update={"simulation": spec.simulation.model_copy(update={"plant_change": None})})
    design = synthesize(unchanged, plant)
    if design.learning is not None:
        return None
    return build(unchanged, design, plant=plant).run()


def _step_metrics(sim: Any, t: np.ndarray) -> tuple[float | None, float | None]:
    """Overshoot (%) and 2 % settling time (s) of a step response, from the first coordinate."""
    ref = np.asarray(sim.desired, dtype=float).reshape(len(t), -1)[:, 0]
    x = np.asarray(sim.joint_positions if not sim.task_space else sim.tracked_positions, dtype=float)
    x = x.reshape(len(t), -1)[:, 0]
    start, target = float(x[0]), float(ref[-1])
    amplitude = target - start
    if abs(amplitude) < 1e-12:
        return None, None
    excursion = (x - start) / amplitude
    overshoot = max(0.0, float(np.max(excursion)) - 1.0) * 100.0
    outside = np.flatnonzero(np.abs(x - target) > SETTLING_BAND * abs(amplitude))
    settling = 0.0 if outside.size == 0 else (float(t[outside[-1] + 1]) if outside[-1] + 1 < t.size else None)
    return overshoot, settling


def compute_metrics(spec: Any, sim: Any, baseline: Any = None) -> Mapping[str, float | None]:
    """Every metric of :data:`designkit.comparison.table.METRICS` for one run (None where it does not apply).

    Parameters
    ----------
    spec : Spec
        The run's single-controller spec (its ``simulation.plant_change`` and trajectory).
    sim : SimulationResult or None
        The run (None: no simulation, every metric None).
    baseline : SimulationResult or None
        The same controller's run on the unchanged plant (:func:`baseline_simulation`); None: the deviation
        metrics are not computed.

    Returns
    -------
    Mapping
        Metric key -> value in the metric's unit (rad or m, s, the command's unit, %); ``inf`` for a run that
        diverged (a non-finite value) and for a re-convergence that did not happen within the run.
    """
    from designkit.comparison.table import METRICS

    out: dict[str, float | None] = dict.fromkeys((m.key for m in METRICS), None)
    if sim is None:
        return out
    t = np.asarray(sim.time, dtype=float)
    e, u = error_norm(sim), command_norm(sim)
    change = spec.simulation.plant_change
    tc = float(change.time) if change is not None and float(change.time) < t[-1] else None
    before = t < tc if tc is not None else np.ones(t.size, dtype=bool)
    after = ~before if tc is not None else np.zeros(t.size, dtype=bool)
    last = t >= t[-1] - window_length(spec, t)
    out.update(
        rms_error_before=_rms(e[before]), max_error_before=_max(e[before]),
        rms_error_after=_rms(e[after]) if tc is not None else None,
        max_error_after=_max(e[after]) if tc is not None else None,
        rms_error_final=_rms(e[last]),
        peak_command=_max(u), rms_command=_rms(u),
        peak_command_after=_max(u[after]) if tc is not None else None,
    )
    if tc is not None and baseline is not None:
        d = deviation(sim, baseline)
        xd = np.asarray(sim.desired, dtype=float)
        band = REBAND * max(float(np.max(xd) - np.min(xd)), 1e-12)
        tail = (t[: d.size] >= tc)
        out.update(rms_deviation=_rms(d[tail]), max_deviation=_max(d[tail]),
                   reconvergence=reconvergence_time(t, d, tc, band))
    if spec.simulation.trajectory is None:
        out["overshoot"], out["settling_time"] = _step_metrics(sim, t)
    return {k: (v if v is None or math.isfinite(v) else math.inf) for k, v in out.items()}
