"""Unimation PUMA 560, standard DH, with the Armstrong, Khatib & Burdick (1986) dynamics.

Values as tabulated by P. Corke and B. Armstrong-Helouvry, "A search for
consensus among model parameters reported for the PUMA 560 robot", Proc. IEEE
ICRA 1994, pp. 1608-1613 -- the same numbers as the ``Puma560`` model of Peter
Corke's Robotics Toolbox for Python (``roboticstoolbox.models.DH.Puma560``),
with the shoulder height ``d1`` (mounting surface to shoulder axis) that the
Python toolbox has used since November 2020: ``26.45 * inch`` = 0.67183 m
(printed 0.6718; commit 5562ebb, "Include pedestal as parameter d1", unchanged in
the current source; the MATLAB toolbox's model has no pedestal).  An earlier
designkit used the toolbox's first value, ``base = 0.672`` m (September 2020,
commit 44e5457); the 0.17 mm between the two moves the base frame along joint
1's axis, the gravity direction, so tool poses shift by 0.17 mm in z and no
dynamic quantity (torques, inertia, Coriolis, gravity, regressor) depends on it.
``puma560.urdf`` is written from this description.  SI units: m, rad, kg, kg*m^2.

The link mass ``m1`` is 0: Armstrong et al. give none, and it does not act on the
joints.  Actuator data, used only with ``friction=True`` / ``motor_inertia=True``
(both off by default), are referred to the joint: rotor inertia ``Jm`` with gear
ratio ``G`` (reflected ``G^2 Jm``), viscous ``G^2 B`` from the motor-side ``B``,
and Coulomb ``|G| (|Tc+| + |Tc-|)/2`` -- the toolbox's direction-dependent
``Tc = (Tc+, Tc-)`` averaged, since the description holds one symmetric value.

Reference figures of the toolbox at ``QN`` (checked in the tests): gravity load
``(0, 31.6399, 6.0351, 0, 0.0283, 0)`` N*m; inertia matrix with rotors ``M11 = 3.6594``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.robot import Robot
from designkit.models.robots._parameters import resolve

__all__ = ["DEFAULTS", "LINK_MASSES", "UNITS", "QN", "QR", "QS", "QZ", "build", "description"]

_DEG = math.pi / 180

DEFAULTS: dict[str, float] = {
    "m1": 0.0,  # link masses (kg)
    "m2": 17.4,
    "m3": 4.8,
    "m4": 0.82,
    "m5": 0.34,
    "m6": 0.09,
    "g": 9.81,  # gravitational acceleration (m/s^2), along -z of the base
}

UNITS: dict[str, tuple[str, str]] = {
    "m1": ("kg", "link 1 mass"),
    "m2": ("kg", "link 2 mass"),
    "m3": ("kg", "link 3 mass"),
    "m4": ("kg", "link 4 mass"),
    "m5": ("kg", "link 5 mass"),
    "m6": ("kg", "link 6 mass"),
    "g": ("m/s^2", "gravitational acceleration"),
}
"""Parameter name -> (SI unit, meaning), for reports and specs."""

LINK_MASSES: tuple[str, ...] = ('m1', 'm2', 'm3', 'm4', 'm5', 'm6')
"""The parameter holding each link's mass (a payload on link i adds to it)."""

