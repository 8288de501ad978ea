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
from designkit.comparison.verdicts import CheckLine, check_lines, member_sentence, member_verified
from designkit.display.numbers import fmt_number, unit

__all__ = ["METRICS", "TIE_TOLERANCE", "ComparisonTable", "ControllerRow", "Metric", "Winner", "baselines",
           "comparison_table", "tally", "tie"]

TIE_TOLERANCE = 0.01
"""Two controllers tie on a metric when their values differ by at most this fraction (1 %) of the larger
magnitude: no controller wins a metric by less.  Equal values (both zero included) tie; a finite value never ties
with a diverged or never-reached one."""


def tie(a: float, b: float) -> bool:
    """Whether two values of one metric tie: ``|a - b| <= TIE_TOLERANCE * max(|a|, |b|)`` (both finite), or equal.

    Parameters
    ----------
    a, b : float
        The two controllers' values, in the metric's unit (``inf``: diverged or never reached).

    Returns
    -------
    bool
        True when neither wins the metric.
    """
    if a == b:
        return True
    if not (math.isfinite(a) and math.isfinite(b)):
        return False
    return abs(a - b) <= TIE_TOLERANCE * max(abs(a), abs(b))


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


_SETTLED = ("over the settled instants: the last quarter of each level of the reference, from {settle} s after each "
            "jump to the next (the error once each jump has been followed, the jumps themselves left out)")
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
    Metric("rms_settled_before", "RMS settled error before the change", "error",
           "root mean square of |xD − x| before the plant change, " + _SETTLED),
    Metric("max_settled_before", "largest settled error before the change", "error",
           "largest |xD − x| before the plant change over the settled instants (the last quarter of each level)"),
    Metric("rms_settled_after", "RMS settled error after the change", "error",
           "root mean square of |xD − x| from the plant change on, " + _SETTLED),
    Metric("max_settled_after", "largest settled error after the change", "error",
           "largest |xD − x| from the plant change on over the settled instants (the last quarter of each level)"),
    Metric("rise_time_before", "mean 90 % rise time before the change", "s",
           "mean, over the reference's jumps before the plant change, of the time from the jump until the output "
           "first covers 90 % of it"),
    Metric("rise_time_after", "mean 90 % rise time after the change", "s",
           "mean, over the reference's jumps from the plant change on, of the time from the jump until the output "
           "first covers 90 % of it"),
    Metric("rms_model_error_before", "RMS error against the reference model before the change", "error",
           "root mean square of |ym − x| before the plant change, ym the output of the reference model the "
           "controller's law follows and records (only for such a law)"),
    Metric("rms_model_error_after", "RMS error against the reference model after the change", "error",
           "root mean square of |ym − x| from the plant change on (ym: the recorded reference model's output)"),
    Metric("rms_deviation", "RMS departure caused by the change", "error",
           "root mean square, from the plant change on, of |x − x0|: x0 is the same controller's output in a run "
           "on the unchanged plant"),
    Metric("max_deviation", "largest departure caused by the change", "error",
           "largest |x − x0| from the plant change on (x0: the run on the unchanged plant)"),
    Metric("reconvergence", "re-convergence time after the change", "s",
           "time after the plant change from which |x − x0| stays within 1 % of the reference's range"),
    Metric("rms_error_final", "RMS tracking error over the last period", "error",
           "root mean square of |xD − x| over the last reference period of the run"),
    Metric("rms_settled_final", "RMS settled error over the last period", "error",
           "root mean square of |xD − x| over the last reference period of the run, " + _SETTLED),
    Metric("max_error_load", "largest tracking error from the load step on", "error",
           "largest |xD − x| from the load step's onset ({load} s) to the end of the run"),
    Metric("peak_command", "peak command", "command", "largest |u| the controller commanded"),
    Metric("peak_command_after", "peak command after the change", "command",
           "largest |u| commanded from the plant change on"),
    Metric("rms_command", "RMS command", "command", "root mean square of the command u over the run"),
    Metric("overshoot", "overshoot", "%", "largest excursion beyond the step, in percent of the step"),
    Metric("settling_time", "settling time (2 %)", "s", "last time the position leaves the 2 % band of the step"),
)
"""Every metric, in table order (lower is better for each); :func:`designkit.comparison.metrics.compute_metrics`
leaves those that do not fit the scenario undefined (None), and the table shows only the others."""

