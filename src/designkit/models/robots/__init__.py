"""Built-in robots, one module each; :func:`robot` builds one by name.

======== ===============================================================
name     robot
======== ===============================================================
onelink  single revolute link (pendulum)
planar2r the notes' SIMNOG planar two-link arm
scara    4-axis RRPR SCARA (Adept Cobra 600 kinematics)
puma560  Unimation PUMA 560 (Armstrong, Khatib & Burdick dynamics)
======== ===============================================================

The ROBEL elastic link is not a rigid chain: its defaults are
:data:`designkit.models.robots.elastic_link.DEFAULTS`.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any

from designkit import arguments
from designkit.errors import ModelError
from designkit.models.robot import Robot
from designkit.models.robots import onelink, planar2r, puma560, scara

__all__ = ["ROBOTS", "robot", "zoo_module"]

ROBOTS: dict[str, Callable[..., Robot]] = {
    "onelink": onelink.build,
    "planar2r": planar2r.build,
    "scara": scara.build,
    "puma560": puma560.build,
}
"""Robot name -> builder ``(*, friction=False, motor_inertia=False, symbolic=(), **overrides) -> Robot``."""

_MODULES: dict[str, ModuleType] = {"onelink": onelink, "planar2r": planar2r, "scara": scara, "puma560": puma560}


def zoo_module(name: str) -> ModuleType:
    """The module of a built-in robot: its ``DEFAULTS`` (values) and ``UNITS`` ((unit, meaning)) by parameter name."""
    try:
        return _MODULES[name]
    except KeyError:
        raise ModelError("robot", f"unknown robot {name!r}; choose from {sorted(ROBOTS)}") from None


def _check_values(name: str, overrides: dict[str, Any]) -> None:
    """Numeric overrides follow the plant's rule (``RobotPlant.with_params``): finite, and positive, or
    non-negative for masses, inertias, frictions, torques and gravity."""
    import math

    from designkit.models.robot_plant import _NON_NEGATIVE_UNITS

    units = getattr(zoo_module(name), "UNITS", {})
    for key, value in overrides.items():
        if key not in units or isinstance(value, bool | str) or not isinstance(value, int | float):
            continue  # symbols, options and unknown names: the builder's own rules
        positive = units[key][0] not in _NON_NEGATIVE_UNITS
        v = arguments.number(value, key, finite=False, error=ModelError)
        if not math.isfinite(v) or (positive and v <= 0) or (not positive and v < 0):
            need = "positive and finite" if positive else "non-negative and finite"
            raise ModelError(key, f"must be {need} ({units[key][1]}, {units[key][0]}), got {v:g}")


def robot(name: str, **overrides: Any) -> Robot:
    """Build a built-in robot by name.

    Parameters
    ----------
    name : str
        A key of :data:`ROBOTS`.
    **overrides
        Named physical parameters of that robot (see its module's ``DEFAULTS``),
        given as numbers or scalar ``casadi.SX`` symbols, plus the options
        ``friction``, ``motor_inertia`` and ``symbolic`` (``True`` or a tuple of names), and
        ``consistent_inertia``: ``"raise"`` or ``"nearest"`` to replace inertias that are not physically
        consistent as published (:func:`designkit.models.physical.nearest_consistent`), default off.

    Raises
    ------
    ModelError
        For an unknown robot or parameter name.

    Examples
    --------
    >>> arm = robot("planar2r", m1=1.0, d2=0.5)
    >>> arm.n, arm.description.links[1].a
    (2, 0.5)
    """
    name = arguments.text(name, "name", error=ModelError)
    try:
        builder = ROBOTS[name]
    except KeyError:
        raise ModelError("robot", f"unknown robot {name!r}; choose from {sorted(ROBOTS)}") from None
    method = overrides.pop("consistent_inertia", None)
    if method not in (None, False):
        method = arguments.choice(method, "consistent_inertia", ("raise", "nearest"), error=ModelError)
    for option in ("friction", "motor_inertia"):
        if option in overrides:
            overrides[option] = arguments.flag(overrides[option], option, error=ModelError)
    _check_values(name, overrides)
    arm = builder(**overrides)
    if method in (None, False):
        return arm
    if arm.description.symbols:
        raise ModelError("consistent_inertia", "needs a numeric robot (this one has symbols)")
    from designkit.models.physical import nearest_consistent

    fixed, _ = nearest_consistent(arm.description, method)
    return Robot(fixed, friction=arm.friction, motor_inertia=arm.motor_inertia)
