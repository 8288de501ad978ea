"""The spec format: a plant, a controller to synthesise, requirements, a simulation scenario, numerics.

Every section forbids unknown keys and is frozen; numbers must be finite.  The ``controller``
section is one of the registered families' spec models (:data:`designkit.families.FAMILIES`), chosen
by its ``kind`` and validated by that family's model alone (:class:`~designkit.schema.by_kind.ByKind`:
a spec imports the family it names and no other), so a new family needs no change here; each family
also checks its cross-section rules (e.g. poles or requirements) and which plant kinds it accepts.
``designkit schema`` prints the JSON Schema generated from these models (:func:`assembled`: the
``controller`` union of every family).
"""

from __future__ import annotations

from functools import cache
from typing import Annotated, Any

from pydantic import Field, create_model, model_validator

from designkit.families import FAMILIES
from designkit.schema.by_kind import ByKind
from designkit.spec.controllers import PoleRequirementsController
from designkit.spec.fields import Section, check_conjugates
from designkit.spec.plants import DHLink, ElasticJointPlantSpec, LinkPlantSpec, PlantSpec, RobotPlantSpec, Uncertainty
from designkit.spec.sections import (
    AntiWindup,
    DeadZone,
    Implementation,
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
from designkit.spec.tune import Tune
from designkit.synthesis.family import SETTINGS

__all__ = [
    "AntiWindup", "Controller", "DHLink", "DeadZone", "ElasticJointPlantSpec", "Implementation", "LinkPlantSpec",
    "Noise", "Numerics", "Perturbation", "PlantSpec", "PoleRequirementsController", "Quantizer", "QuinticTrajectory",
    "Relay", "Requirements", "RobotPlantSpec", "Saturation", "Simulation", "SineTrajectory", "Spec", "Studies",
    "Trajectory", "TrapezoidalTrajectory", "Uncertainty", "ViaPointsTrajectory", "assembled", "check_conjugates",
    "controller_models", "given_settings",
]


def controller_models() -> tuple[type, ...]:
    """The registered families' spec models, in registry order (imports every family)."""
    return tuple(f.spec for f in FAMILIES.values())


CONTROLLER = ByKind(lambda kind: FAMILIES[kind].spec)
"""How the ``controller`` section is validated: by the model of the family its ``kind`` names."""

Controller = Annotated[Section, CONTROLLER]
"""The ``controller`` section: one of the registered families' models, chosen by ``kind``."""


class Spec(Section):
    """A complete design spec."""

    name: str = Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]*$", max_length=100)
    description: str = Field(default="", max_length=10_000)
    plant: PlantSpec
    controller: Controller
    requirements: Requirements | None = None
    simulation: Simulation = Simulation()
    implementation: Implementation | None = None
    numerics: Numerics = Numerics()
    studies: Studies | None = None
    tune: Tune | None = None

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

    @classmethod
    def model_json_schema(cls, *args: Any, **kwargs: Any) -> dict[str, Any]:
        """The JSON Schema of the spec, its ``controller`` the union of every family's section (:func:`assembled`)."""
        if cls is Spec:
            return assembled().model_json_schema(*args, **kwargs)
        return super().model_json_schema(*args, **kwargs)


@cache
def assembled() -> type[Spec]:
    """:class:`Spec` with its ``controller`` typed as the discriminated union of every registered family's section
    (imports every family): the model the JSON Schema and the ranges table are generated from."""
    model = create_model("Spec", __base__=Spec, __module__=__name__,
                         controller=(CONTROLLER.union(), ...))
    model.__doc__ = Spec.__doc__
    return model


def given_settings(spec: Spec) -> tuple[str, ...]:
    """The optional settings of :data:`designkit.synthesis.family.SETTINGS` that ``spec`` gives (a sub-key of
    ``plant.uncertainty`` counts when it differs from its default)."""
    keys = []
    if getattr(spec.plant, "dt", None) is not None:
        keys.append("plant.dt")
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
