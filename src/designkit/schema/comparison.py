"""The comparison spec: several controllers on one task (one plant, simulation, requirements and numerics).

A spec gives either ``controller:`` (one controller, :class:`~designkit.schema.spec.Spec`) or
``controllers:`` (a list of 2 to :data:`MAX_CONTROLLERS` controller sections, :class:`ComparisonSpec`).  Each
entry is exactly what ``controller:`` accepts plus an optional ``label`` (default: its ``kind``; the labels
must differ).  Every entry is checked as the single-controller spec it stands for
(:meth:`ComparisonSpec.members`), so the families' cross-section rules (plant kinds, references, poles,
requirements) apply to it unchanged and their errors name ``controllers[<i>]`` instead of ``controller``.
"""

from __future__ import annotations

import re
from functools import cache
from typing import Annotated, Any, Union

from pydantic import Field, ValidationError, create_model, model_validator

from designkit.families import FAMILIES
from designkit.schema.by_kind import ByKind
from designkit.schema.spec import Spec, assembled
from designkit.spec.fields import Section
from designkit.spec.plants import PlantSpec
from designkit.spec.sections import Implementation, Numerics, Requirements, Simulation, Studies

__all__ = ["MAX_CONTROLLERS", "ComparisonSpec", "ControllerEntry", "assembled_comparison", "entry_model",
           "entry_models", "member_name"]

MAX_CONTROLLERS = 6
"""Most controllers a comparison spec names (at least 2)."""

LABEL_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]*$"
"""A label is also a folder name (the controller's own report): letters, digits, ``_ . -``."""


def entry_model(kind: str) -> type:
    """The ``controllers`` entry of a registered kind: the family's spec model plus an optional ``label`` (imports
    that family only)."""
    base = FAMILIES[kind].spec
    model = create_model(
        f"{base.__name__}Entry", __base__=base, __module__=__name__,
        label=(str | None, Field(default=None, pattern=LABEL_PATTERN, max_length=40,
                                 description="How the comparison names this controller (default: its kind).")),
    )
    model.__doc__ = f"A ``controllers`` entry of kind {kind!r}: its ``controller`` section plus a label."
    return model


ENTRY = ByKind(entry_model)
"""How an entry of ``controllers`` is validated: by the entry model of the family its ``kind`` names."""


def entry_models() -> tuple[type, ...]:
    """One model per registered family: its spec model plus an optional ``label`` (registry order; imports every
    family)."""
    return tuple(ENTRY.model_of(kind) for kind in FAMILIES)


ControllerEntry = Annotated[Section, ENTRY]
"""One entry of ``controllers``: a family's ``controller`` section with an optional ``label``."""


def member_name(label: str) -> str:
    """The spec name of a comparison's member (its label; also the folder of its own report)."""
    return label


_PATH = re.compile(r"^(\[[\w.\[\]]*|[A-Za-z_][\w.\[\]]*): (.*)$")


def _member_error(index: int, exc: ValidationError) -> str:
    """The first error of a member's validation as ``<key path>: <message>``, ``controller`` -> ``controllers[i]``."""
    err = exc.errors(include_url=False)[0]
    msg = re.sub(r"^(Value error|Assertion failed), ", "", str(err.get("msg", "invalid value")))
    m = _PATH.match(msg)
    path, text = (m.group(1), m.group(2)) if m else ("", msg)
    if path == "controller" or path.startswith(("controller.", "controller[")):
        return f"controllers[{index}]{path[len('controller'):]}: {text}"
    return f"{path or f'controllers[{index}]'}: (controllers[{index}]) {text}"


