"""Re-simulations of a comparison's controllers: an external perturbation, another parameter, another change.

Each study runs one controller's single-controller spec with one section changed (through the families'
``synthesize`` and the simulator, as the pipeline does) and measures the run against the controller's
own run of the comparison, with the metrics of :mod:`designkit.comparison.metrics`.  They answer what the
table alone cannot: sensitivity to an external perturbation, the influence of an adaptation parameter, the
robustness to a larger plant change.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.comparison.metrics import REBAND, compute_metrics, deviation, reconvergence_time

__all__ = ["PerturbationRun", "Variant", "perturbation_run", "rise_times", "variant"]


@dataclass(frozen=True)
class PerturbationRun:
    """A controller's response to an input-equivalent perturbation step.

    Parameters
    ----------
    label : str
        The controller.
    value, time : float
        The step (the plant's disturbance unit, e.g. N·m) and its onset (s).
    rms, peak : float
        RMS and largest ``|x - x0|`` (rad or m) from the onset on, ``x0`` the run without the perturbation.
    recovery : float
        Time (s) after the onset from which ``|x - x0|`` stays within 1 % of the reference's range (``inf``:
        never within the run).
    final : float
        ``|x - x0|`` averaged over the last reference period (rad or m): what the perturbation leaves behind.
    """

    label: str
    value: float
    time: float
    rms: float
    peak: float
    recovery: float
    final: float


@dataclass(frozen=True)
class Variant:
    """A controller's run with one setting changed: the setting, its value and the run's metrics."""

    label: str
    setting: str
    value: Any
    metrics: Mapping[str, float | None]
    stable: bool


def _simulate(spec: Any, plant: Any) -> Any:
    from designkit.families import synthesize
    from designkit.simulation.run import build

    design = synthesize(spec, plant)
    return build(spec, design, plant=plant).run()


def _plant(result: Any) -> Any:
    return result.plant if result.plant is not None else result.design.plant


def _with(spec: Any, section: str, **changes: Any) -> Any:
    return spec.model_copy(update={section: getattr(spec, section).model_copy(update=changes)})


def perturbation_run(label: str, result: Any, value: float, time: float) -> PerturbationRun:
    """Run ``result``'s spec with a perturbation step ``value`` from ``time`` on and compare with its own run."""
    from designkit.spec.sections import Perturbation

    spec = result.loaded.spec
    perturbed = _with(spec, "simulation", perturbation=Perturbation(value=value, time=time))
    sim = _simulate(perturbed, _plant(result))
    base = result.simulation
    d = deviation(sim, base)
    t = np.asarray(sim.time, dtype=float)[: d.size]
    xd = np.asarray(base.desired, dtype=float)
    band = REBAND * max(float(np.max(xd) - np.min(xd)), 1e-12)
    after = t >= time
    period = getattr(spec.simulation.trajectory, "period", None) or (t[-1] - t[0]) / 4.0
    last = t >= t[-1] - float(period)
    finite = np.isfinite(d)
    rms = float(np.sqrt(np.mean(d[after] ** 2))) if np.all(finite[after]) else math.inf
    peak = float(np.max(d[after])) if np.all(finite[after]) else math.inf
    return PerturbationRun(label, float(value), float(time), rms, peak, reconvergence_time(t, d, time, band),
                           float(np.mean(d[last])) if np.all(finite[last]) else math.inf)


def variant(label: str, result: Any, setting: str, value: Any, *, section: str = "controller") -> Variant:
    """Run ``result``'s spec with ``section.setting = value`` (e.g. ``controller.gamma``) and measure it."""
    from designkit.comparison.metrics import baseline_simulation

    spec = _with(result.loaded.spec, section, **{setting: value})
    spec = type(spec).model_validate(spec.model_dump())  # the families' rules on the changed section
    plant = _plant(result)
    sim = _simulate(spec, plant)
    metrics = compute_metrics(spec, sim, baseline_simulation(spec, plant))
    stable = bool(np.all(np.isfinite(np.asarray(sim.state, dtype=float)))) and all(
        v is None or math.isfinite(v) for k, v in metrics.items() if k != "reconvergence")
    return Variant(label, setting, value, metrics, stable)


def rise_times(sim: Any, fraction: float = 0.9) -> tuple[tuple[float, float], ...]:
    """``(edge time, rise time)`` (s) of each jump of the reference: the time from the jump until the output first
    covers ``fraction`` of it (``inf`` when it does not before the next jump);
    :func:`designkit.comparison.metrics.rise_times`."""
    from designkit.comparison.metrics import rise_times as measured

    return measured(sim, fraction)
