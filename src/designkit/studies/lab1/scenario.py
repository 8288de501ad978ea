"""Experiment 1's variants of the scenario and of the plant, sized from the spec's own run.

The notes ask what the other parameters of a PID loop do -- the sampling period, the quantization levels, the
measurement noise, the transducer gains, the maximum control level, the delay in the control -- and what the
manipulator's parameters do (masses, lengths, viscosity).  Each variant here is one change of the spec (or of the
true plant, the controller designed as before and not told of it), sized from the run itself so that it means
the same on a 2 kg link and on a 6-joint arm:

* a sampling period and a computation delay of 1/20 and 1/5 of the fastest closed-loop time constant ``1/|p|max`` (set
  in the spec's ``implementation`` section when it has one, else in ``simulation``);
* white measurement noise of 1e-4 and 1e-3 of the commanded move on every measured state;
* the command quantized (a D/A converter) in steps of 1 % and 5 % of the run's peak command;
* the command limited to 50 % and 25 % of the run's peak command (the actuator's maximum level);
* a constant load of 20 % of the peak command from the middle of the run (what integral action is for);
* the plant: viscosity and inertia of a link halved and doubled; on an arm, every link mass halved and doubled,
  every link length scaled by 0.8 and 1.25, every joint viscosity halved and doubled.

A transducer gain other than 1 is not among them: designkit has no transducer element, and the report says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, quantity

__all__ = ["PlantChange", "ScenarioChange", "plant_changes", "scenario_changes"]


@dataclass(frozen=True)
class ScenarioChange:
    """One change of the scenario: which question it answers, its words, and the spec key paths it sets."""

    group: str
    label: str
    changes: tuple[tuple[str, Any], ...]
    size: float


@dataclass(frozen=True)
class PlantChange:
    """One change of the true plant: its words and the parameters it sets (name -> SI value)."""

    group: str
    label: str
    values: dict[str, float]
    factor: float


def _fastest_rate(design: Any) -> float:
    poles = []
    if design.closed_loop is not None:
        poles = list(design.closed_loop.poles)
    poles += [p for loop in design.loops for p in loop.poles] + list(design.poles)
    rates = [abs(p) for p in poles if np.isfinite(abs(p)) and abs(p) > 0]
    return max(rates) if rates else 1.0


def _move(result: Any) -> float:
    sim = result.simulation
    xd = np.asarray(sim.desired, dtype=float).reshape(len(sim.time), -1)
    x0 = np.asarray(sim.tracked_positions, dtype=float).reshape(len(sim.time), -1)[0]
    moves = np.max(np.abs(xd - x0), axis=0)
    return float(np.max(moves)) if np.max(moves) > 0 else 1.0


def _peak_command(result: Any) -> np.ndarray:
    u = np.asarray(result.simulation.u_command, dtype=float).reshape(len(result.simulation.time), -1)
    return np.max(np.abs(u), axis=0)


def _per_input(values: np.ndarray) -> Any:
    return float(values[0]) if values.size == 1 else [float(v) for v in values]


def scenario_changes(result: Any) -> tuple[ScenarioChange, ...]:
    """The scenario variants of the module docstring, for ``result``'s run."""
    rate = _fastest_rate(result.design)
    tc = 1.0 / rate
    move = _move(result)
    peak = _peak_command(result)
    peak = np.where(peak > 0, peak, 1.0)
    unit = next(iter({s.unit for s in result.plant.inputs}), "") if result.plant is not None else ""
    duration = float(result.simulation.time[-1])
    section = "implementation" if getattr(result.loaded.spec, "implementation", None) is not None else "simulation"
    out = []
    for k in (0.05, 0.2):
        out.append(ScenarioChange("sampling", f"sampled every {quantity(k * tc, 's', 3)} ({fmt_number(k, 2)} of the "
                                  f"fastest time constant, {quantity(tc, 's', 3)})",
                                  ((f"{section}.sampling_period", float(k * tc)),), k))
    for k in (0.05, 0.2):
        out.append(ScenarioChange("delay", f"a computation delay of {quantity(k * tc, 's', 3)}",
                                  ((f"{section}.delay", float(k * tc)),), k))
    for k in (1e-4, 1e-3):
        out.append(ScenarioChange("noise", f"measurement noise of σ = {fmt_number(k * move, 3)} on every measured "
                                  f"state ({fmt_number(k, 1)} of the move)",
                                  (("simulation.noise", {"std": float(k * move), "seed": 1}),), k))
    for k in (0.01, 0.05):
        out.append(ScenarioChange("quantization", f"the command quantized in steps of {fmt_number(k * 100, 2)} % of "
                                  f"its peak ({quantity(float(k * peak.max()), unit, 3)})",
                                  (("simulation.nonlinearity", {"kind": "quantizer",
                                                                "step": _per_input(k * peak)}),), k))
    for k in (0.5, 0.25):
        out.append(ScenarioChange("limit", f"the command limited to {fmt_number(k * 100, 2)} % of its peak "
                                  f"({quantity(float(k * peak.max()), unit, 3)})",
                                  (("simulation.nonlinearity", {"kind": "saturation",
                                                                "limit": _per_input(k * peak)}),), k))
    load = quantity(float(0.2 * peak.max()), unit, 3)
    out.append(ScenarioChange("load", f"a constant load of 20 % of the peak command ({load}) from t = "
                              f"{fmt_number(duration / 2, 3)} s",
                              (("simulation.perturbation", {"value": _per_input(0.2 * peak),
                                                            "time": duration / 2}),), 0.2))
    return tuple(out)


def plant_changes(result: Any) -> tuple[PlantChange, ...]:
    """The plant variants of the module docstring, for ``result``'s true plant."""
    plant = result.plant if result.plant is not None else result.design.plant
    values = {q.name: q.value for q in plant.parameters}
    units = {q.name: q.unit for q in plant.parameters}
    out = []
    if plant.kind == "link" and {"Km", "tau"} <= set(values):
        Km, tau = values["Km"], values["tau"]
        for f in (0.5, 2.0):  # viscosity f: Km = 1/f and tau = J/f both scale as 1/f
            out.append(PlantChange("viscosity", f"viscous friction ×{fmt_number(f, 2)}",
                                   {"Km": Km / f, "tau": tau / f}, f))
        for f in (0.5, 2.0):  # inertia J: tau = J/f
            out.append(PlantChange("inertia", f"inertia ×{fmt_number(f, 2)}", {"tau": tau * f}, f))
        return tuple(out)
    groups = (("masses", "every link mass", lambda n: units[n] == "kg", (0.5, 2.0)),
              ("lengths", "every link length", lambda n: units[n] == "m", (0.8, 1.25)),
              ("viscosity", "every joint's viscous friction", lambda n: units[n] == "N*m*s/rad", (0.5, 2.0)))
    for group, words, pick, factors in groups:
        names = [n for n in values if pick(n) and values[n] != 0]
        if not names:
            continue
        for f in factors:
            out.append(PlantChange(group, f"{words} ×{fmt_number(f, 3)} ({', '.join(names)})",
                                   {n: values[n] * f for n in names}, f))
    return tuple(out)
