"""Kinematic and inertial description of a serial manipulator.

A :class:`ChainDescription` is the single input of every model builder
(kinematics, Newton--Euler, Euler--Lagrange, regressor, code generation).
It is a frozen value: builders never modify it.  Every numeric field may
instead hold a named CasADi ``SX`` symbol (or expression), so that a model
can be symbolic in its physical parameters; :attr:`ChainDescription.symbols`
lists those symbols by name.

Conventions (SI units: m, rad, kg, kg*m^2, N, N*m):

* Denavit--Hartenberg parameters per joint, ``convention`` is ``"standard"``
  (Craig's "distal": ``T_{i-1,i} = Rz(theta) Tz(d) Tx(a) Rx(alpha)``) or
  ``"modified"`` (Craig's "proximal": ``T_{i-1,i} = Rx(alpha) Tx(a) Rz(theta) Tz(d)``).
* Revolute joint: ``theta = q + offset``, ``d`` fixed.  Prismatic joint:
  ``d = q + offset``, ``theta`` fixed.
* Inertial parameters of link ``i`` are expressed in frame ``i`` (the frame
  attached to link ``i`` by the DH convention): ``com`` is the centre of mass,
  ``inertia`` the inertia tensor *about the centre of mass*, as
  ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``.
* ``gravity`` is the gravitational acceleration vector in the base frame
  (e.g. ``(0, 0, -9.81)``), ``base`` and ``tool`` are fixed 4x4 homogeneous
  transforms before the first joint and after the last.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

Scalar = Any  # float or casadi.SX expression
JointType = Literal["revolute", "prismatic"]
Convention = Literal["standard", "modified"]

IDENTITY4: tuple[tuple[float, ...], ...] = (
    (1.0, 0.0, 0.0, 0.0),
    (0.0, 1.0, 0.0, 0.0),
    (0.0, 0.0, 1.0, 0.0),
    (0.0, 0.0, 0.0, 1.0),
)


@dataclass(frozen=True)
class LinkDescription:
    """One joint and the link it moves.

    Parameters
    ----------
    joint : {"revolute", "prismatic"}
        Joint type.
    a, alpha, d, theta : float or casadi.SX
        DH parameters (m, rad, m, rad).  The joint variable's own entry
        (``theta`` for revolute, ``d`` for prismatic) is ignored.
    offset : float
        Joint offset added to ``q`` (rad or m).
    mass : float or casadi.SX
        Link mass (kg).
    com : tuple of 3
        Centre of mass in the link frame (m).
    inertia : tuple of 6
        ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` about the centre of mass, link frame (kg*m^2).
    viscous : float or casadi.SX
        Viscous joint friction coefficient (N*m*s/rad or N*s/m).
    coulomb : float or casadi.SX
        Coulomb friction torque (N*m or N); modelled as ``coulomb * sign(qd)``.
    motor_inertia : float or casadi.SX
        Rotor inertia on the motor side (kg*m^2); reflected as ``gear_ratio**2 * motor_inertia``.
    gear_ratio : float
        Motor-to-joint reduction (dimensionless).
    qlim : tuple of 2 or None
        Joint limits (rad or m).
    name : str
        Joint name.
    """

    joint: JointType = "revolute"
    a: Scalar = 0.0
    alpha: Scalar = 0.0
    d: Scalar = 0.0
    theta: Scalar = 0.0
    offset: Scalar = 0.0
    mass: Scalar = 0.0
    com: tuple[Scalar, Scalar, Scalar] = (0.0, 0.0, 0.0)
    inertia: tuple[Scalar, Scalar, Scalar, Scalar, Scalar, Scalar] = (0.0,) * 6
    viscous: Scalar = 0.0
    coulomb: Scalar = 0.0
    motor_inertia: Scalar = 0.0
    gear_ratio: Scalar = 1.0
    qlim: tuple[float, float] | None = None
    name: str = ""


@dataclass(frozen=True)
class ChainDescription:
    """A serial chain: links from base to tool.

    Parameters
    ----------
    name : str
        Robot name.
    links : tuple of LinkDescription
        Joints from base to tool.
    convention : {"standard", "modified"}
        DH convention of the ``links``.
    gravity : tuple of 3
        Gravitational acceleration in the base frame (m/s^2).
    base, tool : 4x4 nested tuples
        Fixed transforms before joint 1 and after joint n.
    symbols : tuple of (str, casadi.SX)
        Named physical-parameter symbols used in the numeric fields; empty for a numeric model.
    source : str
        Where the parameter values come from (citation).
    """

    name: str
    links: tuple[LinkDescription, ...]
    convention: Convention = "standard"
    gravity: tuple[Scalar, Scalar, Scalar] = (0.0, 0.0, -9.81)
    base: tuple[tuple[Scalar, ...], ...] = IDENTITY4
    tool: tuple[tuple[Scalar, ...], ...] = IDENTITY4
    symbols: tuple[tuple[str, Any], ...] = field(default=())
    source: str = ""

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.links)
