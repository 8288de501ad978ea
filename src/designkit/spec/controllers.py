"""Building blocks shared by the controller sections of the families.

A family's spec model (a member of the ``controller`` union) is declared in its own module
(:mod:`designkit.families`); the pieces several families share -- a list of closed-loop poles
with conjugate pairs, the rule deriving poles from overshoot and settling-time requirements --
live here.

Poles are checked with :func:`designkit.spec.ranges.check_poles`: every ``|p|`` between 1e-12 and
1e12 1/s, and ``max |p| / min |Re p|`` at most 1e12 (what double precision can honour).
"""

from __future__ import annotations

from pydantic import Field, field_validator

from designkit.spec.fields import Finite, Pole, PositiveFinite, Section, check_conjugates
from designkit.spec.plants import Payload
from designkit.spec.ranges import PARAMETER, Ranged, check_poles

__all__ = ["ControllerModel", "LinearPoleRequirementsController", "PoleRequirementsController", "three_poles",
           "two_or_three_poles"]


class ControllerModel(Section):
    """The model a model-based controller believes, when it is not the true plant.

    Without this section the controller knows the true plant exactly.  With it, the controller's
    model is the plant's nominal robot (without the true plant's payload) changed as written:
    ``parameters`` (named parameter values, e.g. mass errors; each within 1e6 of its SI unit),
    ``payload`` (a payload it assumes), ``friction`` (false: the model leaves the joint friction out).
    """

    parameters: dict[str, Ranged(PARAMETER.low, PARAMETER.high, PARAMETER.unit, base=Finite)] = Field(
        default_factory=dict)
    payload: Payload | None = None
    friction: bool | None = None


def three_poles(poles: list[complex]) -> list[complex]:
    """Validate a set of three closed-loop poles (1/s): complex ones in conjugate pairs, moduli and spread
    within :func:`~designkit.spec.ranges.check_poles`."""
    if len(poles) != 3:
        raise ValueError(f"must list exactly 3 poles, got {len(poles)}")
    check_poles(poles)
    check_conjugates(poles)
    return poles


class PoleRequirementsController(Section):
    """A controller placed by three closed-loop poles, given or derived from requirements.

    ``poles`` (1/s): three values, real or a complex-conjugate pair plus a real pole (``|p|`` 1e-12 to
    1e12, spread at most 1e12); without them, ``requirements.overshoot`` and
    ``requirements.settling_time`` give a dominant pair (tightened by ``design_margin``, 0 to 0.9) and
    a real pole ``third_pole_factor`` (1 to 100) times further left.
    """

    poles: list[Pole] | None = Field(
        default=None,
        description="Closed-loop poles (1/s): three values, real or a complex-conjugate pair plus a real pole.",
    )
    third_pole_factor: Ranged(1, 100, "", base=PositiveFinite) = Field(
        default=5.0,
        description="When poles come from requirements: the real pole is placed this many times further "
        "left than the real part of the dominant pair.",
    )
    design_margin: Ranged(0, 0.9, "") = Field(
        default=0.1,
        description="When poles come from requirements: the derived pair meets overshoot and settling time "
        "tightened by this fraction, so the verified loop keeps a margin.",
    )

    @field_validator("poles")
    @classmethod
    def _three_conjugate(cls, v: list[complex] | None) -> list[complex] | None:
        return v if v is None else three_poles(v)


def two_or_three_poles(poles: list[complex]) -> list[complex]:
    """Validate 2 or 3 closed-loop poles (1/s): conjugate pairs, moduli and spread as :func:`three_poles`; whether
    the plant takes 2 (a first-order linear plant) is decided when the design is made."""
    if len(poles) not in (2, 3):
        raise ValueError(f"must list exactly 3 poles (2 on a first-order linear plant), got {len(poles)}")
    check_poles(poles)
    check_conjugates(poles)
    return poles


class LinearPoleRequirementsController(PoleRequirementsController):
    """A :class:`PoleRequirementsController` whose family also places PID poles on linear plants of any order:
    ``poles`` lists 3 values, or 2 on a first-order ``transfer_function`` / ``state_space`` plant (whose PID loop
    has order 2); poles derived from requirements are then the dominant pair alone."""

    poles: list[Pole] | None = Field(
        default=None,
        description="Closed-loop poles (1/s): three values, real or a complex-conjugate pair plus a real pole; two on "
        "a first-order linear plant.",
    )

    @field_validator("poles")
    @classmethod
    def _three_conjugate(cls, v: list[complex] | None) -> list[complex] | None:
        return v if v is None else two_or_three_poles(v)
