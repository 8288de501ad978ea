"""The spec format: a plant, a controller to synthesise, requirements, a simulation scenario, numerics.

Every section forbids unknown keys and is frozen; numbers must be finite.  The ``controller``
section is the discriminated union of the registered families' spec models
(:data:`designkit.families.FAMILIES`), so a new family needs no change here; each family also
checks its cross-section rules (e.g. poles or requirements) and which plant kinds it accepts.
``designkit schema`` prints the JSON Schema generated from these models.
"""

from __future__ import annotations

from typing import Annotated, Any, Union

from pydantic import Field, model_validator

from designkit.families import FAMILIES
from designkit.spec.controllers import PoleRequirementsController
from designkit.spec.fields import Section, check_conjugates
from designkit.spec.plants import DHLink, ElasticJointPlantSpec, LinkPlantSpec, PlantSpec, RobotPlantSpec, Uncertainty
from designkit.spec.sections import (
    AntiWindup,
    DeadZone,
    Noise,
    Numerics,
    Perturbation,
    Quantizer,
    QuinticTrajectory,
    Relay,
    Requirements,
    Saturation,
    Simulation,
    SineTrajectory,
    Studies,
    Trajectory,
    TrapezoidalTrajectory,
    ViaPointsTrajectory,
)
from designkit.synthesis.family import SETTINGS

__all__ = [
    "AntiWindup", "Controller", "DHLink", "DeadZone", "ElasticJointPlantSpec", "LinkPlantSpec", "Noise", "Numerics",
    "Perturbation", "PlantSpec", "PoleRequirementsController", "Quantizer", "QuinticTrajectory", "Relay",
    "Requirements", "RobotPlantSpec", "Saturation", "Simulation", "SineTrajectory", "Spec", "Studies", "Trajectory",
    "TrapezoidalTrajectory", "Uncertainty", "ViaPointsTrajectory", "check_conjugates", "controller_models",
    "given_settings",
]


def controller_models() -> tuple[type, ...]:
    """The registered families' spec models, in registry order."""
    return tuple(f.spec for f in FAMILIES.values())


Controller = Annotated[Union[controller_models()], Field(discriminator="kind")]  # noqa: UP007  (built at runtime)
"""The ``controller`` section: one of the registered families' models, chosen by ``kind``."""


class Spec(Section):
    """A complete design spec."""

    name: str = Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]*$", max_length=100)
    description: str = Field(default="", max_length=10_000)
    plant: PlantSpec
    controller: Controller
    requirements: Requirements | None = None
    simulation: Simulation = Simulation()
    numerics: Numerics = Numerics()
    studies: Studies | None = None

    @model_validator(mode="after")
    def _family_rules(self) -> Spec:
        fam = FAMILIES[self.controller.kind]
        if self.plant.kind not in fam.plants:
            raise ValueError(f"controller.kind: {fam.kind} is designed for a {' or '.join(fam.plants)} plant, "
                             f"got plant.kind {self.plant.kind!r}")
        traj = self.simulation.trajectory
        if traj is not None and traj.kind not in fam.references:
            follows = ", ".join(k if k != "step" else "step (simulation.step)" for k in fam.references)
            raise ValueError(f"simulation.trajectory.kind: the {fam.kind} controller follows {follows}, not "
                             f"{traj.kind!r}")
        _refuse_unused(self, fam)
        if fam.validate is not None:
            fam.validate(self)
        return self


def given_settings(spec: Spec) -> tuple[str, ...]:
    """The optional settings of :data:`designkit.synthesis.family.SETTINGS` that ``spec`` gives (a sub-key of
    ``plant.uncertainty`` counts when it differs from its default)."""
    keys = []
    if spec.simulation.anti_windup is not None:
        keys.append("simulation.anti_windup")
    unc = getattr(spec.plant, "uncertainty", None)
    if unc is not None:
        keys.append("plant.uncertainty")
        keys.extend(f"plant.uncertainty.{k}" for k in ("grid", "samples") if _differs(unc, k))
    return tuple(keys)


def _differs(section: Any, name: str) -> bool:
    """``section.name`` differs from the field's default (a canonical dump, which writes every default, gives
    nothing)."""
    field = type(section).model_fields[name]
    default = None if field.default_factory is not None else field.default
    return getattr(section, name) != default


def _refuse_unused(spec: Spec, fam: Any) -> None:
    """A setting the family does not use (:attr:`Family.uses`), a requirement no check it offers reads
    (:attr:`~designkit.verification.suite.CheckRule.reads`), or a ``controller`` field it reads on other plant kinds
    only (:attr:`Family.plant_fields`), is refused naming its key path: nothing given is silently ignored (a
    value equal to the field's default changes nothing and is let through)."""
    for key in given_settings(spec):
        if key not in fam.uses:
            raise ValueError(f"{key}: the {fam.kind} controller does not use it: {SETTINGS[key]}")
    if spec.requirements is not None:
        from designkit.verification.suite import resolve

        read = {key for rule in resolve(fam.checks) for key in rule.reads}
        for name in type(spec.requirements).model_fields:
            key = f"requirements.{name}"
            if _differs(spec.requirements, name) and key not in read:
                raise ValueError(f"{key}: no check of the {fam.kind} controller measures it")
    for pf in fam.plant_fields:
        if _differs(spec.controller, pf.name) and spec.plant.kind not in pf.plants:
            raise ValueError(f"controller.{pf.name}: the {fam.kind} controller reads it on a "
                             f"{' or '.join(pf.plants)} plant only ({pf.what}), not on the {spec.plant.kind} plant")
