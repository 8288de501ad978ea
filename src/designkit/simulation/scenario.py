"""The scenario's per-step inputs beside the reference: measurement noise, the perturbation, the true plant's
parameters (and their change), and the check that the reference stays within the robot's limits."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.simulation.reference import Reference
from designkit.spec.fields import per_joint

__all__ = ["check_reference", "joint_values", "noise_rows_of", "parameter_rows", "perturbation_rows", "plant_change"]

def joint_values(value: Any, n: int, path: str) -> np.ndarray:
    try:
        return np.array(per_joint(value, n, path))
    except ValueError as exc:
        key, msg = str(exc).split(": ", 1)
        raise SpecError(key, msg.replace("per joint", "per entry")) from None


def noise_rows_of(spec: Any, n: int, nx: int, names: tuple[str, ...]) -> tuple[np.ndarray, dict[str, Any]]:
    noise = spec.simulation.noise
    if noise is None:
        return np.zeros((nx, n)), {"std": 0.0, "seed": None}
    std = joint_values(noise.std, nx, "simulation.noise.std")
    if not np.any(std > 0):
        return np.zeros((nx, n)), {"std": 0.0, "seed": None}
    rng = np.random.default_rng(noise.seed)
    samples = rng.normal(0.0, 1.0, size=(n, nx)).T * std[:, None]
    return samples, {"std": float(std[0]) if np.all(std == std[0]) else std.tolist(), "seed": int(noise.seed),
                     "on": list(names), "samples": "one per integration step, held over the step",
                     "generator": "numpy PCG64"}


def perturbation_rows(spec: Any, t: np.ndarray, dt: float, nd: int) -> tuple[np.ndarray, dict[str, Any] | None]:
    pert = spec.simulation.perturbation
    if pert is None:
        return np.zeros((nd, t.size)), None
    value = joint_values(pert.value, nd, "simulation.perturbation.value")
    on = t >= pert.time - 1e-9 * dt
    applied = float(t[on][0]) if on.any() else None
    return np.where(on[None, :], value[:, None], 0.0), {
        "value": float(value[0]) if nd == 1 else value.tolist(), "time": float(pert.time), "time_applied": applied}


def plant_change(section: Any, plant: Any, t: np.ndarray, dt: float) -> tuple[Any, dict[str, Any] | None]:
    """``(first step index, values)`` of ``simulation.plant_change`` (validated on ``plant``), and its settings."""
    if section is None:
        return None, None
    from designkit.errors import ModelError

    try:
        plant.with_params(**section.values)
    except ModelError as exc:
        raise SpecError(f"simulation.plant_change.values.{exc.field}", exc.message) from None
    on = np.flatnonzero(t >= section.time - 1e-9 * dt)
    k = int(on[0]) if on.size else t.size
    return (k, dict(section.values)), {"time": float(section.time), "values": dict(section.values),
                                       "time_applied": float(t[k]) if k < t.size else None}


def parameter_rows(plant: Any, n: int, change: Any) -> np.ndarray:
    """The true plant's parameter vector per step ``(np, n)``, changed from step ``change[0]`` on."""
    rows = np.repeat(np.asarray(plant.parameter_vector, dtype=float).reshape(-1, 1), n, axis=1)
    if change is not None and change[0] < n:
        rows[:, change[0]:] = np.asarray(plant.with_params(**change[1]).parameter_vector, dtype=float)[:, None]
    return rows


def check_reference(ref: Reference, t: np.ndarray, plant: Any, spec: Any, kind: str) -> None:
    """The commanded motion must stay within the robot's joint limits (``qlim``) and, when the spec gives
    them, ``plant.limits.velocity`` and ``acceleration``; else :class:`SpecError` naming the reference."""
    key = "simulation.trajectory" if kind == "trajectory" else "simulation.step"
    x = ref.evaluate(t)
    for j, lim in enumerate(getattr(plant, "joint_limits", ())):
        if lim is None:
            continue
        bad = np.flatnonzero((x[:, j, 0] < lim[0] - 1e-12) | (x[:, j, 0] > lim[1] + 1e-12))
        start = ref.start[j] if j < len(ref.start) else 0.0
        if not lim[0] - 1e-12 <= start <= lim[1] + 1e-12:
            raise SpecError("simulation.initial_position", f"joint {j + 1} starts at {start:.4g} rad, outside its "
                                                           f"limits [{lim[0]:.4g}, {lim[1]:.4g}] rad")
        if bad.size:
            k = int(bad[0])
            raise SpecError(key, f"joint {j + 1} leaves its limits [{lim[0]:.4g}, {lim[1]:.4g}] rad at t = "
                                 f"{t[k]:.4g} s (qD = {x[k, j, 0]:.4g} rad)")
    limits = getattr(spec.plant, "limits", None)
    for name, column, unit in (("velocity", 1, "rad/s"), ("acceleration", 2, "rad/s^2")):
        value = getattr(limits, name, None) if limits is not None else None
        if value is None or kind != "trajectory":
            continue
        bound = np.broadcast_to(np.asarray(value, dtype=float), (ref.n,))
        peak = np.max(np.abs(x[:, :, column]), axis=0)
        j = int(np.argmax(peak / bound))
        if peak[j] > bound[j] * (1 + 1e-9):
            k = int(np.argmax(np.abs(x[:, j, column])))
            raise SpecError(key, f"joint {j + 1} needs {peak[j]:.4g} {unit} at t = {t[k]:.4g} s, above "
                                 f"plant.limits.{name} {bound[j]:g} {unit}")
