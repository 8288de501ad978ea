"""The ``requirements``, ``simulation`` and ``numerics`` sections of a spec.

Values that can differ between joints (``simulation.step``, element levels, perturbations,
trajectory amplitudes, anti-windup levels) are :data:`~designkit.spec.fields.PerJoint`: one
number for every joint or a list with one per joint; the list length is checked against the
plant when it is built (``simulation.step: needs one value per joint (2), got 3``).

Every number has a physically meaningful range declared next to its field
(:mod:`designkit.spec.ranges`; the README's table lists them): durations and instants 1e-6 s to
1e9 s (trajectory moves from 1e-3 s), ``dt`` 1e-9 s to 1e3 s, ``delay`` and ``sampling_period`` 0
or 1e-6 s to 1e3 s, positions and amplitudes within 100 rad (or m), torque levels 1e-6 to 1e6 N*m,
seeds 0 to 2**32 - 1.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import ConfigDict, Field, field_validator, model_validator

from designkit.spec.fields import NonNegativeFinite, PositiveFinite, Section
from designkit.spec.ranges import ANGLE, DURATION, TORQUE, Ranged, RangedInt, RangedPerJoint

__all__ = [
    "Actuator", "AntiWindup", "CircleTrajectory", "DeadZone", "Implementation", "JOINT_TRAJECTORIES", "LineTrajectory",
    "MultisineTrajectory", "Noise", "Nonlinearity", "Numerics", "Perturbation", "PlantChange", "PrbsReference",
    "Quantizer", "QuinticTrajectory", "Relay", "Requirements", "STEP_REFERENCES", "Saturation", "Simulation",
    "SineTrajectory", "SquareReference", "TASK_PATHS", "Trajectory", "TrapezoidalTrajectory", "ViaPointsTrajectory",
]


_TIME = (DURATION.low, DURATION.high, DURATION.unit)
"""A duration or an instant: 1e-6 s to 1e9 s."""
_MOVE = (1e-3, DURATION.high, "s")
"""The duration of a reference move: 1e-3 s to 1e9 s."""
_TORQUE = (TORQUE.low, TORQUE.high, TORQUE.unit)
"""A torque level of an element or a limit: 1e-6 to 1e6 N*m."""
_POSITION = (-100.0, 100.0, "rad or m")
"""A joint position, displacement or amplitude: within 100 rad (or m for a prismatic joint)."""
_HOLD = (1e-6, 1e3, "s")
"""A delay or a sampling period when not 0: 1e-6 s to 1e3 s."""



# ----------------------------------------------------------------------------- requirements


class Requirements(Section):
    """Time-domain requirements, each holding for every joint.

    overshoot (%, 0 to 1000), settling_time (s, to the ``settling_band``; 1e-6 to 1e9), rise_time
    (s, 10-90 %; 1e-6 to 1e9), steady_state_error (same unit as the positions, absolute; 0 to 100),
    tracking_error (largest |q - qD| over the run, rad or m; above 0, at most 100), max_control
    (peak |u| of every input, N*m, one value or one per input; 1e-6 to 1e6), settling_band (a
    fraction of the step, strictly between 0 and 1); and the classical margins of the loop broken at
    every plant input (the ``loop_margins`` check, which they make part of the verdict):
    gain_margin (dB, 0 to 100), phase_margin (deg, 0 to 180), modulus_margin (the smallest
    ``|1 + L(jw)|``, 0 to 1); and how the command may switch (the ``command_switching`` check,
    :mod:`designkit.verification.switching`): max_reversal_rate (reversals of every commanded input per
    second of the run, 1/s, 0 to 1e9), max_command_variation (total variation of every commanded input per
    second of the run, the input's unit per second, N*m/s or V/s; above 0, at most 1e12); and
    max_chatter_amplitude (the switching families' ``chattering`` check: half the peak-to-peak commanded input
    once the loop has settled into its chatter, the input's unit, N*m or V; above 0, at most 1e6).
    """

    overshoot: Ranged(0, 1000, "%", base=NonNegativeFinite) | None = None
    settling_time: Ranged(*_TIME, base=PositiveFinite) | None = None
    rise_time: Ranged(*_TIME, base=PositiveFinite) | None = None
    steady_state_error: Ranged(0, 100, "rad or m", base=NonNegativeFinite) | None = None
    tracking_error: Ranged(0, 100, "rad or m", low_open=True, base=PositiveFinite) | None = None
    max_control: RangedPerJoint(*_TORQUE) | None = None
    settling_band: Ranged(0, 1, "", low_open=True, high_open=True) = 0.02
    gain_margin: Ranged(0, 100, "dB", base=NonNegativeFinite) | None = None
    phase_margin: Ranged(0, 180, "deg", base=NonNegativeFinite) | None = None
    modulus_margin: Ranged(0, 1, "", base=NonNegativeFinite) | None = None
    max_reversal_rate: Ranged(0, 1e9, "1/s", base=NonNegativeFinite) | None = None
    max_command_variation: Ranged(0, 1e12, "unit/s", low_open=True, base=PositiveFinite) | None = None
    max_chatter_amplitude: Ranged(0, 1e6, "N*m or V", low_open=True, base=PositiveFinite) | None = None


# ----------------------------------------------------------------------------- nonlinear elements


class Saturation(Section):
    """``u_applied = clip(u, -limit, limit)`` (N*m, per input; 1e-6 to 1e6)."""

    kind: Literal["saturation"]
    limit: RangedPerJoint(*_TORQUE)


class DeadZone(Section):
    """Zero output for ``|u| <= width``, ``u - sign(u) width`` beyond (N*m, per input; 1e-6 to 1e6)."""

    kind: Literal["dead_zone"]
    width: RangedPerJoint(*_TORQUE)


class Relay(Section):
    """Relay with hysteresis: ``+amplitude`` once ``u > hysteresis``, ``-amplitude`` once ``u < -hysteresis``
    (N*m, per input; amplitude 1e-6 to 1e6, hysteresis 0 to 1e6)."""

    kind: Literal["relay"]
    amplitude: RangedPerJoint(*_TORQUE)
    hysteresis: RangedPerJoint(0, TORQUE.high, TORQUE.unit) = 0.0


class Quantizer(Section):
    """``u_applied = step * round(u / step)`` (N*m, per input; 1e-6 to 1e6)."""

    kind: Literal["quantizer"]
    step: RangedPerJoint(*_TORQUE)


Nonlinearity = Annotated[Saturation | DeadZone | Relay | Quantizer, Field(discriminator="kind")]


class Noise(Section):
    """White Gaussian measurement noise on every measured state, seeded.

    ``std`` is one standard deviation for every state or a list with one per state (state units, 0 to
    100); ``seed`` the generator's seed (0 to 2**32 - 1).
    """

    std: RangedPerJoint(0, 100, "state units") = 0.0
    seed: RangedInt(0, 2**32 - 1) = 0


class Perturbation(Section):
    """Input-equivalent perturbation (the plant's disturbances, e.g. ``xi`` N*m, within 1e6): ``value`` from
    ``time`` on (s, 0 to 1e9)."""

    value: RangedPerJoint(-TORQUE.high, TORQUE.high, TORQUE.unit)
    time: Ranged(0, DURATION.high, "s", base=NonNegativeFinite) = 0.0


class PlantChange(Section):
    """A step change of the true plant's parameters during the run: from ``time`` (s, 0 to 1e9) on, the named
    parameters take the given ``values`` (``{Km: 3.0}``, ``{tau: 0.8}``; any named plant parameter, each in its
    own range), the others keep theirs.  The controller is not told (what an adaptive law must cope with)."""

    time: Ranged(0, DURATION.high, "s", base=NonNegativeFinite)
    values: dict[str, Ranged(-1e6, 1e6, "(in the parameter's SI unit)")] = Field(min_length=1, max_length=100)


class AntiWindup(Section):
    """Limit the integral action.

    ``threshold``: integrate only while ``|x1 - xD| <= value`` (rad or m); ``saturation``: clamp
    ``|K3 * integral| <= value`` (N*m); 1e-6 to 1e6 either way.
    """

    kind: Literal["threshold", "saturation"]
    value: RangedPerJoint(1e-6, 1e6, "rad or m (threshold), N*m (saturation)")


# ----------------------------------------------------------------------------- trajectories


class QuinticTrajectory(Section):
    """Rest-to-rest quintic move of ``amplitude`` (rad, per joint; within 100) over ``duration`` (s, 1e-3 to 1e9)."""

    kind: Literal["quintic"]
    amplitude: RangedPerJoint(*_POSITION) = 1.0
    duration: Ranged(*_MOVE, base=PositiveFinite) = 1.0


class SineTrajectory(Section):
    """``offset + amplitude sin(2 pi frequency t + phase)`` about the initial position (rad per joint, within 100;
    Hz, 1e-6 to 1e3; ``offset`` rad per joint, within 100, default 0; ``phase`` rad per joint, within one turn
    either way, default 0).  ``offset = amplitude``, ``phase = -pi/2`` is ``amplitude (1 - cos 2 pi frequency t)``,
    which starts at the initial position at rest."""

    kind: Literal["sine"]
    amplitude: RangedPerJoint(*_POSITION) = 1.0
    frequency: Ranged(1e-6, 1e3, "Hz", base=PositiveFinite) = 1.0
    offset: RangedPerJoint(*_POSITION) = 0.0
    phase: RangedPerJoint(ANGLE.low, ANGLE.high, "rad") = 0.0


class MultisineTrajectory(Section):
    """A sum of sines per joint from the initial position: joint ``j`` of ``n`` follows
    ``q0 + (amplitude/K) sum_i (sin(2 pi (j + i n) t/period + phi_i) - sin phi_i)``, ``i = 0 .. K - 1``,
    ``K = harmonics`` (interleaved harmonics of ``1/period``: no two joints share a frequency; Schroeder's phases
    ``phi_i = -pi i (i - 1)/K``), swinging within ``amplitude`` of its centre (rad per joint, within 100; s, 1e-3 to
    1e9; 1 to 50 harmonics).  A smooth persistently exciting reference (identification)."""

    kind: Literal["multisine"]
    amplitude: RangedPerJoint(*_POSITION) = 1.0
    period: Ranged(*_MOVE, base=PositiveFinite) = 10.0
    harmonics: RangedInt(1, 50) = 3


class TrapezoidalTrajectory(Section):
    """Trapezoidal-velocity move of ``amplitude`` (per joint), all joints synchronised.

    Within ``max_velocity`` (rad/s, 1e-6 to 1e6) and ``max_acceleration`` (rad/s^2, 1e-6 to 1e6) per
    joint: minimum time when ``duration`` is omitted; with ``duration`` (s, 1e-3 to 1e9), the lowest
    acceleration that meets it.  ``amplitude`` within 100 rad (or m).
    """

    kind: Literal["trapezoidal"]
    amplitude: RangedPerJoint(*_POSITION) = 1.0
    max_velocity: RangedPerJoint(1e-6, 1e6, "rad/s")
    max_acceleration: RangedPerJoint(1e-6, 1e6, "rad/s^2")
    duration: Ranged(*_MOVE, base=PositiveFinite) | None = None


class ViaPointsTrajectory(Section):
    """A C2 path from rest through displacements ``points`` (per joint, within 100 rad or m) at ``times``
    (s, 1e-3 to 1e9, strictly increasing), at rest at the last."""

    kind: Literal["via_points"]
    times: list[Ranged(*_MOVE, base=PositiveFinite)] = Field(min_length=1, max_length=1000)
    points: list[RangedPerJoint(*_POSITION)] = Field(min_length=1, max_length=1000)

    @model_validator(mode="after")
    def _aligned(self) -> ViaPointsTrajectory:
        if len(self.times) != len(self.points):
            raise ValueError(f"points: needs one entry per time ({len(self.times)}), got {len(self.points)}")
        if any(b <= a for a, b in zip(self.times, self.times[1:], strict=False)):
            raise ValueError("times: must be strictly increasing")
        return self


Point3 = Annotated[list[Ranged(-100, 100, "m")], Field(min_length=3, max_length=3)]
"""A point or direction in the robot's base frame (m): ``[x, y, z]``, each within 100."""


class LineTrajectory(Section):
    """Straight line of the end effector, rest to rest with a quintic time law, orientation held.

    From the end effector's position at ``simulation.initial_position`` to ``to`` (m, base frame),
    or by ``displacement`` (m), over ``duration`` (s, 1e-3 to 1e9).  For task-space controllers (resolved
    acceleration).
    """

    kind: Literal["line"]
    to: Point3 | None = None
    displacement: Point3 | None = None
    duration: Ranged(*_MOVE, base=PositiveFinite) = 1.0

    @model_validator(mode="after")
    def _one_end(self) -> LineTrajectory:
        if (self.to is None) == (self.displacement is None):
            raise ValueError("give either to or displacement")
        return self


class CircleTrajectory(Section):
    """Circle of the end effector about the axis through ``center`` along ``normal`` (base frame, m),
    rest to rest with a quintic time law on the angle, orientation held.

    It starts at the end effector's position at ``simulation.initial_position`` (the radius is its
    distance from the axis) and turns ``turns`` times (positive: counter-clockwise about ``normal``;
    within 100) over ``duration`` (s, 1e-3 to 1e9).  For task-space controllers (resolved acceleration).
    """

    kind: Literal["circle"]
    center: Point3
    normal: Point3 = Field(default_factory=lambda: [0.0, 0.0, 1.0])
    turns: Ranged(-100, 100, "turns") = 1.0
    duration: Ranged(*_MOVE, base=PositiveFinite) = 1.0

    @field_validator("normal")
    @classmethod
    def _direction(cls, v: list[float]) -> list[float]:
        if sum(x * x for x in v) < 1e-24:
            raise ValueError("must be a non-zero vector")
        return v


class SquareReference(Section):
    """A square wave of positions about the initial position: ``q0 + amplitude`` for the first half of every
    ``period``, ``q0 - amplitude`` for the second (rad per joint, within 100; s, 1e-3 to 1e9); zero velocity and
    acceleration.  For servo controllers (and the persistent excitation an adaptive law needs)."""

    kind: Literal["square"]
    amplitude: RangedPerJoint(*_POSITION) = 1.0
    period: Ranged(*_MOVE, base=PositiveFinite) = 4.0


class PrbsReference(Section):
    """A pseudo-random binary sequence of positions about the initial position: ``q0 +- amplitude`` (rad per
    joint, within 100), switching at multiples of ``bit`` (s, 1e-3 to 1e9) as the maximal-length shift register
    of ``order`` stages (3 to 16; period ``2^order - 1`` bits) started from a state drawn from ``seed`` (0 to
    2**32 - 1).  For servo controllers: the persistent excitation of an adaptive or identifying law."""

    kind: Literal["prbs"]
    amplitude: RangedPerJoint(*_POSITION) = 1.0
    bit: Ranged(*_MOVE, base=PositiveFinite) = 1.0
    order: RangedInt(3, 16) = 7
    seed: RangedInt(0, 2**32 - 1) = 0


Trajectory = Annotated[QuinticTrajectory | SineTrajectory | TrapezoidalTrajectory | ViaPointsTrajectory
                       | LineTrajectory | CircleTrajectory | SquareReference | PrbsReference | MultisineTrajectory,
                       Field(discriminator="kind")]

JOINT_TRAJECTORIES = ("quintic", "sine", "trapezoidal", "via_points")
"""Smooth trajectory kinds given per joint (a tracking controller follows them with their velocity and
acceleration); ``line`` and ``circle`` are end-effector paths; ``square`` and ``prbs`` piecewise constant
positions (for servos)."""
STEP_REFERENCES = ("step", "square", "prbs")
"""The references a servo follows: ``simulation.step``, or a piecewise-constant ``simulation.trajectory``."""
TASK_PATHS = ("line", "circle")
"""End-effector paths (task-space controllers)."""


class Simulation(Section):
    """Closed-loop simulation scenario on the full nonlinear plant.

    duration (s, 1e-6 to 1e9), step (commanded displacement of each joint from its initial position,
    rad, within 100), initial_position (rad per joint, within 100; default 0), dt (integration step,
    s, 1e-9 to 1e3; default from the fastest closed-loop pole), delay (s, 0 or 1e-6 to 1e3),
    sampling_period (s, 0 = continuous, else 1e-6 to 1e3), trajectory (the reference when not a step:
    a joint trajectory, an end-effector path, a square wave or a PRBS; each controller family says which
    it follows), plant_change (a step change of the true plant's parameters during the run).
    """

    duration: Ranged(*_TIME, base=PositiveFinite) | None = None
    step: RangedPerJoint(*_POSITION) = 1.0
    initial_position: RangedPerJoint(*_POSITION) | None = None
    dt: Ranged(1e-9, 1e3, "s", base=PositiveFinite) | None = None
    nonlinearity: Nonlinearity | None = None
    delay: Ranged(*_HOLD, zero=True, base=NonNegativeFinite) = 0.0
    sampling_period: Ranged(*_HOLD, zero=True, base=NonNegativeFinite) = 0.0
    noise: Noise | None = None
    perturbation: Perturbation | None = None
    plant_change: PlantChange | None = None
    anti_windup: AntiWindup | None = None
    trajectory: Trajectory | None = None

    def still_reference(self) -> str | None:
        """The key path of a reference that does not move -- ``simulation.step`` all 0 without a trajectory, or
        a trajectory whose ``amplitude`` is 0 on every joint -- or None when it moves (or has no amplitude)."""
        if self.trajectory is None:
            key, value = "simulation.step", self.step
        elif hasattr(self.trajectory, "amplitude"):
            key, value = "simulation.trajectory.amplitude", self.trajectory.amplitude
        else:
            return None
        values = value if isinstance(value, list | tuple) else [value]
        return key if all(float(v) == 0.0 for v in values) else None


class Actuator(Section):
    """The actuator between the commanded and the applied input, on every input: a saturation at ``limit``
    (the input's unit, N*m or V, per input; 1e-6 to 1e6) followed by a first-order lag of ``bandwidth``
    (its corner frequency, rad/s, per input; 1e-3 to 1e9): ``u_a' = bandwidth (clip(u, -limit, limit) - u_a)``.
    Either may be left out (no saturation, or no lag)."""

    limit: RangedPerJoint(*_TORQUE) | None = None
    bandwidth: RangedPerJoint(1e-3, 1e9, "rad/s") | None = None


class Implementation(Section):
    """The controller as it will run: what the verdict is on when it is given.

    sampling_period (s, 1e-6 to 1e3): the law computed once per period and its command held in between;
    delay (s, 0 or 1e-6 to 1e3): the computation delay between the sample and the command reaching the
    actuator; quantization (the measured signals' resolution, in each state's unit, one for every measured
    state or one per state; 1e-12 to 100): ``y = step round(x / step)``; actuator: a saturation and a
    first-order lag on each input (:class:`Actuator`). Each must be shorter than the run; a sampling period
    and a delay are bounded by the run's duration when the simulation is built.
    """

    sampling_period: Ranged(*_HOLD, base=PositiveFinite) | None = None
    delay: Ranged(*_HOLD, zero=True, base=NonNegativeFinite) = 0.0
    quantization: RangedPerJoint(1e-12, 100, "state units") | None = None
    actuator: Actuator | None = None


class Numerics(Section):
    """How the numbers are computed (not what is designed).

    integrator: ``rk4`` (fixed step), ``cvodes`` (CasADi's variable-step CVODES, for
    stiff plants such as the elastic joint: over the whole grid in one call on a smooth loop, inside each step
    on a held one) or ``dopri5`` (compiled Dormand-Prince 5(4) with error control
    and dense output, for smooth continuous loops; left out, the simulator picks dopri5 for a smooth loop,
    rk4 for a held, sampled or noisy one, cvodes for a stiff one) with tolerances ``rtol`` (1e-14 to 0.1)
    and ``atol`` (1e-20 to 1, state units; dopri5 defaults 1e-10 and 1e-12 when they are left out);
    ``cvodes_method``: ``auto`` (BDF for a stiff loop, Adams for one that is not), ``adams`` or ``bdf``
    (CVODES over the whole grid; the per-step CVODES of a held loop is BDF);
    ``compile``:
    ``auto`` (compile the simulation step to C when it is cached or pays for itself), ``always``
    or ``never``; ``solver``: the cvxpy solver of the LMIs and LPs.
    """

    integrator: Literal["rk4", "cvodes", "dopri5"] = "rk4"
    cvodes_method: Literal["auto", "adams", "bdf"] = "auto"
    compile: Literal["auto", "always", "never"] = "auto"
    rtol: Ranged(1e-14, 0.1, "") = 1e-8
    atol: Ranged(1e-20, 1.0, "state units") = 1e-10
    solver: Literal["CLARABEL", "SCS"] = "CLARABEL"



class Studies(Section):
    """The ``studies`` section: the work each study may spend (``budget``, s, 0.01 to 3600; default 15) and, under
    a study's name, that study's settings (``gains: {knobs: [K1], factors: [0.5, 2]}``).

    The studies are discovered above this layer (:mod:`designkit.studies`), so their settings are kept as given
    here and validated, with their key paths, by :func:`designkit.studies.validate` before anything is run.
    """

    model_config = ConfigDict(extra="allow", frozen=True, allow_inf_nan=False, str_strip_whitespace=True)

    budget: Ranged(0.01, 3600, "s", base=PositiveFinite) | None = None
