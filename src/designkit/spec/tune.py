"""The ``tune`` section of a spec: what ``designkit tune`` may not move, and where it may move the rest.

``fixed`` names knobs of the controller's family that keep the spec's value; ``ranges`` gives, per knob name, the
interval ``[lo, hi]`` the tuner searches (the knob's unit; for a pole or zero knob, the range of ``|p|`` in 1/s).
The names are checked against the family's knobs above this layer (:mod:`designkit.tuning.space`), with their key
paths; here only the shape and the order of each range are checked.
"""

from __future__ import annotations

import math

from pydantic import Field, field_validator

from designkit.spec.fields import Section

__all__ = ["Tune"]


class Tune(Section):
    """The ``tune`` section: ``fixed`` (knob names kept at the spec's value) and ``ranges`` (knob name ->
    ``[lo, hi]``, ``0 < lo < hi``, finite, in the knob's unit; a pole's or zero's modulus in 1/s)."""

    fixed: list[str] = Field(default_factory=list, max_length=64)
    ranges: dict[str, list[float]] = Field(default_factory=dict, max_length=64)

    @field_validator("ranges")
    @classmethod
    def _ordered(cls, v: dict[str, list[float]]) -> dict[str, list[float]]:
        for name, pair in v.items():
            if len(pair) != 2:
                raise ValueError(f"{name}: give [lo, hi], got {len(pair)} values")
            lo, hi = (float(x) for x in pair)
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ValueError(f"{name}: the range must be finite, got [{lo:g}, {hi:g}]")
            if lo <= 0:
                raise ValueError(f"{name}: the range must be positive (a gain, a modulus), got lo = {lo:g}")
            if lo >= hi:
                raise ValueError(f"{name}: needs lo < hi, got [{lo:g}, {hi:g}]")
        return v
