"""The number of joints of a spec's plant, read cheaply, and the per-joint lists checked against it before
anything is built.

Building a robot's symbolic model grows like ``n^3.5`` (:mod:`designkit.schema.budget`): a 40-joint
chain takes tens of seconds, and a list with the wrong number of entries (``simulation.initial_position``
with 39 values for 40 joints) should not wait for the model to count its joints.
:func:`joint_count` reads ``n`` from what the spec gives -- a built-in robot's published table, the
rows of a DH table, the joints of a URDF's chain (parsed, no model built) -- and
:func:`check_joint_lists` refuses a per-joint list of another length with the message the later stages
give (``simulation.step: needs one value per joint (2), got 3``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from designkit.errors import SpecError
from designkit.families import FAMILIES

__all__ = ["check_joint_lists", "joint_count"]


def joint_count(plant: Any, base_dir: Path | None = None) -> int | None:
    """Joints of the plant section (1 for a link or an elastic joint), or None when it cannot be read cheaply
    (an unknown robot name, a URDF that does not parse: the model's builder refuses those, naming the key)."""
    kind = getattr(plant, "kind", None)
    if kind != "robot":
        return 1
    if plant.dh is not None:
        return len(plant.dh)
    if plant.robot is not None:
        try:
            from designkit.models.robots import zoo_module

            return int(zoo_module(plant.robot).description().n)
        except Exception:  # noqa: BLE001 - the builder names the problem (plant.robot) later
            return None
    if plant.urdf is not None:
        try:
            from designkit.models.urdf import description_from_urdf

            path = Path(plant.urdf)
            if not path.is_absolute() and base_dir is not None:
                path = base_dir / path
            return int(description_from_urdf(path, base_link=plant.base_link, tip_link=plant.tip_link).n)
        except Exception:  # noqa: BLE001 - the builder names the problem (plant.urdf) later
            return None
    return None


def _length(value: Any) -> int | None:
    return len(value) if isinstance(value, list | tuple) else None


def _refuse(path: str, value: Any, n: int, what: str = "joint") -> None:
    m = _length(value)
    if m is not None and m != n:
        raise SpecError(path, f"needs one value per {what} ({n}), got {m}")


def check_joint_lists(spec: Any, n: int) -> None:
    """Refuse a per-joint list of ``spec`` whose length is not ``n`` (:class:`SpecError` naming its key path).

    Only a robot's lists are checked here (a link or an elastic joint is built in milliseconds, and its own
    stages say what its lists mean): ``simulation.step``, ``simulation.initial_position``, the trajectories'
    ``amplitude``, ``max_velocity``, ``max_acceleration`` and ``points[k]``, the ``controller`` fields its family
    declares per joint (:attr:`~designkit.synthesis.family.Family.per_joint_fields`: the model-based families'
    ``damping`` and ``natural_frequency``), ``plant.limits``, the nonlinear element's levels and
    ``requirements.max_control`` (one value per input: a robot has one per joint).
    """
    if getattr(spec.plant, "kind", None) != "robot":
        return
    sim = spec.simulation
    _refuse("simulation.step", sim.step, n)
    _refuse("simulation.initial_position", sim.initial_position, n)
    traj = sim.trajectory
    if traj is not None:
        for key in ("amplitude", "max_velocity", "max_acceleration"):
            if hasattr(traj, key):
                _refuse(f"simulation.trajectory.{key}", getattr(traj, key), n)
        for k, point in enumerate(getattr(traj, "points", None) or ()):
            _refuse(f"simulation.trajectory.points[{k}]", point, n)
    ctrl = getattr(spec, "controller", None)
    fam = FAMILIES.get(getattr(ctrl, "kind", None))
    for key in fam.per_joint_fields if fam is not None else ():
        _refuse(f"controller.{key}", getattr(ctrl, key, None), n)
    limits = getattr(spec.plant, "limits", None)
    if limits is not None:
        for key in ("velocity", "acceleration", "torque"):
            _refuse(f"plant.limits.{key}", getattr(limits, key, None), n)
    element = sim.nonlinearity
    if element is not None:
        for key in ("limit", "width", "amplitude", "hysteresis", "step"):
            _refuse(f"simulation.nonlinearity.{key}", getattr(element, key, None), n, "input")
    req = spec.requirements
    if req is not None:
        _refuse("requirements.max_control", req.max_control, n, "input")
