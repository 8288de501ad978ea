"""A 4-axis SCARA arm (RRPR), standard DH.

Kinematics: the Adept Cobra 600 as modelled in P. Corke's Robotics Toolbox
(``mdl_cobra600``: ``d1 = 0.387``, ``a1 = 0.325``, ``a2 = 0.275`` m, ``alpha2 = pi``,
joint 3 a prismatic quill moving along ``-z`` of the base, stroke 0..0.21 m).
Dynamics: *assumed*, plausible values for an arm of that size (no published
set): links 1 and 2 are uniform rods (radius 0.05 m) with the centre of mass at
mid-length, the quill a 0.3 m rod of radius 0.01 m whose lower end is the frame-3
origin, the last link a disc of radius 0.04 m.  SI units: m, rad, kg, kg*m^2,
N*m*s/rad (N*s/m for the quill).
"""

from __future__ import annotations

import math
from typing import Any

from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.robot import Robot
from designkit.models.robots._parameters import resolve

__all__ = ["DEFAULTS", "LINK_MASSES", "UNITS", "build", "description"]

DEFAULTS: dict[str, float] = {
    "d1": 0.387,  # height of the shoulder (m)
    "a1": 0.325,  # link 1 length (m)
    "a2": 0.275,  # link 2 length (m)
    "m1": 8.0,  # link 1 mass (kg)
    "m2": 6.0,  # link 2 mass (kg)
    "m3": 2.0,  # quill mass (kg)
    "m4": 0.5,  # wrist / flange mass (kg)
    "f1": 1.0,  # joint 1 viscous friction (N*m*s/rad)
    "f2": 0.5,  # joint 2 viscous friction (N*m*s/rad)
    "f3": 5.0,  # quill viscous friction (N*s/m)
    "f4": 0.05,  # joint 4 viscous friction (N*m*s/rad)
    "g": 9.81,  # gravitational acceleration (m/s^2)
}

UNITS: dict[str, tuple[str, str]] = {
    "d1": ("m", "shoulder height"),
    "a1": ("m", "link 1 length"),
    "a2": ("m", "link 2 length"),
    "m1": ("kg", "link 1 mass"),
    "m2": ("kg", "link 2 mass"),
    "m3": ("kg", "quill mass"),
    "m4": ("kg", "wrist mass"),
    "f1": ("N*m*s/rad", "joint 1 viscous friction"),
    "f2": ("N*m*s/rad", "joint 2 viscous friction"),
    "f3": ("N*s/m", "quill viscous friction"),
    "f4": ("N*m*s/rad", "joint 4 viscous friction"),
    "g": ("m/s^2", "gravitational acceleration"),
}
"""Parameter name -> (SI unit, meaning), for reports and specs."""

LINK_MASSES: tuple[str, ...] = ('m1', 'm2', 'm3', 'm4')
"""The parameter holding each link's mass (a payload on link i adds to it)."""

_ARM_RADIUS = 0.05  # m
_QUILL_LENGTH, _QUILL_RADIUS = 0.3, 0.01  # m
_DISC_RADIUS = 0.04  # m


def _rod_along_x(m: Any, length: Any) -> tuple[Any, ...]:
    transverse = m * length**2 / 12
    return (m * _ARM_RADIUS**2 / 2, transverse, transverse, 0.0, 0.0, 0.0)


def description(*, symbolic: bool | tuple[str, ...] = (), **overrides: Any) -> ChainDescription:
    """Chain description; ``overrides`` replace entries of :data:`DEFAULTS`."""
    v, symbols = resolve("scara", DEFAULTS, overrides, symbolic)
    quill_t = v["m3"] * _QUILL_LENGTH**2 / 12
    disc = v["m4"] * _DISC_RADIUS**2
    links = (
        LinkDescription(joint="revolute", d=v["d1"], a=v["a1"], mass=v["m1"], com=(-0.5 * v["a1"], 0.0, 0.0),
                        inertia=_rod_along_x(v["m1"], v["a1"]), viscous=v["f1"],
                        qlim=(-math.radians(105), math.radians(105)), name="shoulder"),
        LinkDescription(joint="revolute", a=v["a2"], alpha=math.pi, mass=v["m2"], com=(-0.5 * v["a2"], 0.0, 0.0),
                        inertia=_rod_along_x(v["m2"], v["a2"]), viscous=v["f2"],
                        qlim=(-math.radians(150), math.radians(150)), name="elbow"),
        LinkDescription(joint="prismatic", mass=v["m3"], com=(0.0, 0.0, -0.5 * _QUILL_LENGTH),
                        inertia=(quill_t, quill_t, v["m3"] * _QUILL_RADIUS**2 / 2, 0.0, 0.0, 0.0),
                        viscous=v["f3"], qlim=(0.0, 0.21), name="quill"),
        LinkDescription(joint="revolute", mass=v["m4"], com=(0.0, 0.0, 0.02),
                        inertia=(disc / 4, disc / 4, disc / 2, 0.0, 0.0, 0.0), viscous=v["f4"],
                        qlim=(-math.radians(360), math.radians(360)), name="wrist"),
    )
    return ChainDescription(
        name="scara", links=links, gravity=(0.0, 0.0, -v["g"]), symbols=symbols,
        source="kinematics: P. Corke, Robotics Toolbox mdl_cobra600 (Adept Cobra 600); "
               "dynamics: assumed uniform-body values",
    )


def build(*, friction: bool = False, motor_inertia: bool = False, symbolic: bool | tuple[str, ...] = (),
          **overrides: Any) -> Robot:
    """The SCARA as a :class:`~designkit.models.robot.Robot`."""
    return Robot(description(symbolic=symbolic, **overrides), friction=friction, motor_inertia=motor_inertia)
