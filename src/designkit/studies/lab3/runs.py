"""The runs lab experiment 3 makes: each controller of the comparison run again, through its family's own run and
checks, with one thing changed.

* **one parameter at a time**: every spec setting its family declares as a knob (:attr:`Family.knobs
  <designkit.synthesis.family.Family.knobs>` with a ``path``) that has a value in use, moved by the knob's own
  factors (:func:`~designkit.runner.variants.vary`);
* **the load removed**: the same design run with the spec's ``simulation.perturbation`` moved past the end of the run
  (:data:`LOAD_AWAY`), to measure what the load does (:class:`LoadEffect`,
  :func:`~designkit.runner.variants.vary_scenario`: the design is the member's own, not one sized without the load);
* **the parameter box**: the true plant at every corner of ``plant.uncertainty`` (at most :data:`BOX_RUNS_MAX`),
  the controller designed as before and not told (:func:`~designkit.runner.variants.vary_plant`).

The budget is checked before each run; what does not fit is listed in
:attr:`designkit.studies.core.members.Plan.left`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number
from designkit.studies.core.members import Measured, Member, Plan, run_again
from designkit.studies.lab3.measures import measures_of

__all__ = ["BOX_RUNS_MAX", "LOAD_AWAY", "LoadEffect", "corner_runs", "corners", "load_effect", "oat_runs"]

LOAD_AWAY = 1e9
"""The load's onset (s) in the run without it: past the end of any run, so the spec still names the load a design may
be sized from, and the run never feels it."""
BOX_RUNS_MAX = 16
"""Most corners of the parameter box run per controller (a larger box is not run, and the answer says so)."""


def oat_runs(m: Member, plan: Plan) -> list[tuple[Any, list[Measured]]]:
    """``(knob, runs)`` for each spec setting of ``m``'s family moved by its own factors (module docstring)."""
    from designkit.runner.variants import knob_value, vary

    out = []
    for knob in m.family.knobs:
        if not knob.path or not knob.applies(m.run.design):
            continue
        current = knob_value(knob, m.run.loaded.spec, m.run.design)
        if current is None:
            continue
        runs = []
        for f in knob.factors:
            value = knob.scaled(current, f)
            if not all(knob.inside(v) for v in np.atleast_1d(value)):
                continue
            words = f"{knob.key} ×{fmt_number(f, 3)}"
            if not plan.fits(f"{m.label}: {words}", 1):
                continue
            runs.append(run_again(m, words, lambda k=knob, v=value: vary(m.run, k, v), value,
                                  measures_of(m.run, m.family), plan.budget, factor=f))
        if runs:
            out.append((knob, runs))
    return out


def corners(result: Any) -> list[dict[str, float]] | None:
    """The corners of the spec's ``plant.uncertainty`` (parameter name -> value, SI), None without a box or with more
    than :data:`BOX_RUNS_MAX`."""
    unc = getattr(result.loaded.spec.plant, "uncertainty", None)
    if unc is None or not unc.intervals:
        return None
    names = list(unc.intervals)
    out = [dict(zip(names, map(float, v), strict=True))
           for v in itertools.product(*(unc.intervals[n] for n in names))]
    return out if len(out) <= BOX_RUNS_MAX else None


def corner_runs(m: Member, plan: Plan, at: list[dict[str, float]]) -> list[tuple[dict[str, float], Measured]]:
    """``m``'s controller, designed as before, on the true plant at each corner ``at``."""
    from designkit.runner.variants import vary_plant

    out = []
    for values in at:
        words = ", ".join(f"{k} = {fmt_number(v, 4)}" for k, v in values.items())
        if not plan.fits(f"{m.label} at {words}", 1):
            continue
        out.append((values, run_again(m, words, lambda v=values: vary_plant(m.run, v), 1.0,
                                      measures_of(m.run, m.family), plan.budget)))
    return out


@dataclass(frozen=True)
class LoadEffect:
    """The load step's effect on a controller: its own run against its run without the load.

    Parameters
    ----------
    measured : Measured
        The run without the load.
    value, onset : float
        The load (the plant's disturbance unit) and its onset (s).
    peak, final : float
        The largest ``|x - x0|`` from the onset on and its mean over the last tenth of the run (the controlled
        position's unit), ``x0`` the run without the load.
    predicted : float or None
        The family's closed-form prediction of the static offset (``Family.predictions``: ``load_offset``), None
        when it predicts none.
    """

    measured: Measured
    value: float
    onset: float
    peak: float
    final: float
    predicted: float | None


def load_effect(m: Member, plan: Plan) -> LoadEffect | None:
    """``m`` run again without the spec's load, against its own run (None without a load, or out of budget)."""
    from designkit.runner.variants import vary_scenario

    pert = m.run.loaded.spec.simulation.perturbation
    if pert is None or not plan.fits(f"{m.label} without the load", 1):
        return None
    value = float(pert.value[0] if isinstance(pert.value, list | tuple) else pert.value)
    away = (("simulation.perturbation.time", LOAD_AWAY),)  # the spec stays valid for designs sized from the load
    done = run_again(m, "without the load", lambda: vary_scenario(m.run, away), 1.0, measures_of(m.run, m.family),
                     plan.budget)
    prediction = m.family.prediction("load_offset")
    predicted = prediction.value(m.run) if prediction is not None else None
    if done.run is None or done.run.simulation is None:
        return LoadEffect(done, value, float(pert.time), math.nan, math.nan, predicted)
    sim, base = m.run.simulation, done.run.simulation
    t = np.asarray(sim.time, float)
    n = min(len(t), len(base.time))
    x = np.asarray(sim.tracked_positions, float).reshape(len(t), -1)[:n, 0]
    x0 = np.asarray(base.tracked_positions, float).reshape(len(base.time), -1)[:n, 0]
    d = np.abs(x - x0)
    after = t[:n] >= float(pert.time)
    last = t[:n] >= t[n - 1] - 0.1 * (t[n - 1] - t[0])
    return LoadEffect(done, value, float(pert.time), float(np.max(d[after])), float(np.mean(d[last])), predicted)
