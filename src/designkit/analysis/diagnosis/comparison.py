"""The same time-domain metrics on the ideal linear response and on the nonlinear simulation, side by side."""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from designkit.display.numbers import quantity

__all__ = ["MetricPair", "compare", "linear_vs_nonlinear"]


@dataclass(frozen=True)
class MetricPair:
    """One metric on the ideal linear response and on the nonlinear simulation (formatted, ``""``: not available)."""

    metric: str
    unit: str
    linear: str
    nonlinear: str


def _metrics_of(sim: Any, band: float) -> Any:
    from designkit.verification.time_domain import response_metrics

    with np.errstate(all="ignore"):
        return response_metrics(sim, settling_band=band)


def _linear_run(result: Any) -> Any | None:
    """The ideal linear response on the simulation's instants, reference and perturbation, as a run-like value."""
    from designkit.simulation.linear import linear_response

    sim, design = result.simulation, result.design
    if sim is None or design.closed_loop is None or sim.task_space or design.linear_law is None:
        return None
    t = np.asarray(sim.time, float)
    try:
        pert = np.asarray(sim.perturbation, float)
        positions, u = linear_response(design, t, np.asarray(sim.reference, float), pert if pert.size else None,
                                       plant=result.plant)
    except Exception:  # noqa: BLE001 -- no linear response (e.g. no equilibrium): the column stays empty
        return None
    nx = len(sim.state_names)
    state = np.full((t.size, nx), np.nan)
    state[:, list(sim.positions)] = positions
    return SimpleNamespace(time=t, reference=sim.reference, state=state, positions=sim.positions, tracked=None,
                           u_command=u, u_applied=u, kind=sim.kind)


def linear_vs_nonlinear(result: Any) -> tuple[MetricPair, ...]:
    """The time-domain metrics of the ideal linear response and of the simulation, side by side."""
    return compare(result)[0]


def compare(result: Any) -> tuple[tuple[MetricPair, ...], Any]:
    """The metric pairs and the linear response's :class:`ResponseMetrics` (None when not available).

    Nothing when the design has no linear loop (its linearization contract is ``none``: a switching law),
    since there is no linear model to set beside the run.
    """
    sim = result.simulation
    if sim is None or result.design.closed_loop is None:
        return (), None
    req = result.loaded.spec.requirements
    band = req.settling_band if req is not None else 0.02
    nl = _metrics_of(sim, band)
    lin_run = _linear_run(result)
    lin = _metrics_of(lin_run, band) if lin_run is not None else None
    units = sorted(set(sim.coordinate_units)) if sim.task_space else ["rad"]
    unit = "/".join(units)
    plant = getattr(result, "plant", None)
    command = "/".join(sorted({s.unit for s in plant.inputs})).replace("*", "·") if plant is not None else "N·m"
    if sim.kind == "trajectory":
        rows = [("max tracking error", unit, "max_tracking_error"), ("settling time", "s", "settling_time"),
                ("final tracking error", unit, "steady_state_error"), ("peak |u| commanded", command, "peak_u_command")]
    else:
        rows = [("overshoot", "%", "overshoot"), ("settling time", "s", "settling_time"),
                ("rise time", "s", "rise_time"), ("steady-state error", unit, "steady_state_error"),
                ("peak |u| commanded", command, "peak_u_command")]
    digits = {"steady_state_error": 3}
    out = []
    for label, u, key in rows:
        d = digits.get(key, 4)
        out.append(MetricPair(label, u, quantity(getattr(lin, key) if lin is not None else None, digits=d),
                              quantity(getattr(nl, key), digits=d)))
    return tuple(out), lin
