"""The runs lab experiment 2 makes: each adaptive controller of the comparison run again, through its family's own
run and checks, with one thing changed.

* **adaptation parameters**: each knob its family declares with the role ``adaptation`` (an adaptation gain,
  divided and multiplied by 10: :data:`ROLE_FACTORS`) or ``forgetting`` (a forgetting factor, its memory ``1 -
  lambda`` multiplied by 5 and divided by 10: 0.99 becomes 0.95 and 0.999);
* **modifications**: each variant its family declares with the role ``modification`` (the ad hoc modifications of
  the off-the-shelf algorithm: a normalised or dead-zoned rule, a projection, safeguards turned off), on the
  comparison's scenario and through the larger change;
* **an external perturbation**: an input-equivalent step of a tenth of the smaller peak command (one significant
  digit) from half-way through the time after the plant change plus a quarter of the reference's period;
* **a larger change**: the spec's plant change with the link's time constant also grown by 60 % (the SELFTUNE
  example's change), when the plant has one.

Every run goes through :func:`~designkit.studies.core.members.run_again`: its outcome, its checks and its numbers
are its own.  The budget (:class:`~designkit.studies.core.budget.Budget`) is checked before each; what does not fit
is listed in :attr:`~designkit.studies.core.members.Plan.left`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.studies.core.members import Measured, Member, Plan, run_again
from designkit.studies.core.metrics import metrics_of

__all__ = ["LARGER_TAU", "ROLE_FACTORS", "Perturbed", "adaptation_runs", "larger_change", "modification_runs",
           "perturbation", "perturbed_runs", "scenario_runs"]

ROLE_FACTORS = {"adaptation": (0.1, 10.0), "forgetting": (5.0, 0.1)}
"""Factors each adaptation parameter is moved by, by its knob's role (a forgetting factor's on ``1 - lambda``)."""
LARGER_TAU = 1.6
"""The larger change grows the link's time constant by this factor on top of the spec's change."""
PERTURBATION_SHARE = 0.1
"""The perturbation step is this fraction of the smaller peak command (one significant digit)."""


def _metrics(m: Member) -> tuple:
    return metrics_of(m.run, m.family)


def adaptation_runs(m: Member, plan: Plan) -> list[tuple[Any, list[Measured]]]:
    """``(knob, runs)`` for each adaptation parameter of ``m``'s family (module docstring)."""
    from designkit.runner.variants import knob_value, vary

    out = []
    for knob in m.family.knobs:
        if knob.role not in ROLE_FACTORS or not knob.path or not knob.applies(m.run.design):
            continue
        current = knob_value(knob, m.run.loaded.spec, m.run.design)
        if current is None:
            continue
        runs = []
        for f in ROLE_FACTORS[knob.role]:
            value = knob.scaled(current, f)
            if not all(knob.inside(float(v)) for v in np.atleast_1d(value)):
                continue
            words = f"{knob.meaning} {knob.key} = {_value(value)}"
            if not plan.fits(f"{m.label}: {words}", 2):
                continue
            runs.append(run_again(m, words, lambda k=knob, v=value: vary(m.run, k, v), value, _metrics(m),
                                  plan.budget, table=True, factor=f))
        if runs:
            out.append((knob, runs))
    return out


def _value(value: Any) -> str:
    from designkit.studies.core.members import amount

    arr = np.atleast_1d(np.asarray(value, dtype=float))
    return amount(float(arr[0]), "", 4) if arr.size == 1 or np.all(arr == arr[0]) else \
        "(" + ", ".join(amount(float(v), "", 4) for v in arr) + ")"


def modification_runs(m: Member, plan: Plan, extra: tuple[tuple[str, Any], ...] = (), where: str = ""
                      ) -> list[tuple[Any, Measured]]:
    """``(variant, run)`` for each modification ``m``'s family declares that applies to its run, with the spec
    changes ``extra`` added (``where`` says what they are, for the budget's words)."""
    from designkit.runner.variants import vary_spec

    out = []
    for variant in m.family.variants:
        if variant.role != "modification":
            continue
        changes = variant.changes_for(m.run)
        if not changes:
            continue
        if not plan.fits(f"{m.label}: the {variant.label}{where}", 2):
            continue
        every = (*changes, *extra)
        out.append((variant, run_again(m, variant.label, lambda c=every: vary_spec(m.run, c), 1.0, _metrics(m),
                                       plan.budget, table=True)))
    return out


