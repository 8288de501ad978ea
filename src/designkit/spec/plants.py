"""The ``plant`` section of a spec: a discriminated union on ``kind``.

* ``link``: the notes' simplified link (``Km``, ``tau``);
* ``robot``: a serial manipulator -- a built-in robot by name (``robot: planar2r`` with
  ``parameters`` overriding its defaults), a DH table (``dh:``) or a URDF file (``urdf:``, a
  path relative to the spec file); ``friction`` and ``motor_inertia`` options;
* ``elastic_joint``: the ROBEL elastic joint (omitted parameters take the built-in defaults).

Every kind takes an optional ``uncertainty``: intervals ``[low, high]`` of named plant
parameters (``{Km: [1.5, 2.5], tau: [0.4, 0.6]}``, ``{m2: [2.5, 3.5]}``) over which robustness is
checked.  Whether the names exist is checked against the built plant (the model layer knows
them), with the key path ``plant.uncertainty.<name>``.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, field_validator, model_validator

from designkit.spec.fields import Finite, NonNegativeFinite, PerJoint, PositiveFinite, Section

__all__ = ["DHLink", "ElasticJointPlantSpec", "Limits", "LinkPlantSpec", "Payload", "PlantSpec", "RobotPlantSpec",
           "Uncertainty"]


class Uncertainty(Section):
    """Intervals of named plant parameters, and how densely to sample them.

    Any key other than ``grid``, ``samples`` and ``seed`` names a plant parameter and takes an
    interval ``[low, high]`` (``low <= high``, finite).  ``grid`` is the number of lattice points
    per parameter (the lattice is capped at :data:`MAX_GRID_POINTS` plants; fewer points per
    axis when there are many parameters), ``samples`` the number of seeded random interior
    points drawn in addition, ``seed`` their seed.
    """

    model_config = ConfigDict(extra="allow", frozen=True, allow_inf_nan=False)

    grid: int = Field(default=21, ge=2, le=1001)
    samples: int = Field(default=0, ge=0, le=100_000)
    seed: int = Field(default=0, ge=0)

    @model_validator(mode="after")
    def _intervals(self) -> Uncertainty:
        extra = self.model_extra or {}
        if not extra:
            raise ValueError("name at least one parameter with an interval, e.g. {Km: [1.5, 2.5]}")
        for name, value in extra.items():
            if not isinstance(value, list | tuple) or len(value) != 2:
                raise ValueError(f"{name}: must be an interval [low, high], got {value!r}")
            lo, hi = value
            for v in (lo, hi):
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                    raise ValueError(f"{name}: interval bounds must be finite numbers, got {value!r}")
            if lo > hi:
                raise ValueError(f"{name}: interval must be [low, high] with low <= high, got [{lo:g}, {hi:g}]")
        return self

    @property
    def intervals(self) -> dict[str, tuple[float, float]]:
        """Parameter name -> ``(low, high)``, in the order written."""
        return {k: (float(v[0]), float(v[1])) for k, v in (self.model_extra or {}).items()}


MAX_GRID_POINTS = 100_000
"""Largest robustness lattice (plants); the points per axis are reduced to stay below it."""


class LinkPlantSpec(Section):
    """Simplified link ``x1' = x2, x2' = -x2/tau + (Km/tau)(u + xi)``.

    ``Km`` is the link gain ((rad/s)/(N*m)), ``tau`` the time constant (s).
    """

    kind: Literal["link"]
    Km: PositiveFinite
    tau: PositiveFinite
    uncertainty: Uncertainty | None = None


class DHLink(Section):
    """One row of a DH table: the joint, its DH parameters (m, rad) and the link's inertial data (SI).

    ``com`` is the centre of mass in the link frame (m), ``inertia`` ``(Ixx, Iyy, Izz, Ixy, Ixz,
    Iyz)`` about the centre of mass (kg*m^2), ``viscous`` (N*m*s/rad) and ``coulomb`` (N*m) the
    joint friction, ``motor_inertia`` (kg*m^2) the rotor inertia reflected through ``gear_ratio``.
    """

    joint: Literal["revolute", "prismatic"] = "revolute"
    a: Finite = 0.0
    alpha: Finite = 0.0
    d: Finite = 0.0
    theta: Finite = 0.0
    offset: Finite = 0.0
    mass: NonNegativeFinite = 0.0
    com: tuple[Finite, Finite, Finite] = (0.0, 0.0, 0.0)
    inertia: tuple[Finite, Finite, Finite, Finite, Finite, Finite] = (0.0,) * 6
    viscous: NonNegativeFinite = 0.0
    coulomb: NonNegativeFinite = 0.0
    motor_inertia: NonNegativeFinite = 0.0
    gear_ratio: Finite = 1.0
    qlim: tuple[Finite, Finite] | None = None
    name: str = Field(default="", max_length=100)


class Payload(Section):
    """A payload of ``mass`` (kg) concentrated at the centre of mass of ``link`` (1-based, default the last)."""

    mass: NonNegativeFinite
    link: int | None = Field(default=None, ge=1)


class Limits(Section):
    """Actuator and motion limits of a robot, per joint (or one value for all): ``velocity`` (rad/s),
    ``acceleration`` (rad/s^2) -- a trajectory exceeding them is refused -- and ``torque`` (N*m), which the
    simulated commands are checked against.  Position limits come from the robot data (``qlim``)."""

    velocity: PerJoint | None = None
    acceleration: PerJoint | None = None
    torque: PerJoint | None = None

    @field_validator("velocity", "acceleration", "torque")
    @classmethod
    def _positive(cls, v: float | list[float] | None) -> float | list[float] | None:
        for x in (v if isinstance(v, list) else [] if v is None else [v]):
            if x <= 0:
                raise ValueError(f"must be positive, got {x:g}")
        return v


class RobotPlantSpec(Section):
    """A serial manipulator: exactly one of ``robot`` (built-in name), ``dh`` (table) or ``urdf`` (path).

    ``parameters`` override a built-in robot's named parameters (see ``designkit model NAME``);
    ``convention`` and ``gravity`` (m/s^2, base frame) describe a DH table; ``base_link`` and
    ``tip_link`` select the chain of a URDF (``gravity`` also applies).  ``friction`` includes the
    joints' viscous and Coulomb friction in the dynamics; ``motor_inertia`` the reflected rotor
    inertia; ``payload`` a mass carried by a link (part of the true plant); ``limits`` the joints'
    velocity, acceleration and torque limits.
    """

    kind: Literal["robot"]
    robot: str | None = Field(default=None, max_length=100)
    parameters: dict[str, Finite] = Field(default_factory=dict)
    dh: list[DHLink] | None = Field(default=None, min_length=1, max_length=64)
    convention: Literal["standard", "modified"] = "standard"
    gravity: tuple[Finite, Finite, Finite] = (0.0, 0.0, -9.81)
    urdf: str | None = Field(default=None, max_length=4096)
    base_link: str | None = None
    tip_link: str | None = None
    friction: bool = True
    motor_inertia: bool = False
    payload: Payload | None = None
    limits: Limits | None = None
    uncertainty: Uncertainty | None = None

    @model_validator(mode="after")
    def _one_source(self) -> RobotPlantSpec:
        given = [k for k in ("robot", "dh", "urdf") if getattr(self, k) is not None]
        if len(given) != 1:
            what = "none" if not given else " and ".join(given)
            raise ValueError(f"give exactly one of robot (a built-in name), dh (a table) or urdf (a file), got {what}")
        if self.parameters and self.robot is None:
            raise ValueError("parameters: only a built-in robot has named parameters to override")
        # judged on values (not on which keys were written) so that a full dump of a spec validates again
        if self.dh is None and self.convention != "standard":
            raise ValueError("convention: only applies to a dh table")
        if self.urdf is None and (self.base_link is not None or self.tip_link is not None):
            raise ValueError("base_link: only applies to a urdf file")
        if self.robot is not None and tuple(self.gravity) != (0.0, 0.0, -9.81):
            raise ValueError("gravity: a built-in robot sets its gravity with parameters.g")
        return self


class ElasticJointPlantSpec(Section):
    """The ROBEL elastic joint (notes appendix B); omitted parameters take the built-in defaults.

    ``J1`` rotor inertia (kg*m^2), ``tau1`` motor time constant (s), ``Km`` motor static gain
    ((rad/s)/input), ``KR`` stiffness (N*m/rad), ``R1``, ``R2`` transmission ratios, ``J2`` link
    inertia (kg*m^2), ``tau2`` link time constant (s), ``mgl`` gravity torque amplitude (N*m).
    """

    kind: Literal["elastic_joint"]
    J1: PositiveFinite | None = None
    tau1: PositiveFinite | None = None
    Km: PositiveFinite | None = None
    KR: PositiveFinite | None = None
    R1: PositiveFinite | None = None
    R2: PositiveFinite | None = None
    J2: PositiveFinite | None = None
    tau2: PositiveFinite | None = None
    mgl: NonNegativeFinite | None = None
    uncertainty: Uncertainty | None = None

    def given(self) -> dict[str, Any]:
        """The parameters the spec sets (the others keep their defaults)."""
        return {k: v for k, v in self.model_dump(exclude={"kind", "uncertainty"}).items() if v is not None}


PlantSpec = Annotated[LinkPlantSpec | RobotPlantSpec | ElasticJointPlantSpec, Field(discriminator="kind")]
"""The ``plant`` section: one of the plant kinds above."""
