"""Physically meaningful ranges of the spec's numbers, declared next to each field.

A field is declared with its bounds and unit, e.g. ``Km: Ranged(1e-6, 1e6, "(rad/s)/(N*m)",
base=PositiveFinite)``; a value outside is refused with the key path and the range::

    plant.Km: must be between 1e-6 and 1e6 (rad/s)/(N*m), got 1e+308

The ranges are wide -- far beyond any real manipulator joint -- and exist so that every accepted
value can be computed in double precision: products of poles and gains, step counts and
durations stay finite and do not underflow.  What cannot be computed whatever the bounds is
refused by a rule of its own (:func:`check_poles`: the spread of a pole set).  The README's
table of ranges is generated from these declarations (:func:`markdown_table`, run
``python -m designkit.schema.ranges_table``) and a test keeps it in step.

:class:`Range` is pydantic metadata: ``Annotated[float, Range(...)]`` validates after the base
type (so a base such as :data:`~designkit.spec.fields.PositiveFinite` keeps its own message for
the sign) and adds ``minimum`` / ``maximum`` to the JSON Schema.  It accepts a number or a list
of numbers (a per-joint value): an entry outside is named ``[k]``.
"""

from __future__ import annotations

import math
import types
import typing
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Annotated, Any, get_args, get_origin

from pydantic import BaseModel
from pydantic_core import core_schema

from designkit.spec.fields import PerJoint, fmt_pole

__all__ = [
    "ANGLE", "DURATION", "LENGTH", "POLE_MODULUS", "POLE_SPREAD", "PARAMETER", "Range", "Ranged",
    "RangedInt", "RangedPerJoint", "TORQUE", "check_interval", "check_poles", "fmt_number",
    "fmt_value", "range_of", "ranges_in",
]


def fmt_number(x: float) -> str:
    """A bound as written in a message or a table: powers of ten as ``1e-6``, whole numbers as integers,
    others to 6 significant digits.

    Examples
    --------
    >>> [fmt_number(v) for v in (1e-6, 1e6, 100.0, 0.0, 2.5, 2 ** 32 - 1, 6.283185307179586)]
    ['1e-6', '1e6', '100', '0', '2.5', '4294967295', '6.28319']
    """
    x = float(x)
    if x == 0.0:
        return "0"
    exponent = math.log10(abs(x))
    if exponent == round(exponent) and abs(exponent) >= 3:
        return f"{'-' if x < 0 else ''}1e{round(exponent)}"
    if x == round(x) and abs(x) < 1e15:
        return str(int(x))
    return f"{x:.6g}"


def fmt_value(x: float) -> str:
    """A user's value as quoted in a message: a float as Python writes it back (shortest round-trip),
    an integer in full up to 20 digits, else by its number of digits.

    Examples
    --------
    >>> [fmt_value(v) for v in (1e308, 5e-324, 2.0, -1, 10 ** 400)]
    ['1e+308', '5e-324', '2.0', '-1', 'an integer of 401 digits']
    """
    if isinstance(x, int) and not isinstance(x, bool):
        if -(10**20) < x < 10**20:
            return str(x)
        size = len(str(abs(x))) if abs(x) < 10**4000 else None  # str() of a huge integer is refused by Python
        return f"{'-' if x < 0 else ''}an integer of {size if size is not None else 'more than 4000'} digits"
    return repr(float(x))


