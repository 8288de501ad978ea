"""Planar two-link arm of the notes' SIMNOG simulator (appendix B, fig. 2.2).

Two uniform links of masses ``m1, m2`` (kg) and lengths ``d1, d2`` (m) with their
centres of mass at mid-length; ``I1, I2`` (kg*m^2) are their inertias about the
centre of mass, perpendicular to the plane of motion.  Joint 1 angle
(``x11``) is measured from the horizontal base ``x`` axis, joint 2 angle (``x21``)
is *relative* to link 1; gravity ``g`` (m/s^2) acts along the base ``-y`` axis.
``f1, f2`` are the joints' viscous friction coefficients (N*m*s/rad).

With these conventions the model reproduces the appendix closed forms, e.g.
``D11 = m1 d1^2/4 + m2 (d1^2 + d2^2/4 + d1 d2 cos x21) + I1 + I2`` and the
gravity torque ``-T1g = g [(m2 + m1/2) d1 cos x11 + (m2/2) d2 cos(x11 + x21)]``
(``tests/models/test_robots.py``).  The notes give no numbers: the defaults
below are illustrative (steel-tube-like links, ``I = m d^2/12`` of a uniform rod).
"""

from __future__ import annotations

from typing import Any

from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.robot import Robot
from designkit.models.robots._parameters import resolve

__all__ = ["DEFAULTS", "LINK_MASSES", "UNITS", "build", "description"]

DEFAULTS: dict[str, float] = {
    "m1": 5.0,  # link 1 mass (kg)
    "m2": 3.0,  # link 2 mass (kg)
    "d1": 0.5,  # link 1 length (m)
    "d2": 0.4,  # link 2 length (m)
    "I1": 5.0 * 0.5**2 / 12,  # link 1 inertia about its centre of mass (kg*m^2)
    "I2": 3.0 * 0.4**2 / 12,  # link 2 inertia about its centre of mass (kg*m^2)
    "f1": 2.0,  # joint 1 viscous friction (N*m*s/rad)
    "f2": 1.0,  # joint 2 viscous friction (N*m*s/rad)
    "g": 9.81,  # gravitational acceleration (m/s^2)
}

UNITS: dict[str, tuple[str, str]] = {
    "m1": ("kg", "link 1 mass"),
    "m2": ("kg", "link 2 mass"),
    "d1": ("m", "link 1 length"),
    "d2": ("m", "link 2 length"),
    "I1": ("kg*m^2", "link 1 inertia about its centre of mass"),
    "I2": ("kg*m^2", "link 2 inertia about its centre of mass"),
    "f1": ("N*m*s/rad", "joint 1 viscous friction"),
    "f2": ("N*m*s/rad", "joint 2 viscous friction"),
    "g": ("m/s^2", "gravitational acceleration"),
}
"""Parameter name -> (SI unit, meaning), for reports and specs."""

LINK_MASSES: tuple[str, ...] = ('m1', 'm2')
"""The parameter holding each link's mass (a payload on link i adds to it)."""


def description(*, symbolic: bool | tuple[str, ...] = (), **overrides: Any) -> ChainDescription:
    """Chain description (standard DH, ``a_i = d_i``); ``overrides`` replace entries of :data:`DEFAULTS`."""
    v, symbols = resolve("planar2r", DEFAULTS, overrides, symbolic)
    links = tuple(
        LinkDescription(
            joint="revolute", a=v[f"d{i}"], mass=v[f"m{i}"], com=(-0.5 * v[f"d{i}"], 0.0, 0.0),
            inertia=(0.0, v[f"I{i}"], v[f"I{i}"], 0.0, 0.0, 0.0), viscous=v[f"f{i}"], name=f"joint{i}",
        )
        for i in (1, 2)
    )
    return ChainDescription(
        name="planar2r", links=links, gravity=(0.0, -v["g"], 0.0), symbols=symbols,
        source="R. M. DeSantis, EPM/RT-88/26 (1988), appendix B, SIMNOG; illustrative values",
    )


def build(*, friction: bool = False, motor_inertia: bool = False, symbolic: bool | tuple[str, ...] = (),
          **overrides: Any) -> Robot:
    """The SIMNOG arm as a :class:`~designkit.models.robot.Robot`."""
    return Robot(description(symbolic=symbolic, **overrides), friction=friction, motor_inertia=motor_inertia)
