"""The simulation-settings table: every setting the simulator recorded, labelled in words, with its unit."""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, is_real, unit
from designkit.report.certificates import fmt_compact, human_key
from designkit.report.design_section import SYMBOLS
from designkit.report.rows import ParameterRow

__all__ = ["simulation_rows"]

# simulation settings: label and unit of each key (values are formatted by fmt_compact, in words)
_SETTINGS: dict[str, tuple[str, str]] = {
    "integrator": ("Integrator", ""), "integrator_choice": ("Integrator choice", ""),
    "integrator_work": ("Integrator work", ""),
    "dt": ("Time step", "s"), "dt_source": ("Time step chosen by", ""), "duration": ("Duration", "s"),
    "duration_requested": ("Duration requested", "s"), "duration_source": ("Duration taken from", ""),
    "n_steps": ("Steps", ""), "fastest_rate": ("Fastest closed-loop rate |p|max", "1/s"),
    "slowest_rate": ("Slowest closed-loop rate", "1/s"), "steps_per_sample": ("Steps per controller sample", ""),
    "delay_steps": ("Delay in steps", ""), "evaluation": ("Evaluation", ""), "plant": ("Simulated plant", ""),
    "nominal_plant": ("Nominal plant (design model)", ""), "controller": ("Controller", ""),
    "reference": ("Reference", ""), "nonlinearity": ("Nonlinearity", ""), "delay": ("Delay", "s"),
    "sampling_period": ("Sampling period", "s"), "noise": ("Measurement noise", ""),
    "perturbation": ("Perturbation", ""), "initial_state": ("Initial state", ""),
    "plant_change": ("Plant change during the run", ""), "start": ("How the run starts", ""),
    "ignored": ("Spec settings ignored", ""), "kind": ("Kind", ""),
    "implementation": ("The verdict is on the controller", ""), "scope": ("What the verdict holds for", ""),
}


def _spec_path(text: str) -> str:
    """``simulation.duration`` -> ``simulation › duration`` (a spec path, not an internal key)."""
    return text.replace(".", " › ") if re.fullmatch(r"[A-Za-z_]+(\.[A-Za-z_]+)+", text) else text


def _setting_value(key: str, value: Any, unit_text: str, plant: Any) -> str:
    if key == "start" and isinstance(value, Mapping):  # the simulator's own sentence (at rest, what was solved)
        return str(value.get("words", ""))
    if key in ("plant", "nominal_plant") and isinstance(value, Mapping):
        parts = []
        for name, v in value.items():
            try:
                u = unit(plant.parameter(name).unit)
            except (KeyError, AttributeError, ValueError, TypeError):
                u = ""
            parts.append(f"{SYMBOLS.get(name, name)} = {fmt_compact(v, 4)}{' ' + u if u and is_real(v) else ''}")
        return ", ".join(parts) or "none"
    if key == "ignored" and isinstance(value, Sequence) and not isinstance(value, str):
        return ", ".join(_spec_path(str(v)) for v in value) or "none"
    if value is None:
        return "none"
    text = _spec_path(fmt_compact(value, 4)) if isinstance(value, str) else fmt_compact(value, 4)
    return text + (f" {unit_text}" if unit_text and is_real(value) else "")


def simulation_rows(simulation, plant: Any = None) -> tuple[ParameterRow, ...]:
    """Simulation settings with labels in words, values formatted (4 significant digits) and units."""
    if simulation is None:
        return ()
    rows = [ParameterRow("Kind", str(simulation.kind), "")]
    t = np.asarray(simulation.time, float)
    if t.size:
        rows.append(ParameterRow("Samples", f"{t.size} over {fmt_number(t[0])} s to {fmt_number(t[-1])} s", ""))
    settings = dict(simulation.settings)
    first = {k: settings.pop(k) for k in ("implementation", "scope") if k in settings}  # what the verdict is on
    for key, value in {**first, **settings}.items():
        name, unit_text = _SETTINGS.get(str(key), (human_key(str(key)).capitalize(), ""))
        rows.append(ParameterRow(name, unit(_setting_value(str(key), value, unit_text, plant)), ""))
    return tuple(rows)
