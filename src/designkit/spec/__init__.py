"""The spec's section models: numbers with ranges, plants, requirements, simulation, numerics.

These are the building blocks the controller families declare their own sections with, so they
sit below the families; the assembled :class:`~designkit.schema.spec.Spec`, whose ``controller``
is the union of the registered families' sections, and the YAML loader are in
:mod:`designkit.schema`, above the families.  :mod:`~designkit.spec.plant_builder` turns a plant
section into a :class:`~designkit.models.plant.Plant`.
"""
