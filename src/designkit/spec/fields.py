"""Building blocks of the spec format: the frozen section base, finite numbers, poles, per-joint values.

Every section forbids unknown keys and is frozen; numbers must be finite.  Sections of the
spec (plant kinds, simulation, requirements, numerics) and every controller family's model are
built from these, so that one rule (and one error message) holds everywhere.

Booleans are not numbers and text is not a number: wherever a field (or an item of a list or
mapping field) holds an ``int`` or a ``float``, ``true`` / ``yes`` is refused (pydantic's lax mode
would read it as 1), so is a quoted value (``'2.0'``, which lax mode would parse), and an integer
beyond the floating-point range is refused where a ``float`` is meant, and so is a subnormal number (nonzero but
below 2.2e-308 in magnitude, ``5e-324``); where a field holds only a
boolean, a number (``friction: 1``) is refused.  Only JSON's types are read.  The rule
is read from each field's annotation by :class:`Section`, so it holds for every section without
restating it per field.
"""

from __future__ import annotations

import cmath
import math
import sys
import types
from collections import abc
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Union, get_args, get_origin

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from designkit.errors import SpecError, short_repr

__all__ = [
    "Finite", "NonNegativeFinite", "PerJoint", "Pole", "PositiveFinite", "Section", "check_conjugates", "fmt_pole",
    "joint_values", "parse_pole", "per_joint", "spec_argument",
]


_NOT_BOOLEAN = "not a boolean (true/false, yes/no, on/off)"

FLOAT_MAX = sys.float_info.max
"""Largest finite float (about 1.8e308): a larger integer cannot be a float."""
FLOAT_MIN = sys.float_info.min
"""Smallest normal float (about 2.2e-308): a nonzero number below it in magnitude is subnormal (``5e-324``), kept
with fewer significant digits, and whatever is computed from it (a step, a scale, a reciprocal) underflows."""


def _subnormal(value: float) -> bool:
    return value != 0.0 and abs(value) < FLOAT_MIN


def _subnormal_message(value: object) -> str:
    return (f"must be 0 or at least {FLOAT_MIN:.3g} in magnitude (a subnormal number is too small to compute "
            f"with), got {short_repr(value)}")


@dataclass(frozen=True)
class _NumberRule:
    """What a field's annotation says about numbers, at one level of nesting.

    ``scalar`` is ``"float"`` or ``"int"`` when a number may stand here (None otherwise), ``bool_ok``
    when a boolean may; ``items`` / ``values`` are the rules for list items and mapping values.
    """

    scalar: str | None = None
    bool_ok: bool = False
    items: _NumberRule | None = None
    values: _NumberRule | None = None
    str_ok: bool = False
    bool_only: bool = False


_ANYTHING = _NumberRule(bool_ok=True, str_ok=True)
_STRING = _NumberRule(str_ok=True)
_BOOLEAN = _NumberRule(bool_ok=True, bool_only=True)


def _merge(rules: list[_NumberRule | None]) -> _NumberRule | None:
    rules_ = [r for r in rules if r is not None]
    if not rules_:
        return None
    scalars = {r.scalar for r in rules_}
    return _NumberRule(
        scalar="float" if "float" in scalars else "int" if "int" in scalars else None,
        bool_ok=any(r.bool_ok for r in rules_),
        items=_merge([r.items for r in rules_]),
        values=_merge([r.values for r in rules_]),
        str_ok=any(r.str_ok for r in rules_),
        bool_only=all(r.bool_only for r in rules_),
    )


def _rule(tp: Any) -> _NumberRule | None:
    """The number rule of a type annotation; None where nothing is to check (models, strings, poles)."""
    origin = get_origin(tp)
    if origin is Annotated:
        return _rule(get_args(tp)[0])
    if tp is bool:
        return _BOOLEAN
    if tp is str:
        return _STRING
    if tp is float or tp is int:
        return _NumberRule(scalar=tp.__name__)
    if tp is Any or tp is object:
        return _ANYTHING
    if origin in (Union, types.UnionType):
        return _merge([_rule(m) for m in get_args(tp) if m is not type(None)])
    if origin is Literal:
        return _ANYTHING if any(isinstance(a, bool) for a in get_args(tp)) else _STRING
    if origin in (list, tuple, set, frozenset, abc.Sequence):
        items = _merge([_rule(a) for a in get_args(tp) if a is not Ellipsis])
        return None if items is None else _NumberRule(items=items)
    if origin in (dict, abc.Mapping):
        args = get_args(tp)
        values = _rule(args[1]) if len(args) == 2 else None
        return None if values is None else _NumberRule(values=values)
    return None  # nested sections validate themselves; complex (poles) and others need nothing here


def _number_problem(rule: _NumberRule, value: object, where: str = "") -> tuple[str, str] | None:
    """``(inner key path, message)`` of the first boolean or out-of-range integer standing for a number."""
    if isinstance(value, bool):
        if rule.scalar is not None and not rule.bool_ok:
            return where, f"must be a number, {_NOT_BOOLEAN}"
    elif isinstance(value, int | float) and rule.bool_only:
        return where, f"must be true or false, got {short_repr(value)} (numbers are not read as booleans)"
    elif isinstance(value, str) and rule.scalar is not None and not rule.str_ok:
        return where, (f"must be a number, got the string {short_repr(value)} (only numbers as JSON writes them are "
                       "read: decimal, without quotes)")
    elif isinstance(value, int):
        if rule.scalar == "float" and abs(value) > FLOAT_MAX:
            return where, f"must be within the floating-point range (|x| <= {FLOAT_MAX:.4g}), got {short_repr(value)}"
    elif isinstance(value, list | tuple) and rule.items is not None:
        for k, item in enumerate(value):
            problem = _number_problem(rule.items, item, f"{where}[{k}]")
            if problem is not None:
                return problem
    elif isinstance(value, dict) and rule.values is not None:
        for key, item in value.items():
            problem = _number_problem(rule.values, item, f"{where}.{key}" if where else str(key))
            if problem is not None:
                return problem
    return None


