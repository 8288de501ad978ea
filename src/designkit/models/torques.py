"""Torques of a robot's dynamics along a path: the coupled terms the joint loops leave to feedback, and the
model-error torque a controller that cancels its model's dynamics leaves uncancelled.

Both the arm study (:mod:`designkit.studies.arm`) and the diagnosis of a model mismatch
(:mod:`designkit.families.computed_torque.model_error`) read them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["coupling_torques", "model_error_torque"]


def coupling_torques(plant: Any, q: Any, qd: Any, qdd: Any) -> dict[str, np.ndarray]:
    """The torques of the coupled dynamics at a batch of states, on ``plant`` (N*m or N per joint).

    Parameters
    ----------
    plant : RobotPlant
    q, qd, qdd : array_like, shape (N, n)
        Joint positions (rad or m), velocities and accelerations.

    Returns
    -------
    dict of ndarray, shape (N, n)
        ``own`` ``D_ii qdd_i``; ``off_diagonal`` ``sum_{j != i} D_ij qdd_j``; ``coriolis``
        ``ID(q, qd, 0) - g(q) - F(qd)`` (Coriolis and centrifugal, ``C(q, qd) qd``); ``coupling``
        ``off_diagonal + coriolis``.
    """
    robot, p = plant.robot, plant.model_parameters()
    q, qd, qdd = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (q, qd, qdd))
    M = np.asarray(robot.mass_matrix(q, p=p), dtype=float).reshape(q.shape[0], q.shape[1], q.shape[1])
    own = np.diagonal(M, axis1=1, axis2=2) * qdd
    off = np.einsum("kij,kj->ki", M, qdd) - own
    rest = np.asarray(robot.inverse_dynamics(q, qd, np.zeros_like(qdd), p=p), dtype=float).reshape(q.shape)
    gravity = np.asarray(robot.gravity_torque(q, p=p), dtype=float).reshape(q.shape)
    friction = np.asarray(robot.friction_torque(qd, p=p), dtype=float).reshape(q.shape)
    coriolis = rest - gravity - friction
    return {"own": own, "off_diagonal": off, "coriolis": coriolis, "coupling": off + coriolis}


def model_error_torque(plant: Any, model: Any, q: Any, qd: Any, qdd: Any) -> np.ndarray:
    """``ID_plant(q, qd, qdd) - ID_model(q, qd, qdd)``, shape (N, n) (N*m or N): the torque a controller
    that cancels ``model``'s dynamics leaves uncancelled on ``plant`` (zero for an exact model)."""
    q, qd, qdd = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (q, qd, qdd))
    true = plant.robot.inverse_dynamics(q, qd, qdd, p=plant.model_parameters())
    believed = model.robot.inverse_dynamics(q, qd, qdd, p=model.model_parameters())
    return (np.asarray(true, dtype=float) - np.asarray(believed, dtype=float)).reshape(q.shape)
