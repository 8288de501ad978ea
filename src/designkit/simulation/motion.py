"""What a task-space family asks the simulation to track: a :class:`TaskMotion`.

A family that tracks something other than its joints (resolved acceleration: the end effector)
declares ``Family.motion``; :func:`motion_of` calls it once per ``(spec, design)`` and keeps the
answer, since the engine, the checks and the report all need the same reference and joint path.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.models.task import JointPath, TaskFunctions, TaskSpace
from designkit.simulation.reference import Reference

__all__ = ["TaskMotion", "motion_of", "tracked_outputs"]

_MEMO: OrderedDict[tuple[Any, ...], tuple[Any, Any, TaskMotion | None]] = OrderedDict()
_MEMO_SIZE = 8


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
    """

    reference: Reference
    space: TaskSpace
    functions: TaskFunctions
    path: JointPath


def motion_of(spec: Any, design: Any) -> TaskMotion | None:
    """``family(design.kind).motion(spec, design)`` (memoised), or None for a joint-space family.

    The motion depends on the spec, the controller's model and the task space, not on the gains:
    designs that differ only in their gains (a gain study) share one inverse-kinematics solution.
    """
    import json

    from designkit.families import family

    hook = family(design.kind).motion
    if hook is None:
        return None
    task = json.dumps(design.extra.get("task"), sort_keys=True, default=str)
    key = (id(spec), id(design.plant), design.kind, task)
    hit = _MEMO.get(key)
    if hit is not None and hit[0] is spec and hit[1] is design.plant:
        return hit[2]
    value = hook(spec, design)
    _MEMO[key] = (spec, design.plant, value)
    while len(_MEMO) > _MEMO_SIZE:
        _MEMO.popitem(last=False)
    return value


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
