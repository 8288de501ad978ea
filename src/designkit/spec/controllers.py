"""Building blocks shared by the controller sections of the families.

A family's spec model (a member of the ``controller`` union) is declared in its own module
(:mod:`designkit.families`); the pieces several families share -- a list of closed-loop poles
with conjugate pairs, the rule deriving poles from overshoot and settling-time requirements --
live here.
"""

from __future__ import annotations

from pydantic import Field, field_validator

from designkit.spec.fields import Finite, Pole, PositiveFinite, Section, check_conjugates
from designkit.spec.plants import Payload

__all__ = ["ControllerModel", "PoleRequirementsController", "three_poles"]


class ControllerModel(Section):
    """The model a model-based controller believes, when it is not the true plant.

    Without this section the controller knows the true plant exactly.  With it, the controller's
    model is the plant's nominal robot (without the true plant's payload) changed as written:
    ``parameters`` (named parameter values, e.g. mass errors), ``payload`` (a payload it assumes),
    ``friction`` (false: the model leaves the joint friction out).
    """

    parameters: dict[str, Finite] = Field(default_factory=dict)
    payload: Payload | None = None
    friction: bool | None = None


def three_poles(poles: list[complex]) -> list[complex]:
    """Validate a set of three closed-loop poles (complex ones in conjugate pairs)."""
    if len(poles) != 3:
        raise ValueError(f"must list exactly 3 poles, got {len(poles)}")
    check_conjugates(poles)
    return poles


class PoleRequirementsController(Section):
    """A controller placed by three closed-loop poles, given or derived from requirements.

    ``poles`` (1/s): three values, real or a complex-conjugate pair plus a real pole; without
    them, ``requirements.overshoot`` and ``requirements.settling_time`` give a dominant pair
    (tightened by ``design_margin``) and a real pole ``third_pole_factor`` times further left.
    """

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
        return v if v is None else three_poles(v)
