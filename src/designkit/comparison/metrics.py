"""The metrics of a comparison, computed from one simulated run (the same definitions for every controller).

Every metric reads the run's arrays only: the tracking error ``e = xD - x`` of the tracked coordinates
(:attr:`~designkit.simulation.result.SimulationResult.tracking_errors`; with several coordinates its
Euclidean norm at each instant), the command ``u`` before the actuator's nonlinearity (``u_command``; with
several inputs the largest magnitude at each instant), the reference, the law's recorded signals and the time
grid.  The plant change splits the run into *before* ``[0, tc)`` and *after* ``[tc, T]``; without one, *before*
is the whole run and the *after* metrics are not defined (None).

What is measured follows the scenario (:class:`Scenario`, read from the run's reference):

Jumps of the reference
    A jump is a sample where the reference moves by more than its velocity explains (a step, a square wave's
    edge, a PRBS switch); a run that starts off its reference (a step from the initial position) starts with one.
    The largest error over a window holding a jump is the jump itself, not the controller's, so it is not
    reported there.  With **repeated** jumps (a square wave), the RMS error of a window is dominated by the
    jumps (each is an error of its full size at once), so the error is measured **after each jump's
    transient**: over the last quarter of each level (the instants at least :data:`SETTLED_FRACTION` of the
    shortest level after the latest jump), and each jump's **90 % rise time** is measured (its mean over the
    jumps of the window).
Reference model
    A law that follows a reference model records its output as the signal :data:`MODEL_SIGNAL`; the RMS of
    ``|ym - x|`` is then reported for it (the error the law itself minimises).
Load step
    With a ``simulation.perturbation`` from ``0 < tp < T`` and no jump after it: the largest ``|e|`` from ``tp``
    on.
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
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["JUMP_TOLERANCE", "MODEL_SIGNAL", "REBAND", "RISE_FRACTION", "SETTLED_FRACTION", "SETTLING_BAND",
           "Scenario", "baseline_simulation", "compute_metrics", "deviation", "error_norm", "jumps",
           "reconvergence_time", "rise_times", "scenario"]

REBAND = 0.01
"""Re-convergence: the deviation from the unchanged plant's run back below this fraction of the reference's range."""
SETTLING_BAND = 0.02
"""Settling: the error within this fraction of the step's amplitude."""
SETTLED_FRACTION = 0.75
"""After a jump, the transient is taken as over once this fraction of the shortest level has passed: the error
after the jumps' transients is measured over the last quarter of each level."""
RISE_FRACTION = 0.9
"""Rise time: from a jump until the output first covers this fraction of it."""
JUMP_TOLERANCE = 1e-3
"""A jump: the reference moves between two samples by more than its velocity explains, by more than this
fraction of its scale (its range, or its initial distance from the output)."""
MODEL_SIGNAL = "ym"
"""The name under which a law that follows a reference model records the model's output (rad or m): the
comparison reports the output's error against it."""


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


def jumps(sim: Any) -> np.ndarray:
    """Indices of the samples where the reference jumps (:data:`JUMP_TOLERANCE`), sorted; ``0`` first when the run
    starts off its reference (a step from the initial position).

    Parameters
    ----------
    sim : SimulationResult
        The run: its ``time`` (s), ``reference`` (position in rad or m and velocity in rad/s or m/s of each tracked
        coordinate) and ``tracked_positions`` (rad or m).

    Returns
    -------
    ndarray of int
        The sample ``i`` of each jump (between samples ``i - 1`` and ``i``; 0: the start).
    """
    t = np.asarray(sim.time, dtype=float)
    ref = np.asarray(sim.reference, dtype=float).reshape(len(t), -1, 3)
    xd, vd = ref[:, :, 0], ref[:, :, 1]
    x = np.asarray(sim.tracked_positions, dtype=float).reshape(len(t), -1)
    scale = max(float(np.max(np.ptp(xd, axis=0))) if t.size else 0.0,
                float(np.max(np.abs(xd[0] - x[0]))) if t.size else 0.0, 1e-12)
    explained = 0.5 * (vd[1:] + vd[:-1]) * np.diff(t)[:, None]
    moved = np.max(np.abs(np.diff(xd, axis=0) - explained), axis=1) if t.size > 1 else np.zeros(0)
    out = (np.flatnonzero(moved > JUMP_TOLERANCE * scale) + 1).tolist()
    if t.size and float(np.max(np.abs(xd[0] - x[0]))) > JUMP_TOLERANCE * scale:
        out.insert(0, 0)
    return np.asarray(out, dtype=int)


@dataclass(frozen=True)
class Scenario:
    """What a run's task holds, as the metrics need it.

    Parameters
    ----------
    change : float or None
        The plant change's time (s), None without one inside the run.
    jumps : tuple of float
        The times (s) of the reference's jumps (:func:`jumps`).
    settle : float or None
        With repeated jumps, the delay (s) after a jump from which the error is measured: :data:`SETTLED_FRACTION`
        of the shortest level; None otherwise.
    window : float
        The last window (s): the reference's period, else a quarter of the run.
    load : float or None
        The load step's onset (s) when the metric after it applies, else None.
    """

    change: float | None
    jumps: tuple[float, ...]
    settle: float | None
    window: float
    load: float | None

    @property
    def repeated(self) -> bool:
        """The reference jumps more than once (a square wave): the error is measured after each jump's transient."""
        return self.settle is not None

    def jumps_in(self, start: float, end: float) -> tuple[float, ...]:
        """The jumps in ``[start, end]`` (s)."""
        return tuple(j for j in self.jumps if start <= j <= end)


