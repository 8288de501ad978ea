"""A single revolute link: a rigid pendulum in a vertical plane.

A uniform rod of mass ``m`` and length ``l`` turns about the base ``z`` axis; the
joint angle is measured from the horizontal base ``x`` axis and gravity acts
along ``-y`` (as the notes' SIMNOG arm).  SI units: m, rad, kg, kg*m^2, N*m*s/rad.
Default values are illustrative (a 1 kg, 0.5 m rod), not taken from a datasheet.
"""

from __future__ import annotations

from typing import Any

from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.robot import Robot
from designkit.models.robots._parameters import resolve

__all__ = ["DEFAULTS", "LINK_MASSES", "UNITS", "build", "description"]

DEFAULTS: dict[str, float] = {
    "m": 1.0,  # rod mass (kg)
    "l": 0.5,  # rod length, joint to tip (m)
    "I": 1.0 * 0.5**2 / 12,  # inertia about the centre of mass, perpendicular to the rod (kg*m^2)
    "f": 0.5,  # joint viscous friction (N*m*s/rad)
    "fc": 0.0,  # joint Coulomb friction (N*m)
    "Jm": 0.0,  # motor rotor inertia (kg*m^2)
    "G": 1.0,  # gear ratio (motor turns per joint turn)
    "g": 9.81,  # gravitational acceleration (m/s^2)
}

UNITS: dict[str, tuple[str, str]] = {
    "m": ("kg", "rod mass"),
    "l": ("m", "rod length"),
    "I": ("kg*m^2", "inertia about the centre of mass"),
    "f": ("N*m*s/rad", "joint viscous friction"),
    "fc": ("N*m", "joint Coulomb friction"),
    "Jm": ("kg*m^2", "motor rotor inertia"),
    "G": ("1", "gear ratio"),
    "g": ("m/s^2", "gravitational acceleration"),
}
"""Parameter name -> (SI unit, meaning), for reports and specs."""

LINK_MASSES: tuple[str, ...] = ('m',)
"""The parameter holding each link's mass (a payload on link i adds to it)."""


def description(*, symbolic: bool | tuple[str, ...] = (), **overrides: Any) -> ChainDescription:
    """Chain description of the pendulum; ``overrides`` replace entries of :data:`DEFAULTS`."""
    v, symbols = resolve("onelink", DEFAULTS, overrides, symbolic)
    link = LinkDescription(
        joint="revolute", a=v["l"], mass=v["m"], com=(-0.5 * v["l"], 0.0, 0.0),
        inertia=(0.0, v["I"], v["I"], 0.0, 0.0, 0.0), viscous=v["f"], coulomb=v["fc"],
        motor_inertia=v["Jm"], gear_ratio=v["G"], name="joint1",
    )
    return ChainDescription(
        name="onelink", links=(link,), gravity=(0.0, -v["g"], 0.0), symbols=symbols,
        source="designkit built-in: uniform rod pendulum (illustrative values)",
    )


def build(*, friction: bool = False, motor_inertia: bool = False, symbolic: bool | tuple[str, ...] = (),
          **overrides: Any) -> Robot:
    """The pendulum as a :class:`~designkit.models.robot.Robot`."""
    return Robot(description(symbolic=symbolic, **overrides), friction=friction, motor_inertia=motor_inertia)
