"""A PID's most advantageous and disadvantageous features, decided from the variants' outcomes (experiment 1).

Every sentence is chosen by the numbers of the runs: whether the loop kept every required check with the plant's
parameters halved and doubled (it needs no model), whether the constant load's static error was removed (integral
action), which sampling period, delay, quantization or actuator limit made a check fail (what it needs of the
implementation).  Nothing is written in advance.
"""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import quantity

__all__ = ["feature_sentences"]

_PLANT = ("viscosity", "inertia", "masses", "lengths")
_IMPLEMENTATION = ("sampling", "delay", "noise", "quantization", "limit")


def feature_sentences(ran: dict[str, list[tuple[str, Any]]], nominal: Any, metric: Any) -> tuple[str, ...]:
    """Advantages, then disadvantages, from the rows of each group of variants (label, row)."""
    good, bad = [], []
    plant = [(g, label, r) for g in _PLANT for label, r in ran.get(g, ())]
    if plant:
        kept = [label for _, label, r in plant if r.passed]
        lost = [label for _, label, r in plant if not r.passed]
        if kept:
            good.append(f"It needs no model of the manipulator: designed for the nominal plant, it still passes every "
                        f"required check with {len(kept)} of the {len(plant)} plant changes tried ("
                        + "; ".join(kept) + ").")
        if lost:
            bad.append(f"Its gains hold for one plant: with {'; '.join(lost)} a required check fails (a fixed-gain "
                       "loop does not adapt to what changed).")
    for label, r in ran.get("load", ()):
        final = r.metrics.get("error_final") if "error_final" in r.metrics else None
        if r.passed:
            good.append(f"Integral action rejects a constant load: with {label}, every required check still passes"
                        + (f" and the final error is {quantity(final, metric.unit if metric else '', 3)}"
                           if final is not None else "") + ".")
        else:
            bad.append(f"With {label}, the run {'fails' if r.outcome == 'failed' else r.outcome} ({r.detail}).")
    for group in _IMPLEMENTATION:
        rows = ran.get(group, ())
        failing = [label for label, r in rows if not r.passed]
        passing = [label for label, r in rows if r.passed]
        if failing:
            bad.append(f"It needs a faithful implementation: with {failing[0]}, a required check fails"
                       + (f" (it passes with {passing[0]})" if passing else "") + ".")
    if not bad:
        bad.append("None of the variants run here made a required check fail; the disadvantages a PID is known for "
                   "(fixed gains, a linear design about one operating point) did not show within these changes.")
    if nominal.outcome != "verified":
        bad.insert(0, f"The spec's own run does not pass ({nominal.detail}).")
    return (*(f"Advantage: {s}" for s in good), *(f"Disadvantage: {s}" for s in bad)) if good or bad else (
        "No variant was run.",)


