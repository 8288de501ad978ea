"""The comparison table: the same metrics for every controller, each check's verdict, and who wins on what.

:func:`comparison_table` reads the per-controller runs (their specs, simulations, checks and plants) and
returns a frozen :class:`ComparisonTable`; :meth:`ComparisonTable.winners` says, metric by metric, which
controller does best and by how much.  The metric definitions are :mod:`designkit.comparison.metrics`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from designkit.comparison.metrics import baseline_simulation, compute_metrics
from designkit.display.numbers import fmt_number, unit

__all__ = ["METRICS", "ComparisonTable", "ControllerRow", "Metric", "Winner", "baselines", "comparison_table"]


@dataclass(frozen=True)
class Metric:
    """One metric of the table.

    Parameters
    ----------
    key : str
        Its name in ``--json`` (``rms_error_after``).
    label : str
        Its heading in the report, in words.
    unit : str
        ``"error"``, ``"command"``, ``"s"`` or ``"%"``: the error's unit (rad or m), the command's, or as given.
    meaning : str
        What was computed, in words.
    """

    key: str
    label: str
    unit: str
    meaning: str


METRICS: tuple[Metric, ...] = (
    Metric("rms_error_before", "RMS tracking error before the change", "error",
           "root mean square of the tracking error |xD − x| over the run before the plant change (the whole run "
           "without one)"),
    Metric("max_error_before", "largest tracking error before the change", "error",
           "largest |xD − x| before the plant change (the whole run without one)"),
    Metric("rms_error_after", "RMS tracking error after the change", "error",
           "root mean square of |xD − x| from the plant change to the end of the run"),
    Metric("max_error_after", "largest tracking error after the change", "error",
           "largest |xD − x| from the plant change on"),
    Metric("rms_deviation", "RMS departure caused by the change", "error",
           "root mean square, from the plant change on, of |x − x0|: x0 is the same controller's output in a run "
           "on the unchanged plant"),
    Metric("max_deviation", "largest departure caused by the change", "error",
           "largest |x − x0| from the plant change on (x0: the run on the unchanged plant)"),
    Metric("reconvergence", "re-convergence time after the change", "s",
           "time after the plant change from which |x − x0| stays within 1 % of the reference's range"),
    Metric("rms_error_final", "RMS tracking error over the last period", "error",
           "root mean square of |xD − x| over the last reference period of the run"),
    Metric("peak_command", "peak command", "command", "largest |u| the controller commanded"),
    Metric("peak_command_after", "peak command after the change", "command",
           "largest |u| commanded from the plant change on"),
    Metric("rms_command", "RMS command", "command", "root mean square of the command u over the run"),
    Metric("overshoot", "overshoot", "%", "largest excursion beyond the step, in percent of the step"),
    Metric("settling_time", "settling time (2 %)", "s", "last time the position leaves the 2 % band of the step"),
)
"""Every metric, in table order (lower is better for each)."""


@dataclass(frozen=True)
class ControllerRow:
    """One controller's line of the table.

    Parameters
    ----------
    label, kind : str
        The controller's label and family kind.
    controller : str
        The family in words.
    verified : bool
        Every check of its own run passed.
    values : Mapping
        Metric key -> value (None: does not apply; ``inf``: diverged, or never re-converged).
    checks : tuple of (str, str, str)
        Each check's name, label in words and status (``PASS``, ``FAIL``, ``UNDECIDED``).
    """

    label: str
    kind: str
    controller: str
    verified: bool
    values: Mapping[str, float | None]
    checks: tuple[tuple[str, str, str], ...]

    @property
    def failed(self) -> tuple[tuple[str, str, str], ...]:
        """The checks that did not pass."""
        return tuple(c for c in self.checks if c[2] != "PASS")


@dataclass(frozen=True)
class Winner:
    """Who does best on one metric: ``label`` with ``value``, against the ``runner_up``'s ``second`` value."""

    metric: Metric
    label: str
    value: float
    runner_up: str
    second: float
    sentence: str