@dataclass(frozen=True)
class Range:
    """Closed range ``[low, high]`` of a number (or of every entry of a per-joint list), with its unit.

    Parameters
    ----------
    low, high : float
        Bounds, in ``unit``.
    unit : str
        Unit of the value (``""`` for a dimensionless number).
    low_open : bool
        ``low`` itself is excluded (e.g. a level that must be above 0).
    high_open : bool
        ``high`` itself is excluded.
    zero : bool
        0 is also accepted (it means "none", e.g. no delay), besides ``[low, high]``.
    note : str
        What the value is, for the README table when the key does not say it.
    """

    low: float
    high: float
    unit: str = ""
    low_open: bool = False
    high_open: bool = False
    zero: bool = False
    note: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if not self.low <= self.high:
            raise ValueError(f"bad range [{self.low}, {self.high}]")

    def contains(self, x: float) -> bool:
        """True when ``x`` is accepted (NaN never is)."""
        if self.zero and x == 0:
            return True
        above = self.low < x if self.low_open else self.low <= x
        below = x < self.high if self.high_open else x <= self.high
        return bool(above and below)

    def describe(self) -> str:
        """The range in words, e.g. ``between 1e-6 and 1e6 (rad/s)/(N*m)``."""
        unit = f" {self.unit}" if self.unit else ""
        lo, hi = fmt_number(self.low), fmt_number(self.high)
        if self.low_open and not self.high_open:
            text = f"above {lo} and at most {hi}{unit}"
        elif self.low_open:
            text = f"strictly between {lo} and {hi}{unit}"
        elif self.high_open:
            text = f"at least {lo} and below {hi}{unit}"
        else:
            text = f"between {lo} and {hi}{unit}"
        return f"0 or {text}" if self.zero else text

    def interval(self) -> str:
        """The range as an interval, for tables: ``[1e-6, 1e6]``, ``(0, 1)``, ``0 or [1e-6, 1e9]``."""
        text = (("(" if self.low_open else "[") + f"{fmt_number(self.low)}, {fmt_number(self.high)}"
                + (")" if self.high_open else "]"))
        return f"0 or {text}" if self.zero else text

    def problem(self, x: float) -> str | None:
        """The message for a value outside the range (None inside).

        A value of the wrong sign is named as such (``must be positive``, ``must be non-negative``,
        ``must be negative``); any other value outside is given the range.
        """
        if self.contains(x):
            return None
        got = fmt_value(x)
        if not self.zero and self.low > 0 and x <= 0:
            return f"must be positive, got {got}"
        if self.low >= 0 and x < 0:
            return f"must be non-negative, got {got}"
        if self.high < 0 and x >= 0:
            return f"must be negative, got {got}"
        return f"must be {self.describe()}, got {got}"

    def check(self, value: Any) -> Any:
        """``value`` (a number, or a list of numbers: one per joint) unchanged; ``ValueError`` when outside."""
        if isinstance(value, list | tuple):
            for k, v in enumerate(value):
                msg = self.problem(v)
                if msg is not None:
                    raise ValueError(f"[{k}]: {msg}")
            return value
        if value is not None:
            msg = self.problem(value)
            if msg is not None:
                raise ValueError(msg)
        return value

    # ------------------------------------------------------------------ pydantic hooks

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> core_schema.CoreSchema:
        return core_schema.no_info_after_validator_function(self.check, handler(source))

    def __get_pydantic_json_schema__(self, schema: Any, handler: Any) -> dict[str, Any]:
        out = handler(schema)
        self._annotate(out)
        return out

    def _annotate(self, js: dict[str, Any]) -> None:
        if js.get("type") in ("number", "integer"):
            if self.zero:
                js["minimum"] = min(0.0, self.low)
            elif self.low_open:
                js["exclusiveMinimum"] = self.low
            else:
                js["minimum"] = self.low
            js["exclusiveMaximum" if self.high_open else "maximum"] = self.high
        for member in js.get("anyOf", ()):
            self._annotate(member)
        if isinstance(js.get("items"), dict):
            self._annotate(js["items"])


def Ranged(low: float, high: float, unit: str = "", *, base: Any = float, **options: Any) -> Any:
    """``Annotated[base, Range(low, high, unit, **options)]``: a field type with its range.

    Parameters
    ----------
    low, high : float
        Bounds (in ``unit``).
    unit : str
        Unit of the value.
    base : type
        The base type, validated first (``float``, ``PositiveFinite``, ``NonNegativeFinite``, ...).
    **options
        ``low_open``, ``high_open``, ``zero``, ``note`` of :class:`Range`.
    """
    return Annotated[base, Range(float(low), float(high), unit, **options)]


def RangedPerJoint(low: float, high: float, unit: str = "", **options: Any) -> Any:
    """A per-joint value (one number or one per joint) whose every entry lies in the range."""
    return Ranged(low, high, unit, base=PerJoint, **options)


def RangedInt(low: int, high: int, unit: str = "", **options: Any) -> Any:
    """An integer in ``[low, high]``."""
    return Annotated[int, Range(low, high, unit, **options)]


# ----------------------------------------------------------------------------- shared ranges

LENGTH = Range(-100.0, 100.0, "m")
"""A length or a position in the base frame (m)."""
ANGLE = Range(-2 * math.pi, 2 * math.pi, "rad")
"""A fixed angle of a robot description (rad): one turn either way."""
DURATION = Range(1e-6, 1e9, "s")
"""A duration or an instant (s): a microsecond to about 30 years."""
TORQUE = Range(1e-6, 1e6, "N*m")
"""A positive torque level (N*m): actuator limits, element levels."""
PARAMETER = Range(-1e6, 1e6, "(in the parameter's SI unit)")
"""Any named plant parameter (a built-in robot's, a DH or URDF robot's masses and frictions), in its SI unit."""

