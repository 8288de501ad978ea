"""Figures the generic checks draw from their certificates and data, one module per check.

Each is a ``(result, check) -> Figure | None`` listed in its rule's ``figures``
(:mod:`designkit.verification.checks`); the report lays them out after the design's own figures.
"""
