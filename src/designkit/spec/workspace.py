"""A box of configurations a controller section names (``controller.workspace``), and the box it stands for.

Two families certify or bound something over a box of the arm's configurations: the decentralized PID's joint
loops (its ``workspace`` check) and the PID/sliding-mode hierarchy's perturbation bound.  Both give the box as
the section :class:`Workspace` or the word ``joint_limits`` (the robot's joint limits, :func:`joint_limits_word`
reads it), and both resolve it against the robot with :func:`workspace_box` once the plant is built.
"""

from __future__ import annotations

from typing import Any

from designkit.errors import SpecError
from designkit.spec.fields import Section, joint_values
from designkit.spec.ranges import Ranged, RangedInt, RangedPerJoint

__all__ = ["Workspace", "joint_limits_word", "workspace_box", "workspace_schema"]


class Workspace(Section):
    """A box of configurations ``low <= q <= high`` (rad, or m for a prismatic joint) for the ``workspace`` check.

    ``low``, ``high``: one value for every joint or one per joint (each within 100); either omitted: the
    robot's joint limits (``qlim``).  ``tolerance`` (1e-9 to 0.1, default 1e-3): the relative gap between
    each proven bound of ``D_ii`` over the box and the configuration found nearest to it
    (:func:`designkit.models.bounds.model_bound`).  ``samples`` (2 to 101): grid points per outboard joint
    of the sampled estimate of the range shown beside it (:func:`designkit.models.link.link_range`).
    Checked against the robot at synthesis: one value per joint, ``low < high``, inside the joint limits.
    """

    low: RangedPerJoint(-100, 100, "rad or m") | None = None
    high: RangedPerJoint(-100, 100, "rad or m") | None = None
    samples: RangedInt(2, 101) = 7
    tolerance: Ranged(1e-9, 0.1, "") = 1e-3


def workspace_schema(schema: dict[str, Any]) -> None:
    """The JSON Schema of a ``workspace`` field also admits the string ``joint_limits`` (``json_schema_extra``)."""
    schema["anyOf"].insert(1, {"const": "joint_limits", "type": "string"})


def joint_limits_word(v: Any) -> Any:
    """A ``workspace`` field's value before validation: ``joint_limits`` stands for ``{}`` (the joint limits on both
    sides); any other string is refused (``ValueError``)."""
    if isinstance(v, str):
        if v.strip() != "joint_limits":
            raise ValueError(f"must be 'joint_limits' or a mapping {{low, high, samples, tolerance}}, got {v!r}")
        return {}
    return v


def workspace_box(spec: Any, plant: Any) -> dict[str, Any] | None:
    """The ``controller.workspace`` box checked against the robot (rad or m per joint), or None.

    Parameters
    ----------
    spec : Spec
        Its ``controller.workspace`` (a :class:`Workspace` or None) is read.
    plant : RobotPlant
        Its ``n_joints`` and ``joint_limits`` (rad or m, None for a joint without limits).

    Returns
    -------
    dict or None
        ``{"low": [...], "high": [...], "samples": int, "tolerance": float, "source": {"low": ..., "high": ...}}``,
        the source of each side being ``"spec"`` or ``"joint limits"``.

    Raises
    ------
    SpecError
        ``controller.workspace.low``: not one value per joint, or omitted on a robot without joint
        limits; ``controller.workspace.high[i]``: not above ``low[i]``; either side outside the
        joint limits.
    """
    ws = spec.controller.workspace
    if ws is None:
        return None
    n, limits = plant.n_joints, plant.joint_limits
    sides: dict[str, tuple[float, ...]] = {}
    source: dict[str, str] = {}
    for k, side in enumerate(("low", "high")):
        given = getattr(ws, side)
        if given is None:
            missing = next((i for i, lim in enumerate(limits) if lim is None), None)
            if missing is not None:
                raise SpecError(f"controller.workspace.{side}", f"needed: joint {missing + 1} has no joint limits "
                                "(qlim) in the robot data to default to")
            sides[side], source[side] = tuple(lim[k] for lim in limits), "joint limits"
        else:
            sides[side], source[side] = joint_values(given, n, f"controller.workspace.{side}"), "spec"

    def path(side: str, i: int) -> str:
        return f"controller.workspace.{side}" + (f"[{i}]" if isinstance(getattr(ws, side), list) else "")

    low, high = sides["low"], sides["high"]
    for i in range(n):
        if not low[i] < high[i]:
            raise SpecError(path("high", i), f"must be greater than low ({low[i]:g}) for joint {i + 1}, "
                            f"got {high[i]:g}")
        lim = limits[i]
        if lim is not None and low[i] < lim[0]:
            raise SpecError(path("low", i), f"outside joint {i + 1}'s limits [{lim[0]:.6g}, {lim[1]:.6g}], "
                            f"got {low[i]:g}")
        if lim is not None and high[i] > lim[1]:
            raise SpecError(path("high", i), f"outside joint {i + 1}'s limits [{lim[0]:.6g}, {lim[1]:.6g}], "
                            f"got {high[i]:g}")
    return {"low": list(low), "high": list(high), "samples": ws.samples, "tolerance": ws.tolerance,
            "source": source}