def _subnormal_problem(rule: _NumberRule, value: object, where: str) -> tuple[str, str] | None:
    """``(inner key path, message)`` of the first subnormal number of a validated value."""
    if isinstance(value, float) and rule.scalar is not None and _subnormal(value):
        return where, _subnormal_message(value)
    if isinstance(value, list | tuple) and rule.items is not None:
        for k, item in enumerate(value):
            problem = _subnormal_problem(rule.items, item, f"{where}[{k}]")
            if problem is not None:
                return problem
    if isinstance(value, dict) and rule.values is not None:
        for key, item in value.items():
            problem = _subnormal_problem(rule.values, item, f"{where}.{key}")
            if problem is not None:
                return problem
    return None


_RULES: dict[tuple[type, str], _NumberRule | None] = {}


def _field_rule(cls: type, name: str, annotation: Any) -> _NumberRule | None:
    key = (cls, name)
    if key not in _RULES:
        _RULES[key] = _rule(annotation)
    return _RULES[key]


class Section(BaseModel):
    """Base of every spec section: unknown keys are errors, values are frozen, numbers finite.

    Where a field's annotation holds numbers (``float``, ``int``, lists or mappings of them), a
    boolean is refused and, for ``float``, so is an integer beyond the floating-point range; the
    message names the item (``[2]: must be a number, not a boolean (...)``).
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, str_strip_whitespace=True)

    @model_validator(mode="before")
    @classmethod
    def _numbers_are_numbers(cls, data: object) -> object:
        if not isinstance(data, dict):
            return data
        for name, value in data.items():
            field = cls.model_fields.get(name) if isinstance(name, str) else None
            if field is None:
                continue  # an unknown key: the schema's error
            rule = _field_rule(cls, name, field.annotation)
            if rule is not None:
                problem = _number_problem(rule, value, name)
                if problem is not None:
                    raise ValueError(f"{problem[0]}: {problem[1]}")
        return data

    @model_validator(mode="after")
    def _no_subnormal_numbers(self) -> Section:
        """After the fields' own ranges (whose messages say more where they exclude it): no subnormal number."""
        cls = type(self)
        for name, field in cls.model_fields.items():
            rule = _field_rule(cls, name, field.annotation)
            if rule is not None:
                problem = _subnormal_problem(rule, getattr(self, name), name)
                if problem is not None:
                    raise ValueError(f"{problem[0]}: {problem[1]}")
        return self


def _finite(value: float) -> float:
    if not math.isfinite(value):
        raise ValueError(f"must be finite, got {value}")
    return value


def _parse_pole(value: object) -> complex:
    """Accept a real number or a string such as ``"-2+3j"``; return a complex number."""
    if isinstance(value, bool):
        raise ValueError(f"must be a number or a complex string like '-2+3j', {_NOT_BOOLEAN}")
    if isinstance(value, int) and abs(value) > FLOAT_MAX:
        raise ValueError(f"must be within the floating-point range (|x| <= {FLOAT_MAX:.4g}), got {short_repr(value)}")
    if isinstance(value, int | float):
        return complex(float(value), 0.0)
    if isinstance(value, complex):
        return value
    if isinstance(value, str):
        try:
            return complex(value.replace(" ", "").replace("i", "j"))
        except ValueError:
            raise ValueError(f"must be a number or a complex string like '-2+3j', got {short_repr(value)}") from None
    raise ValueError(f"must be a number or a complex string like '-2+3j', got {short_repr(value)}")


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
    if isinstance(value, bool):
        raise ValueError(f"{where}must be a number, {_NOT_BOOLEAN}")
    if not isinstance(value, int | float):
        raise ValueError(f"{where}must be a number, got {short_repr(value)}")
    if isinstance(value, int) and abs(value) > FLOAT_MAX:
        raise ValueError(f"{where}must be within the floating-point range (|x| <= {FLOAT_MAX:.4g}), "
                         f"got {short_repr(value)}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{where}must be finite, got {value}")
    if _subnormal(value):
        raise ValueError(f"{where}{_subnormal_message(value)}")
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


def joint_values(value: float | list[float] | tuple[float, ...], n: int, path: str) -> tuple[float, ...]:
    """:func:`per_joint` for a stage that reads the spec after it was validated: a list of the wrong length is
    refused with a :class:`~designkit.errors.SpecError` naming ``path`` (units those of ``value``)."""
    try:
        return per_joint(value, n, path)
    except ValueError as exc:
        key, msg = str(exc).split(": ", 1)
        raise SpecError(key, msg) from None


def spec_argument(spec: Any, name: str = "spec") -> Any:
    """The assembled spec an API function was given: a ``Spec``, or the ``LoadedSpec`` holding one.

    Raises
    ------
    SpecError
        Naming the argument, for anything else (a path, ``None``, a dict).
    """
    from designkit.errors import SpecError

    inner = getattr(spec, "spec", None)
    if inner is not None and hasattr(inner, "controller") and hasattr(inner, "plant"):
        return inner
    if hasattr(spec, "controller") and hasattr(spec, "plant") and hasattr(spec, "simulation"):
        return spec
    raise SpecError(name, f"must be a designkit Spec (dk.load_spec(path).spec or dk.parse_spec(text).spec), got "
                    f"{type(spec).__name__}")
