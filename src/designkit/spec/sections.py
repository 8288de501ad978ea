"""The ``requirements``, ``simulation`` and ``numerics`` sections of a spec.

Values that can differ between joints (``simulation.step``, element levels, perturbations,
trajectory amplitudes, anti-windup levels) are :data:`~designkit.spec.fields.PerJoint`: one
number for every joint or a list with one per joint; the list length is checked against the
plant when it is built (``simulation.step: needs one value per joint (2), got 3``).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from designkit.spec.fields import Finite, NonNegativeFinite, PerJoint, PositiveFinite, Section

__all__ = [
    "AntiWindup", "CircleTrajectory", "DeadZone", "JOINT_TRAJECTORIES", "LineTrajectory", "Noise", "Nonlinearity",
    "Numerics", "Perturbation", "Quantizer", "QuinticTrajectory", "Relay", "Requirements", "Saturation",
    "Simulation", "SineTrajectory", "Trajectory", "TrapezoidalTrajectory", "ViaPointsTrajectory",
]


def _positive(value: float | list[float]) -> float | list[float]:
    values = value if isinstance(value, list) else [value]
    for v in values:
        if v <= 0:
            raise ValueError(f"must be positive, got {v:g}")
    return value


def _non_negative(value: float | list[float]) -> float | list[float]:
    values = value if isinstance(value, list) else [value]
    for v in values:
        if v < 0:
            raise ValueError(f"must be non-negative, got {v:g}")
    return value


# ----------------------------------------------------------------------------- requirements


class Requirements(Section):
    """Time-domain requirements, each holding for every joint.

    overshoot (%), settling_time (s, to the ``settling_band``), rise_time (s, 10-90 %),
    steady_state_error (same unit as the positions, absolute), tracking_error (largest |q - qD| over
    the run, rad), max_control (peak |u| of every input, N*m, one value or one per input).
    """

    overshoot: NonNegativeFinite | None = None
    settling_time: PositiveFinite | None = None
    rise_time: PositiveFinite | None = None
    steady_state_error: NonNegativeFinite | None = None
    tracking_error: PositiveFinite | None = None
    max_control: PerJoint | None = None
    settling_band: float = Field(default=0.02, gt=0, lt=1)

    _check_control = field_validator("max_control")(lambda v: v if v is None else _positive(v))


# ----------------------------------------------------------------------------- nonlinear elements


class Saturation(Section):
    """``u_applied = clip(u, -limit, limit)`` (N*m, per input)."""

    kind: Literal["saturation"]
    limit: PerJoint

    _check = field_validator("limit")(_positive)


class DeadZone(Section):
    """Zero output for ``|u| <= width``, ``u - sign(u) width`` beyond (N*m, per input)."""

    kind: Literal["dead_zone"]
    width: PerJoint

    _check = field_validator("width")(_positive)


class Relay(Section):
    """Relay with hysteresis: ``+amplitude`` once ``u > hysteresis``, ``-amplitude`` once ``u < -hysteresis``."""

    kind: Literal["relay"]
    amplitude: PerJoint
    hysteresis: PerJoint = 0.0

    _check_amplitude = field_validator("amplitude")(_positive)
    _check_hysteresis = field_validator("hysteresis")(_non_negative)


class Quantizer(Section):
    """``u_applied = step * round(u / step)`` (N*m, per input)."""

    kind: Literal["quantizer"]
    step: PerJoint

    _check = field_validator("step")(_positive)


Nonlinearity = Annotated[Saturation | DeadZone | Relay | Quantizer, Field(discriminator="kind")]


class Noise(Section):
    """White Gaussian measurement noise on every measured state, seeded.

    ``std`` is one standard deviation for every state or a list with one per state (state units).
    """

    std: PerJoint = 0.0
    seed: int = Field(default=0, ge=0)

    _check = field_validator("std")(_non_negative)


class Perturbation(Section):
    """Input-equivalent perturbation (the plant's disturbances, e.g. ``xi`` N*m): ``value`` from ``time`` on."""

    value: PerJoint
    time: NonNegativeFinite = 0.0


class AntiWindup(Section):
    """Limit the integral action.

    ``threshold``: integrate only while ``|x1 - xD| <= value``; ``saturation``: clamp ``|K3 * integral| <= value``.
    """

    kind: Literal["threshold", "saturation"]
    value: PerJoint

    _check = field_validator("value")(_positive)


# ----------------------------------------------------------------------------- trajectories


class QuinticTrajectory(Section):
    """Rest-to-rest quintic move of ``amplitude`` (rad, per joint) over ``duration`` (s)."""

    kind: Literal["quintic"]
    amplitude: PerJoint = 1.0
    duration: PositiveFinite = 1.0


class SineTrajectory(Section):
    """``amplitude sin(2 pi frequency t)`` about the initial position (rad per joint, Hz)."""

    kind: Literal["sine"]
    amplitude: PerJoint = 1.0
    frequency: PositiveFinite = 1.0


class TrapezoidalTrajectory(Section):
    """Trapezoidal-velocity move of ``amplitude`` (per joint), all joints synchronised.

    Within ``max_velocity`` (rad/s) and ``max_acceleration`` (rad/s^2) per joint: minimum time
    when ``duration`` is omitted; with ``duration`` (s), the lowest acceleration that meets it.
    """

    kind: Literal["trapezoidal"]
    amplitude: PerJoint = 1.0
    max_velocity: PerJoint
    max_acceleration: PerJoint
    duration: PositiveFinite | None = None

    _check = field_validator("max_velocity", "max_acceleration")(_positive)


class ViaPointsTrajectory(Section):
    """A C2 path from rest through displacements ``points`` (per joint) at ``times`` (s), at rest at the last."""

    kind: Literal["via_points"]
    times: list[PositiveFinite] = Field(min_length=1, max_length=1000)
    points: list[PerJoint] = Field(min_length=1, max_length=1000)

    @model_validator(mode="after")
    def _aligned(self) -> ViaPointsTrajectory:
        if len(self.times) != len(self.points):
            raise ValueError(f"points: needs one entry per time ({len(self.times)}), got {len(self.points)}")
        if any(b <= a for a, b in zip(self.times, self.times[1:], strict=False)):
            raise ValueError("times: must be strictly increasing")
        return self


Point3 = Annotated[list[Finite], Field(min_length=3, max_length=3)]
"""A point or direction in the robot's base frame (m): ``[x, y, z]``."""


class LineTrajectory(Section):
    """Straight line of the end effector, rest to rest with a quintic time law, orientation held.

    From the end effector's position at ``simulation.initial_position`` to ``to`` (m, base frame),
    or by ``displacement`` (m), over ``duration`` (s).  For task-space controllers (resolved
    acceleration).
    """

    kind: Literal["line"]
    to: Point3 | None = None
    displacement: Point3 | None = None
    duration: PositiveFinite = 1.0

    @model_validator(mode="after")
    def _one_end(self) -> LineTrajectory:
        if (self.to is None) == (self.displacement is None):
            raise ValueError("give either to or displacement")
        return self


class CircleTrajectory(Section):
    """Circle of the end effector about the axis through ``center`` along ``normal`` (base frame, m),
    rest to rest with a quintic time law on the angle, orientation held.

    It starts at the end effector's position at ``simulation.initial_position`` (the radius is its
    distance from the axis) and turns ``turns`` times (positive: counter-clockwise about ``normal``)
    over ``duration`` (s).  For task-space controllers (resolved acceleration).
    """

    kind: Literal["circle"]
    center: Point3
    normal: Point3 = Field(default_factory=lambda: [0.0, 0.0, 1.0])
    turns: Finite = 1.0
    duration: PositiveFinite = 1.0

    @field_validator("normal")
    @classmethod
    def _direction(cls, v: list[float]) -> list[float]:
        if sum(x * x for x in v) < 1e-24:
            raise ValueError("must be a non-zero vector")
        return v


Trajectory = Annotated[QuinticTrajectory | SineTrajectory | TrapezoidalTrajectory | ViaPointsTrajectory
                       | LineTrajectory | CircleTrajectory, Field(discriminator="kind")]

JOINT_TRAJECTORIES = ("quintic", "sine", "trapezoidal", "via_points")
"""Trajectory kinds given per joint; the others (``line``, ``circle``) are end-effector paths."""


class Simulation(Section):
    """Closed-loop simulation scenario on the full nonlinear plant.

    duration (s), step (commanded displacement of each joint from its initial position, rad),
    initial_position (rad per joint, default 0), dt (integration step, s; default from the
    fastest closed-loop pole), delay (s), sampling_period (s, 0 = continuous).
    """

    duration: PositiveFinite | None = None
    step: PerJoint = 1.0
    initial_position: PerJoint | None = None
    dt: PositiveFinite | None = None
    nonlinearity: Nonlinearity | None = None
    delay: NonNegativeFinite = 0.0
    sampling_period: NonNegativeFinite = 0.0
    noise: Noise | None = None
    perturbation: Perturbation | None = None
    anti_windup: AntiWindup | None = None
    trajectory: Trajectory | None = None


class Numerics(Section):
    """How the numbers are computed (not what is designed).

    integrator: ``rk4`` (fixed step, default) or ``cvodes`` (CasADi's variable-step BDF, for
    stiff plants such as the elastic joint) with tolerances ``rtol``, ``atol``; ``compile``:
    ``auto`` (compile the simulation step to C when it is cached or pays for itself), ``always``
    or ``never``; ``solver``: the cvxpy solver of the LMIs and LPs.
    """

    integrator: Literal["rk4", "cvodes"] = "rk4"
    compile: Literal["auto", "always", "never"] = "auto"
    rtol: float = Field(default=1e-8, gt=0, lt=1)
    atol: float = Field(default=1e-10, gt=0, lt=1)
    solver: Literal["CLARABEL", "SCS"] = "CLARABEL"

