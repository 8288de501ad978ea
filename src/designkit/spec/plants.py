"""The ``plant`` section of a spec: a discriminated union on ``kind``.

* ``link``: the notes' simplified link (``Km``, ``tau``);
* ``robot``: a serial manipulator -- a built-in robot by name (``robot: planar2r`` with
  ``parameters`` overriding its defaults), a DH table (``dh:``) or a URDF file (``urdf:``, a
  path relative to the spec file); ``friction`` and ``motor_inertia`` options;
* ``elastic_joint``: the ROBEL elastic joint (omitted parameters take the built-in defaults);
* ``transfer_function``: a SISO ``num(s)/den(s)`` (coefficients highest power first);
* ``state_space``: ``x' = A x + B u``, ``y = C x + D u`` with named states, inputs and outputs.

Either linear kind with ``dt`` (the sample period, s) is **discrete-time**: ``num(z)/den(z)``, or the difference
equation ``x[k+1] = A x[k] + B u[k]``.  Only a family that says it runs sampled plants (``plant.dt`` in
:attr:`~designkit.synthesis.family.Family.uses`: the learning family) accepts one; any other refuses ``plant.dt``
when the spec is read.

The two linear kinds take ``parameters`` (name -> value) that their entries may name (``"b"``, ``"-a"``,
``"2*a"``: :mod:`designkit.models.expression`); :mod:`designkit.models.linear_plant` says how they are realised.

Every kind takes an optional ``uncertainty``: intervals ``[low, high]`` of named plant
parameters (``{Km: [1.5, 2.5], tau: [0.4, 0.6]}``, ``{m2: [2.5, 3.5]}``) over which robustness is
checked.  Whether the names exist is checked against the built plant (the model layer knows
them), with the key path ``plant.uncertainty.<name>``.

Every number has a physically meaningful range declared next to its field
(:mod:`designkit.spec.ranges`; the README's table lists them): e.g. ``Km`` 1e-6 to 1e6
(rad/s)/(N*m), ``tau`` 1e-6 to 1e6 s, masses 0 to 1e4 kg, lengths within 100 m, any named
parameter within 1e6 of its SI unit; both ends of an uncertainty interval lie in the
parameter's range.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, field_validator, model_validator

from designkit.spec.fields import Finite, NonNegativeFinite, PositiveFinite, Section
from designkit.spec.ranges import (
    ANGLE,
    PARAMETER,
    Range,
    Ranged,
    RangedInt,
    RangedPerJoint,
    check_interval,
    range_of,
)

__all__ = ["DHLink", "ElasticJointPlantSpec", "Limits", "LinkPlantSpec", "Payload", "PlantSpec", "RobotPlantSpec",
           "StateSpacePlantSpec", "TransferFunctionPlantSpec", "Uncertainty", "linear_order"]


class Uncertainty(Section):
    """Intervals of named plant parameters, and how densely to sample them.

    Any key other than ``grid``, ``samples`` and ``seed`` names a plant parameter and takes an
    interval ``[low, high]`` (``low <= high``, finite, both within :data:`~designkit.spec.ranges.PARAMETER`
    of the parameter's SI unit; the plant kinds narrow it to the range of their own fields).
    ``grid`` is the number of lattice points per parameter (2 to 1001; the lattice is capped at
    :data:`MAX_GRID_POINTS` plants, fewer points per axis when there are many parameters),
    ``samples`` the number of seeded random interior points drawn in addition (0 to 100,000),
    ``seed`` their seed (0 to 2**32 - 1).
    """

    model_config = ConfigDict(extra="allow", frozen=True, allow_inf_nan=False)

    grid: RangedInt(2, 1001) = 21
    samples: RangedInt(0, 100_000) = 0
    seed: RangedInt(0, 2**32 - 1) = 0

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

    def check_ranges(self, model: type[Section]) -> None:
        """Every interval inside the range of its parameter: the field's of the plant section ``model`` when
        the parameter is one of its fields, else :data:`~designkit.spec.ranges.PARAMETER` (``ValueError``
        naming ``uncertainty.<name>``; the sign is the model layer's to check)."""
        for name, bounds in self.intervals.items():
            rng = range_of(model, name)
            check_interval(f"uncertainty.{name}", bounds, rng or PARAMETER,
                           f"the range of plant.{name}" if rng is not None else "")

    @property
    def intervals(self) -> dict[str, tuple[float, float]]:
        """Parameter name -> ``(low, high)``, in the order written."""
        return {k: (float(v[0]), float(v[1])) for k, v in (self.model_extra or {}).items()}


MAX_GRID_POINTS = 100_000
"""Largest robustness lattice (plants); the points per axis are reduced to stay below it."""


class LinkPlantSpec(Section):
    """Simplified link ``x1' = x2, x2' = -x2/tau + (Km/tau)(u + xi)``.

    ``Km`` is the link gain ((rad/s)/(N*m), 1e-6 to 1e6), ``tau`` the time constant (s, 1e-6 to 1e6);
    an ``uncertainty`` interval of either lies in the same range.
    """

    kind: Literal["link"]
    Km: Ranged(1e-6, 1e6, "(rad/s)/(N*m)", base=PositiveFinite)
    tau: Ranged(1e-6, 1e6, "s", base=PositiveFinite)
    uncertainty: Uncertainty | None = None

    @model_validator(mode="after")
    def _uncertainty_in_range(self) -> LinkPlantSpec:
        if self.uncertainty is not None:
            self.uncertainty.check_ranges(LinkPlantSpec)
        return self


class DHLink(Section):
    """One row of a DH table: the joint, its DH parameters (m, rad) and the link's inertial data (SI).

    ``a``, ``d`` (m) and ``offset`` (rad or m) within 100; ``alpha``, ``theta`` (rad) within one
    turn; ``mass`` (kg) 0 to 1e4; ``com`` the centre of mass in the link frame (m, each within 100),
    ``inertia`` ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` about the centre of mass (kg*m^2, moments 0 to
    1e4, products within 1e4), ``viscous`` (N*m*s/rad) and ``coulomb`` (N*m) the joint friction (0
    to 1e6), ``motor_inertia`` (kg*m^2, 0 to 1e4) the rotor inertia reflected through
    ``gear_ratio`` (within 1e4), ``qlim`` the joint limits (rad or m, within 100).
    """

    joint: Literal["revolute", "prismatic"] = "revolute"
    a: Ranged(-100, 100, "m") = 0.0
    alpha: Ranged(ANGLE.low, ANGLE.high, "rad") = 0.0
    d: Ranged(-100, 100, "m") = 0.0
    theta: Ranged(ANGLE.low, ANGLE.high, "rad") = 0.0
    offset: Ranged(-100, 100, "rad or m") = 0.0
    mass: Ranged(0, 1e4, "kg", base=NonNegativeFinite) = 0.0
    com: tuple[Ranged(-100, 100, "m"), Ranged(-100, 100, "m"), Ranged(-100, 100, "m")] = (0.0, 0.0, 0.0)
    inertia: tuple[Ranged(0, 1e4, "kg*m^2"), Ranged(0, 1e4, "kg*m^2"), Ranged(0, 1e4, "kg*m^2"),
                   Ranged(-1e4, 1e4, "kg*m^2"), Ranged(-1e4, 1e4, "kg*m^2"), Ranged(-1e4, 1e4, "kg*m^2")] = (0.0,) * 6
    viscous: Ranged(0, 1e6, "N*m*s/rad", base=NonNegativeFinite) = 0.0
    coulomb: Ranged(0, 1e6, "N*m", base=NonNegativeFinite) = 0.0
    motor_inertia: Ranged(0, 1e4, "kg*m^2", base=NonNegativeFinite) = 0.0
    gear_ratio: Ranged(-1e4, 1e4, "") = 1.0
    qlim: tuple[Ranged(-100, 100, "rad or m"), Ranged(-100, 100, "rad or m")] | None = None
    name: str = Field(default="", max_length=100)


class Payload(Section):
    """A payload of ``mass`` (kg, 0 to 1e4) concentrated at the centre of mass of ``link`` (1-based, default the
    last)."""

    mass: Ranged(0, 1e4, "kg", base=NonNegativeFinite)
    link: int | None = Field(default=None, ge=1)


class Limits(Section):
    """Actuator and motion limits of a robot, per joint (or one value for all): ``velocity`` (rad/s),
    ``acceleration`` (rad/s^2) -- a trajectory exceeding them is refused -- and ``torque`` (N*m), which the
    simulated commands are checked against; each 1e-6 to 1e6.  Position limits come from the robot data
    (``qlim``)."""

    velocity: RangedPerJoint(1e-6, 1e6, "rad/s") | None = None
    acceleration: RangedPerJoint(1e-6, 1e6, "rad/s^2") | None = None
    torque: RangedPerJoint(1e-6, 1e6, "N*m") | None = None

    @field_validator("velocity", "acceleration", "torque")
    @classmethod
    def _positive(cls, v: float | list[float] | None) -> float | list[float] | None:
        for x in (v if isinstance(v, list) else [] if v is None else [v]):
            if x <= 0:
                raise ValueError(f"must be positive, got {x:g}")
        return v


class RobotPlantSpec(Section):
    """A serial manipulator: exactly one of ``robot`` (built-in name), ``dh`` (table) or ``urdf`` (path).

    ``parameters`` override a built-in robot's named parameters (see ``designkit model NAME``; each
    within 1e6 of its SI unit, the model checks its sign); ``convention`` and ``gravity`` (m/s^2,
    base frame, each component within 100) describe a DH table; ``base_link`` and
    ``tip_link`` select the chain of a URDF (``gravity`` also applies).  ``friction`` includes the
    joints' viscous and Coulomb friction in the dynamics; ``motor_inertia`` the reflected rotor
    inertia; ``payload`` a mass carried by a link (part of the true plant); ``limits`` the joints'
    velocity, acceleration and torque limits.  ``consistent_inertia`` (``raise`` or ``nearest``)
    replaces the link inertias that are not physically consistent as published (their principal
    moments break a triangle inequality; :mod:`designkit.models.physical`); default: as published.
    """

    kind: Literal["robot"]
    robot: str | None = Field(default=None, max_length=100)
    parameters: dict[str, Ranged(PARAMETER.low, PARAMETER.high, PARAMETER.unit, base=Finite)] = Field(
        default_factory=dict)
    dh: list[DHLink] | None = Field(default=None, min_length=1, max_length=64)
    convention: Literal["standard", "modified"] = "standard"
    gravity: tuple[Ranged(-100, 100, "m/s^2"), Ranged(-100, 100, "m/s^2"), Ranged(-100, 100, "m/s^2")] = (
        0.0, 0.0, -9.81)
    urdf: str | None = Field(default=None, max_length=4096)
    base_link: str | None = None
    tip_link: str | None = None
    friction: bool = True
    motor_inertia: bool = False
    consistent_inertia: Literal["raise", "nearest"] | None = None
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
        if self.uncertainty is not None:
            self.uncertainty.check_ranges(RobotPlantSpec)
        return self


class ElasticJointPlantSpec(Section):
    """The ROBEL elastic joint (notes appendix B); omitted parameters take the built-in defaults.

    ``J1`` rotor inertia (kg*m^2, 1e-9 to 1e4), ``tau1`` motor time constant (s, 1e-6 to 1e6), ``Km``
    motor static gain ((rad/s)/input, 1e-6 to 1e6), ``KR`` stiffness (N*m/rad, 1e-6 to 1e9), ``R1``,
    ``R2`` transmission ratios (1e-4 to 1e4), ``J2`` link inertia (kg*m^2, 1e-9 to 1e4), ``tau2``
    link time constant (s, 1e-6 to 1e6), ``mgl`` gravity torque amplitude (N*m, 0 to 1e6).
    """

    kind: Literal["elastic_joint"]
    J1: Ranged(1e-9, 1e4, "kg*m^2", base=PositiveFinite) | None = None
    tau1: Ranged(1e-6, 1e6, "s", base=PositiveFinite) | None = None
    Km: Ranged(1e-6, 1e6, "(rad/s)/input", base=PositiveFinite) | None = None
    KR: Ranged(1e-6, 1e9, "N*m/rad", base=PositiveFinite) | None = None
    R1: Ranged(1e-4, 1e4, "", base=PositiveFinite) | None = None
    R2: Ranged(1e-4, 1e4, "", base=PositiveFinite) | None = None
    J2: Ranged(1e-9, 1e4, "kg*m^2", base=PositiveFinite) | None = None
    tau2: Ranged(1e-6, 1e6, "s", base=PositiveFinite) | None = None
    mgl: Ranged(0, 1e6, "N*m", base=NonNegativeFinite) | None = None
    uncertainty: Uncertainty | None = None

    @model_validator(mode="after")
    def _uncertainty_in_range(self) -> ElasticJointPlantSpec:
        if self.uncertainty is not None:
            self.uncertainty.check_ranges(ElasticJointPlantSpec)
        return self

    def given(self) -> dict[str, Any]:
        """The parameters the spec sets (the others keep their defaults)."""
        return {k: v for k, v in self.model_dump(exclude={"kind", "uncertainty"}).items() if v is not None}


COEFFICIENT = Range(-1e12, 1e12, "(in the entry's SI unit)")
"""A numeric entry of a linear plant's polynomial or matrix."""

Entry = Ranged(COEFFICIENT.low, COEFFICIENT.high, COEFFICIENT.unit, base=Finite) | Annotated[str, Field(max_length=200)]
"""A number, or a text over the plant's parameters (``"2*a"``; :mod:`designkit.models.expression`)."""

SignalName = Annotated[str, Field(max_length=100)]


class _LinearPlantSpec(Section):
    """What the two linear plant kinds share: ``parameters`` their entries name, ``units``, ``dt``, ``uncertainty``."""

    parameters: dict[str, Ranged(PARAMETER.low, PARAMETER.high, PARAMETER.unit, base=Finite)] = Field(
        default_factory=dict, max_length=100)
    units: dict[str, Annotated[str, Field(max_length=40)]] = Field(default_factory=dict, max_length=200)
    dt: Ranged(1e-9, 1e6, "s", base=Finite) | None = None
    uncertainty: Uncertainty | None = None

    @field_validator("dt")
    @classmethod
    def _sample_period(cls, v: float | None) -> float | None:
        if v is not None and v <= 0:
            raise ValueError(f"must be positive (the sample period of a discrete-time plant, s), got {v:g}")
        return v

    @model_validator(mode="after")
    def _linear(self) -> _LinearPlantSpec:
        if self.uncertainty is not None:
            self.uncertainty.check_ranges(type(self))
        return self


class TransferFunctionPlantSpec(_LinearPlantSpec):
    """A SISO plant ``output(s)/input(s) = num(s)/den(s)`` (or in ``z`` with ``dt``), strictly proper.

    ``num``, ``den``: coefficients, highest power of ``s`` first, each a number (within 1e12) or a text over
    ``parameters`` (``"Km"``, ``"2*a"``, ``"-(a + 1)/tau"``); no leading zero; ``len(num) < len(den)``, the
    denominator of degree 1 to 20.  ``input``, ``output`` name the signals (default ``u``, ``y``); ``units`` gives
    units by name (the output ``rad``, the input and parameters ``1`` by default).  ``dt`` (s, 1e-9 to 1e6) makes it
    discrete-time: ``num(z)/den(z)``, highest power of ``z`` first, ``dt`` the sample period.  Realised in
    observability canonical form, ``y = x1``
    (:mod:`designkit.models.linear_plant`).
    """

    kind: Literal["transfer_function"]
    num: list[Entry] = Field(min_length=1, max_length=21)
    den: list[Entry] = Field(min_length=1, max_length=21)
    input: SignalName = "u"
    output: SignalName = "y"


class StateSpacePlantSpec(_LinearPlantSpec):
    """A plant ``x' = A x + B u``, ``y = C x + D u`` (or ``x[k+1] = A x[k] + B u[k]`` with ``dt``).

    ``A`` (n x n, n at most 20), ``B`` (n x m), ``C`` (q x n), ``D`` (q x m, default zero): lists of rows whose
    entries are numbers (within 1e12) or texts over ``parameters``.  ``states``, ``inputs``, ``outputs`` name the
    signals (defaults ``x1..``, ``u``/``u1..``, ``y``/``y1..``); ``units`` gives units by name.  The first output is
    the tracked position: it must measure something and have no direct feedthrough (``D[0] = 0``).  ``dt`` (s, 1e-9
    to 1e6) makes it discrete-time: ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k] + D u[k]``, ``dt`` the sample
    period.
    """

    kind: Literal["state_space"]
    A: list[list[Entry]] = Field(min_length=1, max_length=20)
    B: list[list[Entry]] = Field(min_length=1, max_length=20)
    C: list[list[Entry]] = Field(min_length=1, max_length=20)
    D: list[list[Entry]] | None = Field(default=None, max_length=20)
    states: list[SignalName] | None = Field(default=None, max_length=20)
    inputs: list[SignalName] | None = Field(default=None, max_length=20)
    outputs: list[SignalName] | None = Field(default=None, max_length=20)


def linear_order(section: Any) -> int | None:
    """The number of states of a ``transfer_function`` or ``state_space`` section (None for another kind)."""
    if section.kind == "transfer_function":
        return len(section.den) - 1
    if section.kind == "state_space":
        return len(section.A)
    return None


PlantSpec = Annotated[LinkPlantSpec | RobotPlantSpec | ElasticJointPlantSpec | TransferFunctionPlantSpec
                      | StateSpacePlantSpec, Field(discriminator="kind")]
"""The ``plant`` section: one of the plant kinds above."""
