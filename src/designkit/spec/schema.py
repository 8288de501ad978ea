"""The spec format: one pydantic model per spec section.

Every model forbids unknown keys and is frozen.  Numbers must be finite.  A
spec describes a plant, a controller to synthesise, optional performance
requirements and an optional simulation scenario.  ``designkit schema``
prints the JSON Schema generated from these models.
"""

from __future__ import annotations

import cmath
import math
from typing import Annotated, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    field_validator,
    model_validator,
)


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, str_strip_whitespace=True)


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise ValueError(f"must be finite, got {value}")
    return value


def _parse_pole(value: object) -> complex:
    """Accept a real number or a string such as ``"-2+3j"``; return a complex number."""
    if isinstance(value, bool):
        raise ValueError(f"must be a number or a complex string like '-2+3j', got {value!r}")
    if isinstance(value, int | float):
        return complex(float(value), 0.0)
    if isinstance(value, complex):
        return value
    if isinstance(value, str):
        try:
            return complex(value.replace(" ", "").replace("i", "j"))
        except ValueError:
            raise ValueError(f"must be a number or a complex string like '-2+3j', got {value!r}") from None
    raise ValueError(f"must be a number or a complex string like '-2+3j', got {value!r}")


def _stable_pole(p: complex) -> complex:
    if not (cmath.isfinite(p)):
        raise ValueError(f"must be finite, got {p}")
    if p.real >= 0.0:
        raise ValueError(f"must have negative real part, got {_fmt(p)}")
    return p


def _fmt(p: complex) -> str:
    return f"{p.real:g}" if p.imag == 0 else f"{p.real:g}{p.imag:+g}j"


Finite = Annotated[float, AfterValidator(_finite)]
PositiveFinite = Annotated[float, Field(gt=0), AfterValidator(_finite)]
NonNegativeFinite = Annotated[float, Field(ge=0), AfterValidator(_finite)]
Pole = Annotated[complex, BeforeValidator(_parse_pole), AfterValidator(_stable_pole)]


def check_conjugates(poles: list[complex]) -> None:
    """Raise ``ValueError`` naming the first complex pole whose conjugate is missing."""
    remaining = list(poles)
    while remaining:
        p = remaining.pop(0)
        if p.imag == 0:
            continue
        match = next((k for k, r in enumerate(remaining) if abs(r - p.conjugate()) <= 1e-12 * (1 + abs(p))), None)
        if match is None:
            raise ValueError(f"complex pole {_fmt(p)} has no conjugate {_fmt(p.conjugate())} in the list")
        remaining.pop(match)


# ----------------------------------------------------------------------------- plant


class Uncertainty(_Section):
    """A box of plant parameters over which robustness is checked.

    Each entry is ``[low, high]``; ``grid`` is the number of grid points per axis.
    """

    Km: tuple[PositiveFinite, PositiveFinite] | None = None
    tau: tuple[PositiveFinite, PositiveFinite] | None = None
    grid: int = Field(default=21, ge=2, le=1001)

    @field_validator("Km", "tau")
    @classmethod
    def _ordered(cls, v: tuple[float, float] | None) -> tuple[float, float] | None:
        if v is not None and v[0] > v[1]:
            raise ValueError(f"interval must be [low, high] with low <= high, got [{v[0]:g}, {v[1]:g}]")
        return v


class LinkPlantSpec(_Section):
    """Simplified link model ``x1' = x2, x2' = -x2/tau + (Km/tau)(u + xi)``.

    ``Km`` is the link gain ((rad/s)/(N*m)), ``tau`` the time constant (s).
    """

    kind: Literal["link"]
    Km: PositiveFinite
    tau: PositiveFinite
    uncertainty: Uncertainty | None = None


# ----------------------------------------------------------------------------- controller


class _PoleZeroController(_Section):
    poles: list[Pole] | None = Field(
        default=None,
        description="Closed-loop poles (1/s): three values, real or a complex-conjugate pair plus a real pole.",
    )
    third_pole_factor: PositiveFinite = Field(
        default=5.0,
        description="When poles come from requirements: the real pole is placed this many times further "
        "left than the real part of the dominant pair.",
    )
    design_margin: float = Field(
        default=0.1, ge=0, lt=1,
        description="When poles come from requirements: the derived pair meets overshoot and settling time "
        "tightened by this fraction, so the verified loop keeps a margin.",
    )

    @field_validator("poles")
    @classmethod
    def _three_conjugate(cls, v: list[complex] | None) -> list[complex] | None:
        if v is None:
            return v
        if len(v) != 3:
            raise ValueError(f"must list exactly 3 poles, got {len(v)}")
        check_conjugates(v)
        return v


