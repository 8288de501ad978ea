"""What a task-space design asks the simulation to track: a :class:`TaskMotion`.

A family that tracks something other than its joints (resolved acceleration: the end effector)
computes its motion once, at synthesis, and puts it in ``design.motion``: the engine, the checks and
the report all read the same reference and joint path from there, and the checks and diagnoses of
the task Jacobian (``singularity``, ``error_poles``) read how the design resolves task accelerations
to the joints (``damping``) and the conditioning it accepts (``max_condition``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from designkit.models.task import JointPath, TaskFunctions, TaskSpace
from designkit.simulation.reference import Reference

__all__ = ["TaskMotion", "tracked_outputs"]


@dataclass(frozen=True)
class TaskMotion:
    """The task-space reference, the tracked coordinates and the joint motion that tracks them exactly.

    Attributes
    ----------
    reference : Reference
        Rows are the task coordinates (``space.names``; m, rad); ``start`` is the initial joint
        configuration.
    space : TaskSpace
        The controlled coordinates.
    functions : TaskFunctions
        ``tracked(q)`` and friends on the controller's model.
    path : JointPath
        Inverse kinematics along the reference, with the conditioning of ``J`` there.
    damping : float or None
        How the design resolves a task acceleration ``b`` to the joints: ``lambda`` of the damped least squares
        ``qdd* = (J^T J + lambda^2 I)^-1 J^T b`` (units of ``J``'s singular values, m/rad for position rows), or
        None for the exact inverse ``qdd* = J^-1 b``.
    max_condition : float
        The condition number of ``J`` (1) above which a configuration of the path counts as near-singular.
    """

    reference: Reference
    space: TaskSpace
    functions: TaskFunctions
    path: JointPath
    damping: float | None
    max_condition: float


def tracked_outputs(motion: TaskMotion, joint_positions: np.ndarray) -> np.ndarray:
    """The tracked coordinates ``(N, m)`` of joint positions ``(N, n)``, evaluated in one mapped call."""
    Q = np.asarray(joint_positions, dtype=float)
    if not np.all(np.isfinite(Q)):
        out = np.full((Q.shape[0], motion.space.m), np.nan)
        ok = np.all(np.isfinite(Q), axis=1)
        if ok.any():
            out[ok] = tracked_outputs(motion, Q[ok])
        return out
    return np.asarray(motion.functions.tracked.map(Q.shape[0])(Q.T)).T.reshape(Q.shape[0], motion.space.m)
