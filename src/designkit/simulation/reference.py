"""Reference signals ``(xD, xD', xD'')`` as analytic NumPy functions of time.

* ``step`` (servo controllers): ``xD = step`` for ``t >= 0``; ``xD' = xD'' = 0``.
* ``quintic`` (tracking): rest-to-rest ``0 -> amplitude`` over ``duration`` ``T``; with
  ``s = clip(t/T, 0, 1)``: ``xD = A (10 s^3 - 15 s^4 + 6 s^5)``,
  ``xD' = (A/T)(30 s^2 - 60 s^3 + 30 s^4)``, ``xD'' = (A/T^2)(60 s - 180 s^2 + 120 s^3)``;
  ``xD = A``, ``xD' = xD'' = 0`` after ``T``.
* ``sine`` (tracking): ``xD = A sin(w t)``, ``xD' = A w cos(w t)``, ``xD'' = -A w^2 sin(w t)``,
  ``w = 2 pi frequency``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.spec.schema import Simulation, Trajectory


@dataclass(frozen=True)
class Reference:
    """A reference signal.

    Parameters
    ----------
    evaluate : callable
        ``t (s, array) -> array (len(t), 3)`` of ``(xD rad, xD' rad/s, xD'' rad/s^2)``.
    horizon : float
        Time the reference itself needs (s): the motion's duration, three sine periods, 0 for a step.
    rate : float
        Fastest rate of the reference (rad/s), for the choice of the integration step (0 for a step).
    settings : dict
        Parameters used, JSON-serialisable.
    """

    evaluate: Callable[[np.ndarray], np.ndarray]
    horizon: float
    rate: float
    settings: dict[str, Any]


def step_reference(amplitude: float) -> Reference:
    """``xD = amplitude`` (rad) from ``t = 0``."""

    def evaluate(t: np.ndarray) -> np.ndarray:
        out = np.zeros((np.size(t), 3))
        out[:, 0] = amplitude
        return out

    return Reference(evaluate, 0.0, 0.0, {"kind": "step", "amplitude": float(amplitude)})


def quintic(amplitude: float, duration: float) -> Reference:
    """Quintic rest-to-rest motion ``0 -> amplitude`` (rad) over ``duration`` (s)."""
    A, T = float(amplitude), float(duration)

    def evaluate(t: np.ndarray) -> np.ndarray:
        s = np.clip(np.asarray(t, float) / T, 0.0, 1.0)
        return np.column_stack([
            A * s**3 * (10.0 - 15.0 * s + 6.0 * s**2),
            (A / T) * s**2 * (30.0 - 60.0 * s + 30.0 * s**2),
            (A / T**2) * s * (60.0 - 180.0 * s + 120.0 * s**2),
        ])

    return Reference(evaluate, T, 2.0 * math.pi / T, {"kind": "quintic", "amplitude": A, "duration": T})


def sine(amplitude: float, frequency: float) -> Reference:
    """``xD = amplitude sin(2 pi frequency t)`` (rad, Hz)."""
    A, w = float(amplitude), 2.0 * math.pi * float(frequency)

    def evaluate(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, float)
        return np.column_stack([A * np.sin(w * t), A * w * np.cos(w * t), -A * w**2 * np.sin(w * t)])

    return Reference(evaluate, 3.0 / float(frequency), w,
                     {"kind": "sine", "amplitude": A, "frequency": float(frequency)})


TRAJECTORIES: dict[str, Callable[[Trajectory], Reference]] = {
    "quintic": lambda tr: quintic(tr.amplitude, tr.duration),
    "sine": lambda tr: sine(tr.amplitude, tr.frequency),
}
"""``simulation.trajectory.kind`` -> reference builder."""


def _trajectory(sim: Simulation) -> Reference:
    traj = sim.trajectory if sim.trajectory is not None else Trajectory()
    try:
        build = TRAJECTORIES[traj.kind]
    except KeyError:
        raise SpecError("simulation.trajectory.kind", f"unknown {traj.kind!r}; known: {sorted(TRAJECTORIES)}") from None
    return build(traj)


REFERENCES: dict[str, Callable[[Simulation], Reference]] = {
    "step": lambda sim: step_reference(sim.step),
    "trajectory": _trajectory,
}
"""Controller family's reference kind (``family(kind).reference``) -> reference builder."""


def reference_for(kind: str, sim: Simulation) -> Reference:
    """The reference of kind ``"step"`` or ``"trajectory"`` described by ``sim``."""
    try:
        build = REFERENCES[kind]
    except KeyError:
        raise SpecError("controller.kind", f"unknown reference kind {kind!r}; known: {sorted(REFERENCES)}") from None
    return build(sim)