def larger_change(result: Any) -> dict[str, float] | None:
    """The larger plant change (module docstring): the spec's values, and the link's time constant grown by
    :data:`LARGER_TAU`; None without a plant change or a time constant."""
    change = result.loaded.spec.simulation.plant_change
    plant = result.results[0].plant if result.results[0].plant is not None else result.results[0].design.plant
    names = {p.name for p in plant.parameters}
    if change is None or "tau" not in names:
        return None
    return {**{k: float(v) for k, v in change.values.items()}, "tau": LARGER_TAU * float(plant.parameter("tau").value)}


def scenario_runs(m: Member, plan: Plan, changes: tuple[tuple[str, Any], ...], words: str) -> Measured | None:
    """``m`` run again with the spec ``changes`` (``words``: what they are), with the table's metrics."""
    from designkit.runner.variants import vary_spec

    if not plan.fits(f"{m.label}: {words}", 2):
        return None
    return run_again(m, words, lambda: vary_spec(m.run, changes), 1.0, _metrics(m), plan.budget, table=True)


def perturbation(result: Any) -> tuple[float, float] | None:
    """``(value, onset)``: the perturbation step (the plant's disturbance unit) and its onset (s) (module
    docstring); None when a run has no finite peak command."""
    spec = result.loaded.spec
    t_end = float(spec.simulation.duration or result.results[0].simulation.time[-1])
    change = spec.simulation.plant_change
    tc = float(change.time) if change is not None else 0.0
    period = float(getattr(spec.simulation.trajectory, "period", 0.0) or 0.0)
    onset = round(tc + (t_end - tc) / 2.0 + period / 4.0, 6)
    peaks = [row.values.get("peak_command") for row in result.table.rows]
    finite = [p for p in peaks if p is not None and math.isfinite(p)]
    if not finite:
        return None
    return float(f"{PERTURBATION_SHARE * min(finite):.1g}"), onset


@dataclass(frozen=True)
class Perturbed:
    """A member run again with the perturbation step, against its own run.

    Parameters
    ----------
    measured : Measured
        The perturbed run.
    rms, peak : float
        RMS and largest ``|x - x0|`` (rad or m) from the onset on, ``x0`` the member's own run.
    recovery : float
        Time (s) after the onset from which ``|x - x0|`` stays within 1 % of the reference's range (``inf``: never
        within the run).
    final : float
        ``|x - x0|`` averaged over the last reference period (rad or m).
    """

    measured: Measured
    rms: float
    peak: float
    recovery: float
    final: float


def perturbed_runs(m: Member, plan: Plan, value: float, onset: float) -> Perturbed | None:
    """``m`` run again with the perturbation step ``value`` from ``onset`` (module docstring) and compared with its
    own run."""
    from designkit.comparison.metrics import REBAND, deviation, reconvergence_time
    from designkit.runner.variants import vary_spec

    words = f"a perturbation step of {value:g} from t = {onset:g} s"
    if not plan.fits(f"{m.label}: {words}", 1):
        return None
    changes = (("simulation.perturbation", {"value": value, "time": onset}),)
    done = run_again(m, words, lambda: vary_spec(m.run, changes), value, _metrics(m), plan.budget)
    if done.run is None or done.run.simulation is None:
        return Perturbed(done, math.nan, math.nan, math.nan, math.nan)
    sim, base = done.run.simulation, m.run.simulation
    d = deviation(sim, base)
    t = np.asarray(sim.time, dtype=float)[: d.size]
    xd = np.asarray(base.desired, dtype=float)
    band = REBAND * max(float(np.max(xd) - np.min(xd)), 1e-12)
    after = t >= onset
    period = getattr(m.run.loaded.spec.simulation.trajectory, "period", None) or (t[-1] - t[0]) / 4.0
    last = t >= t[-1] - float(period)
    finite = np.isfinite(d)
    rms = float(np.sqrt(np.mean(d[after] ** 2))) if np.all(finite[after]) else math.inf
    peak = float(np.max(d[after])) if np.all(finite[after]) else math.inf
    final = float(np.mean(d[last])) if np.all(finite[last]) else math.inf
    return Perturbed(done, rms, peak, reconvergence_time(t, d, onset, band), final)
