"""The controller families, one module (or package) each, and the registry derived from them.

Every module or subpackage of this package (other than those starting with ``_``) is named by its
controller ``kind`` and defines ``FAMILY``, a :class:`~designkit.synthesis.family.Family` of that kind.
:data:`FAMILIES` maps each ``kind`` to it, in module-name order; the spec's ``controller`` union, the
loader's tags, the checks that run and the report's law and gain tables are derived from it.  The kinds
are read from the package listing and a family's module is imported when its kind is first asked for
(:class:`designkit.discovery.Registry`), so a run imports the family it designs with and no other.
Adding a family is adding a module here (see ``docs/architecture.md`` for the worked examples); a family
with checks, figures or diagnoses of its own is a package holding them.
"""

from __future__ import annotations

from designkit import arguments
from designkit.discovery import Registry
from designkit.errors import SpecError
from designkit.synthesis.family import Family

__all__ = ["FAMILIES", "check_rules", "family", "synthesize"]


FAMILIES: Registry = Registry(__name__, "FAMILY", Family, key="kind")
"""Controller kind -> :class:`~designkit.synthesis.family.Family` (read-only; a family's module is imported when its
kind is first looked up, iterating the values imports every family)."""


def family(kind: str) -> Family:
    """The family registered for ``kind``; :class:`SpecError` naming ``controller.kind`` otherwise."""
    kind = arguments.text(kind, "controller.kind")
    if kind not in FAMILIES:
        raise SpecError("controller.kind", f"unknown controller kind {kind!r}; known: {sorted(FAMILIES)}")
    return FAMILIES[kind]


def synthesize(spec, plant=None, *, base_dir=None):
    """The design a spec asks for (the nominal plant is built from ``spec.plant`` when not given).

    The family's synthesis, then the design's law rebuilt with the spec's ``simulation.anti_windup`` (the
    linearization is unchanged: an anti-windup gate is open and its clamp inactive at the operating point)
    and the family's label.
    """
    import dataclasses

    from designkit.models.plant import Plant
    from designkit.spec.fields import spec_argument

    spec = spec_argument(spec)
    arguments.instance(plant, "plant", Plant, "a Plant (dk.zoo_plant, spec.plant.build())", optional=True)
    if base_dir is not None:
        base_dir = arguments.path(base_dir, "base_dir", what="a folder path")
    if plant is None:
        from designkit.spec.plant_builder import plant_from_spec

        plant = plant_from_spec(spec.plant, base_dir)
    fam = family(spec.controller.kind)
    design = fam.synthesize(spec, plant)
    changes = {"label": fam.display.label}
    if spec.simulation.anti_windup is not None:
        changes["law"] = fam.law(design, spec.simulation.anti_windup)
    return dataclasses.replace(design, **changes)


def check_rules(kind: str) -> tuple:
    """The :class:`~designkit.verification.suite.CheckRule` values the family of ``kind`` offers, in report order."""
    from designkit.verification.suite import resolve

    return resolve(family(kind).checks)