@dataclass(frozen=True)
class ComparisonTable:
    """The metrics of every controller of a comparison.

    Parameters
    ----------
    metrics : tuple of Metric
        The metrics that apply to at least one controller, in table order.
    rows : tuple of ControllerRow
        One per controller, in spec order.
    error_unit, command_unit : str
        Units of the tracking error (rad or m) and of the command (as the report writes them).
    """

    metrics: tuple[Metric, ...]
    rows: tuple[ControllerRow, ...]
    error_unit: str
    command_unit: str

    def unit_of(self, metric: Metric) -> str:
        """The metric's unit as the report writes it."""
        return {"error": self.error_unit, "command": self.command_unit}.get(metric.unit, metric.unit)

    def row(self, label: str) -> ControllerRow:
        """The row of controller ``label`` (KeyError when absent)."""
        for r in self.rows:
            if r.label == label:
                return r
        raise KeyError(label)

    def value(self, label: str, key: str) -> float | None:
        """Metric ``key`` of controller ``label``."""
        return self.row(label).values.get(key)

    def cell(self, metric: Metric, value: float | None) -> str:
        """A value as the table writes it, with its unit."""
        if value is None:
            return "—"
        if math.isinf(value):
            return "never" if metric.key == "reconvergence" else "diverged"
        return f"{fmt_number(value, 4)} {self.unit_of(metric)}"

    def winners(self) -> tuple[Winner, ...]:
        """For each metric defined for two controllers or more: who has the lowest value, and by how much."""
        out = []
        for m in self.metrics:
            have = [(r.values[m.key], r.label) for r in self.rows if r.values.get(m.key) is not None]
            if len(have) < 2:
                continue
            have.sort(key=lambda p: p[0])
            (best, who), (second, other) = have[0], have[1]
            if best == second:
                sentence = f"On the {m.label}, {who} and {other} tie at {self.cell(m, best)}."
            elif math.isinf(second):
                sentence = (f"On the {m.label}, {who} wins with {self.cell(m, best)}; {other}: "
                            f"{self.cell(m, second)}.")
            else:
                ratio = second / best if best > 0 else math.inf
                by = f"{fmt_number(ratio, 3)} times lower" if ratio >= 1.5 and math.isfinite(ratio) else (
                    f"{fmt_number(100 * (second - best) / second, 3)} % lower")
                sentence = (f"On the {m.label}, {who} wins with {self.cell(m, best)} against "
                            f"{self.cell(m, second)} for {other} ({by}).")
            out.append(Winner(m, who, best, other, second, sentence))
        return tuple(out)

    def to_json(self) -> list[dict[str, Any]]:
        """One object per controller: label, kind, verified, metrics (non-finite values as None), checks."""
        return [{
            "label": r.label, "kind": r.kind, "verified": r.verified,
            "metrics": {m.key: (None if r.values.get(m.key) is None or not math.isfinite(r.values[m.key])
                                else r.values[m.key]) for m in self.metrics},
            "diverged_or_never": [m.key for m in self.metrics
                                  if r.values.get(m.key) is not None and math.isinf(r.values[m.key])],
            "checks": {name: status for name, _, status in r.checks},
        } for r in self.rows]


def _units(results: Sequence[Any]) -> tuple[str, str]:
    errors, commands = [], []
    for res in results:
        sim = res.simulation
        if sim is not None:
            errors.extend(sim.coordinate_units)
        plant = res.plant if res.plant is not None else res.design.plant
        commands.extend(s.unit for s in getattr(plant, "inputs", ()))
    def one(units: list[str], default: str) -> str:
        kept = list(dict.fromkeys(unit(u) for u in units))
        return kept[0] if len(kept) == 1 else (" or ".join(kept) if kept else default)
    return one(errors, "rad"), one(commands, "")


def _worded(metric: Metric, results: Sequence[Any]) -> Metric:
    """``metric`` with its words for the comparison's scenario: without a plant change "before the change" is the
    whole run, and without a periodic reference the last window is the last quarter of the run
    (:func:`~designkit.comparison.metrics.window_length`)."""
    import dataclasses

    from designkit.comparison.metrics import window_length

    spec = next((r.loaded.spec for r in results if r.simulation is not None), None)
    if spec is None:
        return metric
    label, meaning = metric.label, metric.meaning
    if spec.simulation.plant_change is None and metric.key in ("rms_error_before", "max_error_before"):
        label = label.replace("before the change", "over the run")
        for words in (" over the run before the plant change (the whole run without one)",
                      " before the plant change (the whole run without one)"):
            meaning = meaning.replace(words, " over the whole run")
    if metric.key == "rms_error_final" and getattr(spec.simulation.trajectory, "period", None) is None:
        t = next(r.simulation.time for r in results if r.simulation is not None)
        window = fmt_number(window_length(spec, t), 3)
        label = f"RMS tracking error over the last {window} s"
        meaning = f"root mean square of |xD − x| over the last quarter of the run ({window} s)"
    return dataclasses.replace(metric, label=label, meaning=meaning)


def baselines(results: Sequence[Any]) -> tuple[Any, ...]:
    """Each run's re-run on the unchanged plant (:func:`~designkit.comparison.metrics.baseline_simulation`; None
    without a plant change, without a simulation, or for a design run in trials)."""
    out = []
    for res in results:
        plant = res.plant if res.plant is not None else res.design.plant
        ran_once = res.simulation is not None and res.trials is None
        out.append(baseline_simulation(res.loaded.spec, plant) if ran_once else None)
    return tuple(out)


def comparison_table(labels: Sequence[str], results: Sequence[Any],
                     unchanged: Sequence[Any] | None = None) -> ComparisonTable:
    """The table of a comparison's runs (pure: reads the runs, returns a new value).

    Parameters
    ----------
    labels : sequence of str
        The controllers' labels, in spec order.
    results : sequence of PipelineResult
        Their runs, each of its single-controller spec.
    unchanged : sequence of SimulationResult or None, optional
        Their runs on the unchanged plant (default: :func:`baselines`).
    """
    from designkit.families import family

    unchanged = baselines(results) if unchanged is None else tuple(unchanged)
    rows = []
    for label, res, base in zip(labels, results, unchanged, strict=True):
        values = compute_metrics(res.loaded.spec, res.simulation, base)
        checks = tuple((c.name, getattr(c, "label", "") or c.name.replace("_", " ").capitalize(), c.status)
                       for c in res.checks)
        rows.append(ControllerRow(label, res.design.kind, family(res.design.kind).display.label,
                                  bool(res.verified), values, checks))
    used = tuple(_worded(m, results) for m in METRICS if any(r.values.get(m.key) is not None for r in rows))
    error_unit, command_unit = _units(results)
    return ComparisonTable(used, tuple(rows), error_unit, command_unit)