_NEVER = ("reconvergence", "rise_time_before", "rise_time_after")
"""Metrics whose infinite value means the event did not happen within the run (written ``never``)."""


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
        Every required check of its own run passed (an undecided check is not a pass).
    values : Mapping
        Metric key -> value (None: does not apply; ``inf``: diverged, or never re-converged).
    checks : tuple of CheckLine
        Each check's name, label in words, status (``PASS``, ``FAIL``, ``UNDECIDED``) and whether it is required.
    warnings : tuple of str
        Its run's warnings (:attr:`~designkit.pipeline.PipelineResult.warnings`: weak margins, chattering...),
        one plain sentence each.
    """

    label: str
    kind: str
    controller: str
    verified: bool
    values: Mapping[str, float | None]
    checks: tuple[CheckLine, ...]
    warnings: tuple[str, ...] = ()

    @property
    def failed(self) -> tuple[CheckLine, ...]:
        """The checks that did not pass, required or informational."""
        return tuple(c for c in self.checks if c.status != "PASS")

    @property
    def sentence(self) -> str:
        """Its verdict in one or two sentences, from its checks' statuses (:func:`~designkit.comparison.verdicts.
        member_sentence`)."""
        return member_sentence(self.label, self.controller, self.checks)


@dataclass(frozen=True)
class Winner:
    """Who does best on one metric, or who ties on it.

    Parameters
    ----------
    metric : Metric
        The metric.
    label, value : str, float
        The controller with the lowest value, and that value (in the metric's unit).
    runner_up, second : str, float
        The controller with the second lowest value, and that value.
    sentence : str
        What the comparison says of it, in words.
    tie : bool
        True when ``second`` is within :data:`TIE_TOLERANCE` of ``value``: nobody wins the metric.
    tied : tuple of str
        With a tie, every controller whose value is within the tolerance of the lowest, lowest first.
    """

    metric: Metric
    label: str
    value: float
    runner_up: str
    second: float
    sentence: str
    tie: bool = False
    tied: tuple[str, ...] = ()


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
            return "never" if metric.key in _NEVER else "diverged"
        return f"{fmt_number(value, 4)} {self.unit_of(metric)}"

    def winners(self) -> tuple[Winner, ...]:
        """For each metric defined for two controllers or more: who has the lowest value and by how much, or who
        ties with it (values within :data:`TIE_TOLERANCE` of the lowest)."""
        out = []
        for m in self.metrics:
            have = [(r.values[m.key], r.label) for r in self.rows if r.values.get(m.key) is not None]
            if len(have) < 2:
                continue
            have.sort(key=lambda p: p[0])
            (best, who), (second, other) = have[0], have[1]
            group = [(v, label) for v, label in have if tie(best, v)]
            if len(group) >= 2:
                names = _and([label for _, label in group])
                if all(v == best for v, _ in group):
                    sentence = f"On the {m.label}, {names} tie at {self.cell(m, best)}."
                else:
                    worst = group[-1][0]
                    gap = 100 * (worst - best) / max(abs(best), abs(worst))
                    sentence = (f"On the {m.label}, {names} tie: {_and([self.cell(m, v) for v, _ in group])} differ "
                                f"by {fmt_number(gap, 2)} % at most, within the {fmt_number(100 * TIE_TOLERANCE, 2)} % "
                                "tie tolerance.")
                out.append(Winner(m, who, best, other, second, sentence, True, tuple(lb for _, lb in group)))
                continue
            if math.isinf(second):
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

    def winners_json(self) -> list[dict[str, Any]]:
        """``--json``'s ``winners``: one object per metric with a finite lowest and second value: ``metric``,
        ``label`` and ``value`` (the lowest), ``runner_up`` and ``runner_up_value``, ``tie`` (True: within
        :data:`TIE_TOLERANCE`, nobody wins) and ``tied`` (the tied labels, lowest first; empty without a tie)."""
        return [{"metric": w.metric.key, "label": w.label, "value": w.value, "runner_up": w.runner_up,
                 "runner_up_value": w.second, "tie": w.tie, "tied": list(w.tied)}
                for w in self.winners() if math.isfinite(w.value) and math.isfinite(w.second)]

    def to_json(self) -> list[dict[str, Any]]:
        """One object per controller: label, kind, verified, metrics (non-finite values as None), the metrics that
        diverged or never re-converged, checks (name -> status) and its run's warnings."""
        return [{
            "label": r.label, "kind": r.kind, "verified": r.verified,
            "metrics": {m.key: (None if r.values.get(m.key) is None or not math.isfinite(r.values[m.key])
                                else r.values[m.key]) for m in self.metrics},
            "diverged_or_never": [m.key for m in self.metrics
                                  if r.values.get(m.key) is not None and math.isinf(r.values[m.key])],
            "checks": {c.name: c.status for c in r.checks},
            "warnings": list(r.warnings),
        } for r in self.rows]


def _and(words: Sequence[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def tally(labels: Sequence[str], winners: Sequence[Winner]) -> str:
    """How many metrics each controller wins, and which are ties, in words.

    Parameters
    ----------
    labels : sequence of str
        The controllers' labels, in spec order.
    winners : sequence of Winner
        :meth:`ComparisonTable.winners`.

    Returns
    -------
    str
        ``Of the N metrics compared, a wins 3 and b wins none. 1 is a tie (values within 1 % of each other): …``
    """
    wins = {label: sum(1 for w in winners if not w.tie and w.label == label) for label in labels}
    ties = [w.metric.label for w in winners if w.tie]
    n = len(winners)
    text = f"Of the {n} metric{'s' * (n != 1)} compared, " + _and(
        [f"{label} wins {k or 'none'}" for label, k in wins.items()])
    if ties:
        text += (f". {len(ties)} {'is a tie' if len(ties) == 1 else 'are ties'} (values within "
                 f"{fmt_number(100 * TIE_TOLERANCE, 2)} % of each other): " + "; ".join(ties))
    return text + "."


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
    """``metric`` with its words for the comparison's scenario (:func:`~designkit.comparison.metrics.scenario`):
    without a plant change "before the change" is the whole run; without a periodic reference the last window is
    the last quarter of the run (:func:`~designkit.comparison.metrics.window_length`); the delay after each jump
    and the load step's onset are written in seconds; a single jump's rise time is the step's."""
    import dataclasses

    from designkit.comparison.metrics import scenario

    run = next((r for r in results if r.simulation is not None), None)
    if run is None:
        return metric
    spec = run.loaded.spec
    label, meaning = metric.label, metric.meaning
    sc = scenario(spec, run.simulation) if hasattr(run.simulation, "reference") else None
    if spec.simulation.plant_change is None:
        label = label.replace(" before the change", " over the run")
        for words, by in ((" over the run before the plant change (the whole run without one)", " over the whole run"),
                          (" before the plant change (the whole run without one)", " over the whole run"),
                          (" before the plant change", " over the whole run")):
            meaning = meaning.replace(words, by)
    if metric.key in ("rms_error_final", "rms_settled_final") and getattr(spec.simulation.trajectory, "period",
                                                                           None) is None:
        t = run.simulation.time
        window = fmt_number((float(t[-1]) - float(t[0])) / 4.0, 3)
        if metric.key == "rms_error_final":
            label = f"RMS tracking error over the last {window} s"
            meaning = f"root mean square of |xD − x| over the last quarter of the run ({window} s)"
        else:
            label = f"RMS settled error over the last {window} s"
            meaning = meaning.replace("the last reference period of the run",
                                      f"the last quarter of the run ({window} s)")
    if sc is not None:
        if sc.settle is not None:
            meaning = meaning.replace("{settle}", fmt_number(sc.settle, 3))
        if sc.load is not None:
            meaning = meaning.replace("{load}", fmt_number(sc.load, 4))
        if metric.key == "rise_time_before" and len(sc.jumps) == 1 and spec.simulation.plant_change is None:
            label = "90 % rise time of the step"
            meaning = "time from the step until the output first covers 90 % of it"
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
        checks = check_lines(res.checks)
        rows.append(ControllerRow(label, res.design.kind, family(res.design.kind).display.label,
                                  member_verified(checks), values, checks, tuple(res.warnings)))
    used = tuple(_worded(m, results) for m in METRICS if any(r.values.get(m.key) is not None for r in rows))
    error_unit, command_unit = _units(results)
    return ComparisonTable(used, tuple(rows), error_unit, command_unit)
