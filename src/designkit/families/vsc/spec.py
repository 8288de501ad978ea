"""The ``controller`` section of the ``vsc`` family (theorem 3's variable structure regulator), and its rules.

Fields (every number with its unit and range, refused with its key path otherwise):

* ``sliding_poles`` (1/s): the ``n - 1`` poles of the sliding motion on ``sigma = c x = 0`` (3 on the elastic
  joint, 1 on the link, the order less one on a ``transfer_function`` or ``state_space`` plant), each in the open
  left half plane, complex ones in conjugate pairs.
* ``margin`` (1, above 0, at most 10; default 0.2): the designed gains clear every bound ``l_i`` by
  ``margin S_i`` (:mod:`~designkit.families.vsc.gains`) and the relay its bound by ``(1 + margin)``.
* ``alpha``, ``beta`` (input units per state unit, one per state, within 1e9): the switching gains given instead
  of designed (``alpha_i < beta_i`` each); the certificate judges them.
* ``relay_amplitude`` (input units, above 0, at most 1e6): the relay amplitude ``delta`` given instead of
  designed (not ``delta``: that key path is another family's, with another range).  Required when no perturbation
  is known (no ``perturbation_bound`` and no ``simulation.perturbation``).
* ``perturbation_bound`` (the disturbance's unit, 1e-6 to 1e6): ``sup |d|`` of the plant's disturbance input
  (the link's input-equivalent perturbation, the elastic joint's load torque on the link).  Default:
  ``|simulation.perturbation.value|``.
* ``chattering_band`` (sigma's unit, above 0): the band ``|sigma| <= band`` the command held over one step may
  leave; it sets the integration step.  Default ``1e-3 |sigma(0)|``.
* ``boundary_layer`` (sigma's unit, above 0): ``sat(sigma/epsilon)`` instead of ``sign(sigma)``.
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

from pydantic import Field, field_validator, model_validator

from designkit.spec.fields import Finite, Pole, Section, check_conjugates
from designkit.spec.ranges import Ranged, check_poles

KIND = "vsc"
"""The controller kind of this family (the spec's ``controller.kind``)."""

__all__ = ["KIND", "VscSpec", "perturbation_level", "states_of", "validate"]

STATES = {"link": 2, "elastic_joint": 4}
"""States of the plant kinds the family designs for."""


class VscSpec(Section):
    """Variable structure regulator ``u = sum_i psi_i x_i - delta sign(sigma)``, ``sigma = c x`` (notes section
    5.2, theorem 3; ROBEL figure 5.3); fields in the module docstring."""

    step_fields: ClassVar[dict[str, int]] = {"boundary_layer": 1, "chattering_band": 1, "relay_amplitude": -1}
    """Fields that set the law's largest step (name -> +1: the step grows with it, -1: shrinks), first given
    first: the step-bound refusal names it (:func:`designkit.simulation.timing.step_field`)."""

    kind: Literal[KIND]
    sliding_poles: list[Pole] = Field(description="The n - 1 poles (1/s) of the sliding motion on sigma = c x = 0.")
    margin: Ranged(0, 10, "", low_open=True, base=Finite) = Field(
        default=0.2, description="Relative margin of the designed gains on every condition.")
    alpha: list[Ranged(-1e9, 1e9, "input per state unit", base=Finite)] | None = Field(
        default=None, description="Switching gains where x_i sigma > 0, one per state (given, not designed).")
    beta: list[Ranged(-1e9, 1e9, "input per state unit", base=Finite)] | None = Field(
        default=None, description="Switching gains where x_i sigma < 0, one per state (given, not designed).")
    relay_amplitude: Ranged(0, 1e6, "input", low_open=True, base=Finite) | None = Field(
        default=None, description="Relay amplitude delta > 0 (input units), given instead of designed.")
    perturbation_bound: Ranged(1e-6, 1e6, "disturbance unit", base=Finite) | None = Field(
        default=None, description="sup |d| of the plant's disturbance input; default |simulation.perturbation|.")
    chattering_band: Ranged(0, 1e6, "sigma unit", low_open=True, base=Finite) | None = Field(
        default=None, description="Band |sigma| <= band the held command may leave; sets the step.")
    boundary_layer: Ranged(0, 1e6, "sigma unit", low_open=True, base=Finite) | None = Field(
        default=None, description="epsilon: sat(sigma/epsilon) instead of sign(sigma).")

    @field_validator("sliding_poles")
    @classmethod
    def _poles(cls, v: list[complex]) -> list[complex]:
        if not v:
            raise ValueError("must list the n - 1 poles of the sliding motion, got none")
        check_conjugates(v)
        check_poles(v)
        return v

    @field_validator("relay_amplitude")
    @classmethod
    def _positive_delta(cls, v: float | None) -> float | None:
        if v is not None and v <= 0:
            raise ValueError(f"must be positive (theorem 3 needs delta > 0 for finite-time reaching), got {v:g}")
        return v

    @model_validator(mode="after")
    def _brackets(self) -> VscSpec:
        if self.chattering_band is not None and self.boundary_layer is not None:
            raise ValueError("boundary_layer: give chattering_band (sign held over a step) or boundary_layer, "
                             "not both")
        if self.alpha is not None and self.beta is not None:
            if len(self.alpha) != len(self.beta):
                raise ValueError(f"beta: {len(self.beta)} gains for {len(self.alpha)} alpha gains")
            for i, (a, b) in enumerate(zip(self.alpha, self.beta, strict=True)):
                if a >= b:
                    raise ValueError(f"alpha[{i}]: alpha_{i + 1} = {a:g} must be below beta_{i + 1} = {b:g} "
                                     "(theorem 3 needs alpha_i < l_i < beta_i)")
        return self


def perturbation_level(sim: Any) -> float | None:
    """``max |simulation.perturbation.value|`` (the disturbance's unit), None without a perturbation."""
    pert = sim.perturbation
    if pert is None:
        return None
    values = pert.value if isinstance(pert.value, list | tuple) else [pert.value]
    return max(abs(float(v)) for v in values)


def states_of(spec: Any) -> int:
    """Number of plant states of the spec's plant (the order of a ``transfer_function`` or ``state_space``)."""
    plant = spec.plant
    if plant.kind == "transfer_function":
        return len(plant.den) - 1
    if plant.kind == "state_space":
        return len(plant.A)
    return STATES[plant.kind]


def validate(spec: Any) -> None:
    """Cross-section rules (``ValueError("key.path: message")``)."""
    ctl, sim = spec.controller, spec.simulation
    n = states_of(spec)
    if len(ctl.sliding_poles) != n - 1:
        raise ValueError(f"controller.sliding_poles: the {spec.plant.kind} plant has {n} states, so the sliding "
                         f"motion on sigma = c x = 0 has {n - 1} poles; got {len(ctl.sliding_poles)}")
    for key in ("alpha", "beta"):
        v = getattr(ctl, key)
        if v is not None and len(v) != n:
            raise ValueError(f"controller.{key}: one gain per state ({n}), got {len(v)}")
    level = perturbation_level(sim)
    if ctl.perturbation_bound is not None and level is not None and ctl.perturbation_bound < level:
        raise ValueError(f"controller.perturbation_bound: {ctl.perturbation_bound:g} is below the simulated "
                         f"perturbation {level:g} (simulation.perturbation.value): the certificate would not cover "
                         "the run")
    if ctl.relay_amplitude is None and ctl.perturbation_bound is None and not level:
        raise ValueError("controller.relay_amplitude: give the relay amplitude delta > 0 (input units), or a "
                         "perturbation (controller.perturbation_bound or simulation.perturbation) to design it from")
    if sim.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the variable structure law has no integral to wind up")
    if spec.plant.kind == "elastic_joint" and (spec.plant.mgl or 0.0) > 0:
        raise ValueError("plant.mgl: the regulator is designed on the linear plant at rest at the reference; with "
                         "gravity the rest state needs a holding torque the law does not provide (mgl = 0 only)")
    key = sim.still_reference()
    if key is not None:
        raise ValueError(f"{key}: the reference does not move (amplitude 0): there is no error to regulate (the "
                         "relay's band and the integration step are sized on the reference's displacement)")