class PidServoSpec(_PoleZeroController):
    """PID position servo ``u = -K1 (x1 - xD) - K2 x2 - K3 int(x1 - xD) + K3 K4 xD``.

    ``zero`` (1/s) is the closed-loop zero of ``x1/xD``; when omitted, ``K4 = 0`` and the zero
    falls at ``-K3/K1`` (reported), or, with poles derived from requirements, on the third pole.
    """

    kind: Literal["pid_servo"]
    zero: Finite | None = None

    @field_validator("zero")
    @classmethod
    def _lhp_zero(cls, v: float | None) -> float | None:
        if v is not None and v >= 0:
            raise ValueError(f"must be negative (left half plane), got {v:g}")
        return v

    @model_validator(mode="after")
    def _zero_not_pole(self) -> PidServoSpec:
        if self.zero is not None and self.poles is not None:
            for p in self.poles:
                if abs(p - self.zero) <= 1e-9 * (1 + abs(p)):
                    raise ValueError(f"zero: must differ from every pole, got {self.zero:g} equal to a pole")
        return self


class PidTrackingSpec(_PoleZeroController):
    """PID trajectory tracking ``u = (tau/Km) xD'' + x2/Km - K1 dx1 - K2 dx2 - K3 int(dx1)``."""

    kind: Literal["pid_tracking"]


Controller = Annotated[PidServoSpec | PidTrackingSpec, Field(discriminator="kind")]


# ----------------------------------------------------------------------------- requirements


class Requirements(_Section):
    """Time-domain requirements for the commanded step (or trajectory).

    overshoot (%), settling_time (s, to the ``settling_band``), rise_time (s, 10-90 %),
    steady_state_error (same unit as the output, absolute), max_control (peak |u|).
    """

    overshoot: NonNegativeFinite | None = None
    settling_time: PositiveFinite | None = None
    rise_time: PositiveFinite | None = None
    steady_state_error: NonNegativeFinite | None = None
    max_control: PositiveFinite | None = None
    settling_band: float = Field(default=0.02, gt=0, lt=1)


# ----------------------------------------------------------------------------- simulation


class Saturation(_Section):
    """``u_applied = clip(u, -limit, limit)``."""

    kind: Literal["saturation"]
    limit: PositiveFinite


class DeadZone(_Section):
    """Zero output for ``|u| <= width``, ``u - sign(u) width`` beyond."""

    kind: Literal["dead_zone"]
    width: PositiveFinite


class Relay(_Section):
    """Relay with hysteresis: ``+amplitude`` once ``u > hysteresis``, ``-amplitude`` once ``u < -hysteresis``."""

    kind: Literal["relay"]
    amplitude: PositiveFinite
    hysteresis: NonNegativeFinite = 0.0


class Quantizer(_Section):
    """``u_applied = step * round(u / step)``."""

    kind: Literal["quantizer"]
    step: PositiveFinite


Nonlinearity = Annotated[Saturation | DeadZone | Relay | Quantizer, Field(discriminator="kind")]


class Noise(_Section):
    """White Gaussian measurement noise on position and speed, seeded."""

    std: NonNegativeFinite = 0.0
    seed: int = 0


class Perturbation(_Section):
    """Input-equivalent perturbation ``xi`` (same unit as u): ``value`` from ``time`` on (0 = constant)."""

    value: Finite
    time: NonNegativeFinite = 0.0


class AntiWindup(_Section):
    """Limit the integral action.

    ``threshold``: integrate only while ``|x1 - xD| <= value``; ``saturation``: clamp ``|K3 * integral| <= value``.
    """

    kind: Literal["threshold", "saturation"]
    value: PositiveFinite


class Trajectory(_Section):
    """Desired trajectory for tracking controllers: quintic rest-to-rest or a sine."""

    kind: Literal["quintic", "sine"] = "quintic"
    amplitude: Finite = 1.0
    duration: PositiveFinite = 1.0
    frequency: PositiveFinite = 1.0


class Simulation(_Section):
    """Closed-loop simulation scenario on the nonlinear link model.

    duration (s), step (amplitude of the commanded step, rad), dt (integration step, s;
    default: from the fastest closed-loop pole), delay (s), sampling_period (s, 0 = continuous).
    """

    duration: PositiveFinite | None = None
    step: Finite = 1.0
    dt: PositiveFinite | None = None
    nonlinearity: Nonlinearity | None = None
    delay: NonNegativeFinite = 0.0
    sampling_period: NonNegativeFinite = 0.0
    noise: Noise | None = None
    perturbation: Perturbation | None = None
    anti_windup: AntiWindup | None = None
    trajectory: Trajectory | None = None


# ----------------------------------------------------------------------------- spec


class Spec(_Section):
    """A complete design spec."""

    name: str = Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]*$", max_length=100)
    description: str = ""
    plant: LinkPlantSpec
    controller: Controller
    requirements: Requirements | None = None
    simulation: Simulation = Simulation()

    @model_validator(mode="after")
    def _poles_or_requirements(self) -> Spec:
        if self.controller.poles is None:
            req = self.requirements
            if req is None or req.overshoot is None or req.settling_time is None:
                raise ValueError(
                    "controller.poles: missing; give three poles, or requirements.overshoot and "
                    "requirements.settling_time to derive them"
                )
        return self
