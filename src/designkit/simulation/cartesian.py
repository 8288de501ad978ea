"""End-effector paths (``simulation.trajectory`` kinds ``line`` and ``circle``) as task-space references.

Both are rest to rest with the quintic time law ``sigma(s) = 10 s^3 - 15 s^4 + 6 s^5``,
``s = clip(t/T, 0, 1)``, and start where the end effector is at ``simulation.initial_position``
(``p0``); the orientation is held (its tracked coordinates, ``-e_o``, have a desired value of zero,
see :mod:`designkit.models.task`).

* ``line``: ``p(t) = p0 + (p1 - p0) sigma``, ``p1 = to`` or ``p0 + displacement``;
* ``circle`` about the axis through ``c`` along the unit ``k``: with ``rho0 = (p0 - c) - ((p0 - c).k) k``
  (radius ``|rho0|``) and the angle ``phi = 2 pi turns sigma``, ``rho = Rot(k, phi) rho0`` and
  ``p = c + ((p0 - c).k) k + rho``, ``p' = phi' k x rho``, ``p'' = phi'' k x rho - phi'^2 rho``.

The reference's rows are the task space's coordinates (:class:`~designkit.models.task.TaskSpace`);
a path that moves along a coordinate the arm cannot control (``z`` of a planar arm) is refused.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.models.task import TaskSpace
from designkit.simulation.reference import Reference

__all__ = ["cartesian_reference"]

_KEY = "simulation.trajectory"


def _quintic(t: np.ndarray, T: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = np.clip(np.atleast_1d(np.asarray(t, dtype=float)) / T, 0.0, 1.0)
    return (s**3 * (10.0 - 15.0 * s + 6.0 * s**2), s**2 * (30.0 - 60.0 * s + 30.0 * s**2) / T,
            s * (60.0 - 180.0 * s + 120.0 * s**2) / T**2)


def _line(traj: Any, p0: np.ndarray) -> tuple[Any, dict[str, Any], float]:
    p1 = np.asarray(traj.to, dtype=float) if traj.to is not None else p0 + np.asarray(traj.displacement, dtype=float)
    delta, T = p1 - p0, float(traj.duration)

    def position(t: np.ndarray) -> np.ndarray:
        s, ds, dds = _quintic(t, T)
        return np.stack([p0 + np.outer(s, delta), np.outer(ds, delta), np.outer(dds, delta)], axis=2)

    length = float(np.linalg.norm(delta))
    return position, {"kind": "line", "from": p0.tolist(), "to": p1.tolist(), "length_m": length,
                      "duration": T}, 2.0 * math.pi / T


def _circle(traj: Any, p0: np.ndarray) -> tuple[Any, dict[str, Any], float]:
    k = np.asarray(traj.normal, dtype=float)
    k = k / np.linalg.norm(k)
    c = np.asarray(traj.center, dtype=float)
    along = float((p0 - c) @ k)
    rho0 = (p0 - c) - along * k
    radius = float(np.linalg.norm(rho0))
    if radius < 1e-6:
        raise SpecError(f"{_KEY}.center", "the end effector starts on the circle's axis (radius 0)")
    T, angle = float(traj.duration), 2.0 * math.pi * float(traj.turns)
    kxrho0 = np.cross(k, rho0)

    def position(t: np.ndarray) -> np.ndarray:
        s, ds, dds = _quintic(t, T)
        phi, dphi, ddphi = angle * s, angle * ds, angle * dds
        rho = np.outer(np.cos(phi), rho0) + np.outer(np.sin(phi), kxrho0)  # Rodrigues, rho0 normal to k
        k_x_rho = np.cross(k[None, :], rho)
        p = c + along * k + rho
        return np.stack([p, dphi[:, None] * k_x_rho, ddphi[:, None] * k_x_rho - (dphi**2)[:, None] * rho], axis=2)

    return position, {"kind": "circle", "center": c.tolist(), "normal": k.tolist(), "radius_m": radius,
                      "turns": float(traj.turns), "duration": T}, max(2.0 * math.pi / T, 1.875 * abs(angle) / T)


def cartesian_reference(traj: Any, p0: Any, space: TaskSpace, q0: Any) -> Reference:
    """The task-space reference of a ``line`` or ``circle`` section, from the end-effector position ``p0`` (m).

    Parameters
    ----------
    traj : LineTrajectory or CircleTrajectory
        The spec's ``simulation.trajectory``.
    p0 : array_like, shape (3,)
        End-effector position at the initial configuration (m, base frame).
    space : TaskSpace
        The controlled coordinates (rows of the reference).
    q0 : array_like, shape (n,)
        Initial configuration (the reference's ``start``: where the arm starts at rest).

    Raises
    ------
    SpecError
        ``simulation.trajectory...``: a path along an uncontrolled coordinate, a circle whose axis
        passes through the start.
    """
    p0 = np.asarray(p0, dtype=float)
    position, settings, rate = (_line if traj.kind == "line" else _circle)(traj, p0)
    pos_rows, n_rot = list(space.position_rows), len(space.orientation_rows)
    free = [i for i in range(3) if i not in pos_rows]
    if free:
        probe = position(np.linspace(0.0, float(traj.duration), 201))[:, free, 0]
        drift = np.max(np.abs(probe - p0[free]))
        if drift > 1e-9:
            axis = "xyz"[free[int(np.argmax(np.max(np.abs(probe - p0[free]), axis=0)))]]
            raise SpecError(_KEY, f"the path moves along {axis} by up to {drift:.3g} m, which this arm's end "
                                  f"effector cannot (its controlled coordinates: {', '.join(space.names)})")

    def evaluate(t: np.ndarray) -> np.ndarray:
        full = position(np.atleast_1d(np.asarray(t, dtype=float)))
        rows = full[:, pos_rows, :]
        return np.concatenate([rows, np.zeros((rows.shape[0], n_rot, 3))], axis=1) if n_rot else rows

    settings = {**settings, "coordinates": list(space.names), "orientation": "held" if n_rot else "free"}
    before = tuple(evaluate(np.zeros(1))[0, :, 0])
    return Reference(evaluate, space.m, float(traj.duration), rate, settings, tuple(np.asarray(q0, dtype=float)),
                     before)