POLE_MODULUS = Range(1e-12, 1e12, "1/s")
"""Modulus ``|p|`` of a closed-loop pole (1/s)."""
POLE_SPREAD = 1e12
"""Largest ``max |p| / min |Re p|`` over a controller's poles.  Eigenvalues are computed with an
error of about ``eps * max |p|`` (``eps = 2.2e-16``): beyond this ratio the slowest decay is not
known to better than 2e-4 relative, and the sign of ``Re p`` of the slowest pole is no longer
decided by double precision (``[-1, -2, -1e6]`` spans 1e6, far inside)."""


def check_poles(poles: Sequence[complex], where: str = "") -> None:
    """Every pole's modulus within :data:`POLE_MODULUS`, and the set's spread within :data:`POLE_SPREAD`.

    Parameters
    ----------
    poles : sequence of complex
        Closed-loop poles (1/s), each already with a negative real part.
    where : str
        Key-path suffix of the list (``""``, ``"[1]"``); an entry is named ``where[k]``.

    Raises
    ------
    ValueError
        ``"[k]: |p| must be between 1e-12 and 1e12 1/s, got ..."`` or the spread of the set.
    """
    for k, p in enumerate(poles):
        if not POLE_MODULUS.contains(abs(p)):
            raise ValueError(f"{where}[{k}]: |p| must be {POLE_MODULUS.describe()}, got {fmt_pole(p)}")
    if not poles:
        return
    fast = max(abs(p) for p in poles)
    slow = min(abs(p.real) for p in poles)
    if fast > POLE_SPREAD * slow:
        prefix = f"{where}: " if where else ""
        raise ValueError(f"{prefix}the poles span more than double precision can honour: max |p| / min |Re p| = "
                         f"{fast / slow:.3g} > {fmt_number(POLE_SPREAD)} (largest |p| {fast:.4g} 1/s, slowest decay "
                         f"{slow:.4g} 1/s)")


def check_interval(name: str, bounds: tuple[float, float], rng: Range, what: str = "") -> None:
    """Both ends of an uncertainty interval ``[low, high]`` of ``name`` within the magnitudes of ``rng``.

    A bound of the wrong sign (e.g. ``Km: [0, 3]``) is left to the model layer, which refuses it with the
    same key path and the parameter's own rule; a bound too large or too small in magnitude is refused here.

    Raises
    ------
    ValueError
        ``"<name>: interval bounds must be ..., got [lo, hi]"`` (the key path is the parameter's).
    """
    lo, hi = bounds

    def wrong_sign(v: float) -> bool:
        return (rng.low > 0 and v <= 0) or (rng.low >= 0 and v < 0) or (rng.high < 0 and v >= 0)

    if all(rng.contains(v) or wrong_sign(v) for v in (lo, hi)):
        return
    of = f" ({what})" if what else ""
    raise ValueError(f"{name}: interval bounds must be {rng.describe()}{of}, got [{fmt_value(lo)}, {fmt_value(hi)}]")


def range_of(model: type[BaseModel], name: str) -> Range | None:
    """The :class:`Range` declared on field ``name`` of ``model`` (None without one)."""
    info = model.model_fields.get(name)
    if info is None:
        return None
    found = [r for _, r in ranges_in(info.annotation, info.metadata, "")]
    return found[0] if found else None


def _indices(indices: list[int], size: int) -> str:
    if len(indices) == size:
        return "[]"
    return f"[{indices[0]}]" if len(indices) == 1 else f"[{indices[0]}..{indices[-1]}]"


def ranges_in(tp: Any, metadata: Sequence[Any], path: str) -> Iterator[tuple[str, Range]]:
    """Every :class:`Range` declared in the annotation ``tp`` (with ``metadata``), with its key path under ``path``."""
    for m in metadata:
        if isinstance(m, Range):
            yield path, m
    origin = get_origin(tp)
    if origin is Annotated:
        inner, *meta = get_args(tp)
        yield from ranges_in(inner, meta, path)
    elif origin in (typing.Union, types.UnionType):
        for member in get_args(tp):
            yield from ranges_in(member, (), path)
    elif origin is tuple and Ellipsis not in get_args(tp):  # fixed length: group the entries sharing a range
        members = get_args(tp)
        groups: dict[Range, list[int]] = {}
        for k, member in enumerate(members):
            for _, rng in ranges_in(member, (), ""):
                groups.setdefault(rng, []).append(k)
        for rng, indices in groups.items():
            yield f"{path}{_indices(indices, len(members))}", rng
    elif origin in (list, tuple):
        for member in get_args(tp):
            if member is not Ellipsis:
                yield from ranges_in(member, (), f"{path}[]")
    elif origin is dict:
        yield from ranges_in(get_args(tp)[1], (), f"{path}.<name>")