class ComparisonSpec(Section):
    """A spec comparing several controllers on one task.

    Parameters
    ----------
    name, description : str
        As in :class:`~designkit.schema.spec.Spec` (the name is the report folder).
    plant : PlantSpec
        The plant every controller is designed for and simulated on.
    controllers : list of ControllerEntry
        2 to :data:`MAX_CONTROLLERS` controller sections, each with an optional ``label``.
    requirements, simulation, implementation, numerics
        Shared by every controller (the ``plant_change``, trajectory, perturbation and duration too).
    """

    name: str = Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]*$", max_length=100)
    description: str = Field(default="", max_length=10_000)
    plant: PlantSpec
    controllers: list[ControllerEntry] = Field(min_length=2, max_length=MAX_CONTROLLERS)
    requirements: Requirements | None = None
    simulation: Simulation = Simulation()
    implementation: Implementation | None = None
    numerics: Numerics = Numerics()
    studies: Studies | None = None

    @property
    def labels(self) -> tuple[str, ...]:
        """Each controller's label (its ``label``, else its ``kind``), in spec order."""
        return tuple(c.label or c.kind for c in self.controllers)

    def member(self, index: int) -> Spec:
        """The single-controller :class:`Spec` of entry ``index``: the shared sections and that controller.

        Its name is the entry's label (:func:`member_name`); its ``controller`` is the entry without the label,
        validated by the family's own model, so it equals the section a one-controller spec would give.
        """
        entry = self.controllers[index]
        fam = FAMILIES[entry.kind]
        controller = fam.spec.model_validate(entry.model_dump(exclude={"label"}))
        return Spec.model_validate({
            "name": member_name(self.labels[index]), "description": self.description, "plant": self.plant,
            "controller": controller, "requirements": self.requirements, "simulation": self.simulation,
            "implementation": self.implementation, "numerics": self.numerics, "studies": self.studies,
        })

    def members(self) -> tuple[tuple[str, Spec], ...]:
        """``(label, Spec)`` of every controller, in spec order."""
        return tuple((label, self.member(k)) for k, label in enumerate(self.labels))

    @model_validator(mode="after")
    def _members_valid(self) -> ComparisonSpec:
        seen: dict[str, int] = {}
        for k, label in enumerate(self.labels):
            if label in seen:
                raise ValueError(f"controllers[{k}].label: {label!r} already names controllers[{seen[label]}]; "
                                 "give each controller a distinct label")
            seen[label] = k
        for k in range(len(self.controllers)):
            try:
                self.member(k)
            except ValidationError as exc:
                raise ValueError(_member_error(k, exc)) from None
        return self

    @classmethod
    def model_json_schema(cls, *args: Any, **kwargs: Any) -> dict[str, Any]:
        """The JSON Schema of a comparison spec, each entry the union of every family's entries
        (:func:`assembled_comparison`)."""
        if cls is ComparisonSpec:
            return assembled_comparison().model_json_schema(*args, **kwargs)
        return super().model_json_schema(*args, **kwargs)


@cache
def assembled_comparison() -> type[ComparisonSpec]:
    """:class:`ComparisonSpec` with its entries typed as the discriminated union of every family's entry (imports
    every family): the model its JSON Schema is generated from."""
    entries = list[ENTRY.union()]  # type: ignore[misc]
    model = create_model("ComparisonSpec", __base__=ComparisonSpec, __module__=__name__,
                         controllers=(entries, Field(min_length=2, max_length=MAX_CONTROLLERS)))
    model.__doc__ = ComparisonSpec.__doc__
    return model


def json_schema(form: str = "single") -> dict[str, Any]:
    """The JSON Schema of a spec: ``"single"`` (``controller:``), ``"comparison"`` (``controllers:``) or
    ``"any"`` (exactly one of the two forms, ``oneOf``).  Each family's section says which plant kinds it accepts
    (:func:`with_plant_kinds`)."""
    if form == "single":
        return with_plant_kinds(Spec.model_json_schema())
    if form == "comparison":
        return with_plant_kinds(ComparisonSpec.model_json_schema())
    from pydantic import TypeAdapter

    schema = TypeAdapter(Union[assembled(), assembled_comparison()]).json_schema()  # noqa: UP007
    schema["oneOf"] = schema.pop("anyOf")  # exclusive: each form forbids the other's key
    schema["title"] = "designkit spec (one controller, or a comparison of several)"
    return with_plant_kinds(schema)


def with_plant_kinds(schema: dict[str, Any]) -> dict[str, Any]:
    """``schema`` with each family's section (the targets of every discriminator on ``kind`` naming a registered
    family) given ``x-plant-kinds``, the plant kinds the family is designed for (:attr:`Family.plants`), and a
    sentence saying so at the end of its description; the top level gets ``x-families-by-plant-kind``."""
    defs = schema.get("$defs", {})
    by_plant: dict[str, list[str]] = {}

    def visit(node: Any) -> None:
        if isinstance(node, dict):
            disc = node.get("discriminator")
            if isinstance(disc, dict) and disc.get("propertyName") == "kind":
                for kind, ref in disc.get("mapping", {}).items():
                    if kind not in FAMILIES:
                        continue
                    plants = list(FAMILIES[kind].plants)
                    target = defs.get(ref.rsplit("/", 1)[-1])
                    if target is not None and "x-plant-kinds" not in target:
                        target["x-plant-kinds"] = plants
                        target["description"] = (target.get("description", "").rstrip()
                                                 + f"\n\nPlant kinds: {', '.join(plants)}.").lstrip()
                    for plant in plants:
                        by_plant.setdefault(plant, [])
                        if kind not in by_plant[plant]:
                            by_plant[plant].append(kind)
            for value in node.values():
                visit(value)
        elif isinstance(node, list):
            for value in node:
                visit(value)

    visit(schema)
    if by_plant:
        schema["x-families-by-plant-kind"] = {k: sorted(v) for k, v in sorted(by_plant.items())}
    return schema
