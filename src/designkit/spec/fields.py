"""Building blocks of the spec format: the frozen section base, finite numbers, poles, per-joint values.

Every section forbids unknown keys and is frozen; numbers must be finite.  Sections of the
spec (plant kinds, simulation, requirements, numerics) and every controller family's model are
built from these, so that one rule (and one error message) holds everywhere.
"""

from __future__ import annotations

import cmath
import math
from typing import Annotated

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field

__all__ = [
    "Finite", "NonNegativeFinite", "PerJoint", "Pole", "PositiveFinite", "Section", "check_conjugates", "fmt_pole",
    "parse_pole", "per_joint",
]


class Section(BaseModel):
    """Base of every spec section: unknown keys are errors, values are frozen, numbers finite."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, str_strip_whitespace=True)


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise ValueError(f"must be finite, got {value}")
    return value


def _parse_pole(value: object) -> complex:
    """Accept a real number or a string such as ``"-2+3j"``; return a complex number."""
    if isinstance(value, bool):
        raise ValueError(f"must be a number or a complex string like '-2+3j', got {value!r}")
    if isinstance(value, int | float):
        return complex(float(value), 0.0)
    if isinstance(value, complex):
        return value
    if isinstance(value, str):
        try:
            return complex(value.replace(" ", "").replace("i", "j"))
        except ValueError:
            raise ValueError(f"must be a number or a complex string like '-2+3j', got {value!r}") from None
    raise ValueError(f"must be a number or a complex string like '-2+3j', got {value!r}")


def _stable_pole(p: complex) -> complex:
    if not (cmath.isfinite(p)):
        raise ValueError(f"must be finite, got {p}")
    if p.real >= 0.0:
        raise ValueError(f"must have negative real part, got {fmt_pole(p)}")
    return p


def fmt_pole(p: complex) -> str:
    return f"{p.real:g}" if p.imag == 0 else f"{p.real:g}{p.imag:+g}j"


def parse_pole(value: object) -> complex:
    """A stable closed-loop pole from a number or a string such as ``"-2+3j"`` (``ValueError`` otherwise)."""
    return _stable_pole(_parse_pole(value))


Finite = Annotated[float, AfterValidator(_finite)]
PositiveFinite = Annotated[float, Field(gt=0), AfterValidator(_finite)]
NonNegativeFinite = Annotated[float, Field(ge=0), AfterValidator(_finite)]
Pole = Annotated[complex, BeforeValidator(_parse_pole), AfterValidator(_stable_pole)]


def check_conjugates(poles: list[complex]) -> None:
    """Raise ``ValueError`` naming the first complex pole whose conjugate is missing."""
    remaining = list(poles)
    while remaining:
        p = remaining.pop(0)
        if p.imag == 0:
            continue
        match = next((k for k, r in enumerate(remaining) if abs(r - p.conjugate()) <= 1e-12 * (1 + abs(p))), None)
        if match is None:
            raise ValueError(f"complex pole {fmt_pole(p)} has no conjugate {fmt_pole(p.conjugate())} in the list")
        remaining.pop(match)




def _number(value: object, where: str = "") -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{where}must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{where}must be finite, got {value}")
    return value


def _per_joint(value: object) -> float | list[float]:
    if isinstance(value, list | tuple):
        if not value:
            raise ValueError("must list one number per joint, got an empty list")
        return [_number(v, f"entry {k}: ") for k, v in enumerate(value)]
    return _number(value)


PerJoint = Annotated[float | list[float], BeforeValidator(_per_joint)]
"""A number for every joint, or a list with one number per joint (the length is checked against the plant)."""


def per_joint(value: float | list[float] | tuple[float, ...], n: int, path: str) -> tuple[float, ...]:
    """``value`` broadcast to ``n`` joints; ``ValueError`` naming ``path`` when a list has the wrong length."""
    if isinstance(value, list | tuple):
        if len(value) != n:
            raise ValueError(f"{path}: needs one value per joint ({n}), got {len(value)}")
        return tuple(float(v) for v in value)
    return (float(value),) * n