# d (m), a (m), alpha (rad), centre of mass (m), (Ixx, Iyy, Izz) about it (kg*m^2),
# Jm (kg*m^2), G, B (N*m*s/rad, motor side), Tc = (Tc+, Tc-) (N*m, motor side), qlim (rad)
_LINKS: tuple[dict[str, Any], ...] = (
    dict(d=26.45 * 0.0254, a=0.0, alpha=math.pi / 2, r=(0.0, 0.0, 0.0), I=(0.0, 0.35, 0.0),
         Jm=200e-6, G=-62.6111, B=1.48e-3, Tc=(0.395, -0.435), qlim=(-160 * _DEG, 160 * _DEG)),
    dict(d=0.0, a=0.4318, alpha=0.0, r=(-0.3638, 0.006, 0.2275), I=(0.13, 0.524, 0.539),
         Jm=200e-6, G=107.815, B=0.817e-3, Tc=(0.126, -0.071), qlim=(-45 * _DEG, 225 * _DEG)),
    dict(d=0.15005, a=0.0203, alpha=-math.pi / 2, r=(-0.0203, -0.0141, 0.070), I=(0.066, 0.086, 0.0125),
         Jm=200e-6, G=-53.7063, B=1.38e-3, Tc=(0.132, -0.105), qlim=(-225 * _DEG, 45 * _DEG)),
    dict(d=0.4318, a=0.0, alpha=math.pi / 2, r=(0.0, 0.019, 0.0), I=(1.8e-3, 1.3e-3, 1.8e-3),
         Jm=33e-6, G=76.0364, B=71.2e-6, Tc=(11.2e-3, -16.9e-3), qlim=(-110 * _DEG, 170 * _DEG)),
    dict(d=0.0, a=0.0, alpha=-math.pi / 2, r=(0.0, 0.0, 0.0), I=(0.3e-3, 0.4e-3, 0.3e-3),
         Jm=33e-6, G=71.923, B=82.6e-6, Tc=(9.26e-3, -14.5e-3), qlim=(-100 * _DEG, 100 * _DEG)),
    dict(d=0.0, a=0.0, alpha=0.0, r=(0.0, 0.0, 0.032), I=(0.15e-3, 0.15e-3, 0.04e-3),
         Jm=33e-6, G=76.686, B=36.7e-6, Tc=(3.96e-3, -10.5e-3), qlim=(-266 * _DEG, 266 * _DEG)),
)

QZ = np.zeros(6)
"""Zero angles, 'L'-shaped pose (rad)."""
QR = np.array([0.0, math.pi / 2, -math.pi / 2, 0.0, 0.0, 0.0])
"""Ready pose, arm up (rad)."""
QS = np.array([0.0, 0.0, -math.pi / 2, 0.0, 0.0, 0.0])
"""Arm stretched horizontally (rad)."""
QN = np.array([0.0, math.pi / 4, math.pi, 0.0, math.pi / 4, 0.0])
"""Nominal table-top pose (rad)."""


def description(*, symbolic: bool | tuple[str, ...] = (), **overrides: Any) -> ChainDescription:
    """Chain description; ``overrides`` replace entries of :data:`DEFAULTS` (masses, ``g``)."""
    v, symbols = resolve("puma560", DEFAULTS, overrides, symbolic)
    links = tuple(
        LinkDescription(
            joint="revolute", d=row["d"], a=row["a"], alpha=row["alpha"], mass=v[f"m{i + 1}"], com=row["r"],
            inertia=(*row["I"], 0.0, 0.0, 0.0), motor_inertia=row["Jm"], gear_ratio=row["G"],
            viscous=row["B"] * row["G"] ** 2, coulomb=abs(row["G"]) * (abs(row["Tc"][0]) + abs(row["Tc"][1])) / 2,
            qlim=row["qlim"], name=f"joint{i + 1}",
        )
        for i, row in enumerate(_LINKS)
    )
    return ChainDescription(
        name="puma560", links=links, gravity=(0.0, 0.0, -v["g"]), symbols=symbols,
        source="Armstrong, Khatib & Burdick 1986 via Corke & Armstrong-Helouvry, ICRA 1994; "
               "as in P. Corke's Robotics Toolbox Puma560",
    )


def build(*, friction: bool = False, motor_inertia: bool = False, symbolic: bool | tuple[str, ...] = (),
          **overrides: Any) -> Robot:
    """The PUMA 560 as a :class:`~designkit.models.robot.Robot` (friction and rotors off by default)."""
    return Robot(description(symbolic=symbolic, **overrides), friction=friction, motor_inertia=motor_inertia)