def scenario(spec: Any, sim: Any) -> Scenario:
    """The :class:`Scenario` of one run of ``spec``.

    Parameters
    ----------
    spec : Spec
        The run's single-controller spec (its ``simulation.plant_change``, ``perturbation`` and trajectory).
    sim : SimulationResult
        The run (its time grid in s and its reference).
    """
    t = np.asarray(sim.time, dtype=float)
    change = spec.simulation.plant_change
    tc = float(change.time) if change is not None and float(change.time) < t[-1] else None
    at = tuple(float(t[i]) for i in jumps(sim))
    levels = np.diff(np.asarray(at))
    settle = SETTLED_FRACTION * float(np.min(levels)) if levels.size and float(np.min(levels)) > 0 else None
    perturbation = spec.simulation.perturbation
    tp = float(perturbation.time) if perturbation is not None else None
    load = tp if tp is not None and 0.0 < tp < t[-1] and not any(j >= tp for j in at) else None
    return Scenario(tc, at, settle, window_length(spec, t), load)


def settled(t: np.ndarray, jump_times: tuple[float, ...], settle: float) -> np.ndarray:
    """The instants at least ``settle`` after the latest jump (those before the first jump included).

    Parameters
    ----------
    t : ndarray
        The time grid (s).
    jump_times : tuple of float
        The jumps' times (s), sorted.
    settle : float
        The delay after a jump (s).

    Returns
    -------
    ndarray of bool
        One flag per instant of ``t``.
    """
    j = np.asarray(jump_times, dtype=float)
    k = np.searchsorted(j, t, side="right") - 1
    since = np.where(k >= 0, t - j[np.clip(k, 0, None)], np.inf)
    return since >= settle - 1e-12


def rise_times(sim: Any, fraction: float = RISE_FRACTION) -> tuple[tuple[float, float], ...]:
    """``(jump time, rise time)`` (s) of each jump of the reference (:func:`jumps`; first coordinate): the time
    from the jump until the output first covers ``fraction`` of it (``inf`` when it does not before the next
    jump).  A last jump cut short by the end of the run (a level shorter than the one before) is left out."""
    t = np.asarray(sim.time, dtype=float)
    xd = np.asarray(sim.desired, dtype=float).reshape(len(t), -1)[:, 0]
    x = np.asarray(sim.tracked_positions, dtype=float).reshape(len(t), -1)[:, 0]
    edges = jumps(sim).tolist()
    out = []
    for k, i in enumerate(edges):
        end = edges[k + 1] if k + 1 < len(edges) else len(t)
        if k + 1 == len(edges) and k > 0 and (end - i) < (i - edges[k - 1]):
            break
        start, target = float(x[i - 1] if i > 0 else x[0]), float(xd[i])
        level = start + fraction * (target - start)
        hit = np.flatnonzero((x[i:end] - level) * np.sign(target - start) >= 0)
        out.append((float(t[i]), float(t[i + hit[0]] - t[i]) if hit.size else math.inf))
    return tuple(out)


def _mean_rise(rises: tuple[tuple[float, float], ...], start: float, end: float) -> float | None:
    values = [r for at, r in rises if start <= at < end]
    return float(np.mean(values)) if values else None


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
    sc = scenario(spec, sim)
    tc, end = sc.change, float(t[-1])
    before = t < tc if tc is not None else np.ones(t.size, dtype=bool)
    after = ~before if tc is not None else np.zeros(t.size, dtype=bool)
    last = t >= t[-1] - sc.window
    jumps_before = bool(sc.jumps_in(0.0, (tc if tc is not None else end) - 1e-12)) if sc.jumps else False
    jumps_after = tc is not None and bool(sc.jumps_in(tc, end))
    out.update(peak_command=_max(u), rms_command=_rms(u),
               peak_command_after=_max(u[after]) if tc is not None else None)
    if sc.repeated:
        ok = settled(t, sc.jumps, sc.settle)
        out.update(rms_settled_before=_rms(e[before & ok]), max_settled_before=_max(e[before & ok]),
                   rms_settled_after=_rms(e[after & ok]) if tc is not None else None,
                   max_settled_after=_max(e[after & ok]) if tc is not None else None,
                   rms_settled_final=_rms(e[last & ok]))
    else:
        out.update(rms_error_before=_rms(e[before]), rms_error_final=_rms(e[last]),
                   rms_error_after=_rms(e[after]) if tc is not None else None)
    out.update(max_error_before=None if jumps_before else _max(e[before]),
               max_error_after=_max(e[after]) if tc is not None and not jumps_after else None)
    if sc.jumps:
        rises = rise_times(sim)
        out.update(rise_time_before=_mean_rise(rises, 0.0, tc if tc is not None else math.inf),
                   rise_time_after=_mean_rise(rises, tc, math.inf) if tc is not None else None)
    model = sim.signals.get(MODEL_SIGNAL) if getattr(sim, "signals", None) else None
    if model is not None:
        x = np.asarray(sim.tracked_positions, dtype=float).reshape(len(t), -1)[:, 0]
        em = np.abs(np.asarray(model, dtype=float) - x)
        out.update(rms_model_error_before=_rms(em[before]),
                   rms_model_error_after=_rms(em[after]) if tc is not None else None)
    if sc.load is not None:
        out["max_error_load"] = _max(e[t >= sc.load])
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
