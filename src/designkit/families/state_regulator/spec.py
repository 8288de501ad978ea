"""The ``controller`` section of the ``state_regulator`` family (ROBEL's linear state regulator, figure 5.2).

Fields:

* ``observer_poles`` (1/s, optional, ``transfer_function`` and ``state_space`` plants): the ``n`` poles of a
  Luenberger observer of the state from the plant's outputs ``y = C x``; without them the law reads the full state.
* ``poles`` (1/s): the ``n`` closed-loop poles of ``x' = (A - B K) x`` (4 on the elastic joint, 2 on the link, the
  order of a ``transfer_function`` or ``state_space`` plant),
  each in the open left half plane (a pole with ``Re p >= 0`` is refused at ``controller.poles[k]``), complex ones
  in conjugate pairs, within the ranges of every pole list (:func:`~designkit.spec.ranges.check_poles`).
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, field_validator

from designkit.spec.fields import Pole, Section, check_conjugates
from designkit.spec.plants import linear_order
from designkit.spec.ranges import check_poles

KIND = "state_regulator"
"""The controller kind of this family (the spec's ``controller.kind``)."""

STATES = {"link": 2, "elastic_joint": 4}
"""States of the plant kinds the family designs for."""

__all__ = ["KIND", "STATES", "StateRegulatorSpec", "validate"]


class StateRegulatorSpec(Section):
    """Linear state regulator ``u = -K x + N xD`` by pole placement (module docstring for the fields)."""

    kind: Literal[KIND]
    poles: list[Pole] = Field(description="The n closed-loop poles (1/s) of x' = (A - B K) x, one per plant state.")
    observer_poles: list[Pole] | None = Field(
        default=None, description="The n poles (1/s) of a Luenberger observer x̂' = A x̂ + B u + L (y − C x̂) reading "
        "the outputs y = C x of a transfer_function or state_space plant; without them the full state is measured.")

    @field_validator("observer_poles")
    @classmethod
    def _observer(cls, v: list[complex] | None) -> list[complex] | None:
        if v is None:
            return v
        if not v:
            raise ValueError("must list one observer pole per plant state, got none")
        check_conjugates(v)
        check_poles(v)
        return v

    @field_validator("poles")
    @classmethod
    def _poles(cls, v: list[complex]) -> list[complex]:
        if not v:
            raise ValueError("must list one closed-loop pole per plant state, got none")
        check_conjugates(v)
        check_poles(v)
        return v


def validate(spec: Any) -> None:
    """Cross-section rules (``ValueError("key.path: message")``)."""
    n = STATES.get(spec.plant.kind) or linear_order(spec.plant)
    if len(spec.controller.poles) != n:
        raise ValueError(f"controller.poles: the {spec.plant.kind} plant has {n} states, so the state feedback "
                         f"places {n} poles; got {len(spec.controller.poles)}")
    if spec.plant.kind == "elastic_joint" and (spec.plant.mgl or 0.0) > 0:
        raise ValueError("plant.mgl: the regulator is designed on the linear plant at rest at the reference; with "
                         "gravity the rest state needs a holding torque u = -K x + N xD does not provide (mgl = 0)")
    observer = spec.controller.observer_poles
    if observer is not None and len(observer) != n:
        raise ValueError(f"controller.observer_poles: the observer estimates the {n} states, so it places {n} poles; "
                         f"got {len(observer)}")
    if spec.simulation.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the state regulator has no integral to wind up")
