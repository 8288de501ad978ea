"""Physically meaningful ranges of the spec's numbers, declared next to each field.

A field is declared with its bounds and unit, e.g. ``Km: Ranged(1e-6, 1e6, "(rad/s)/(N*m)",
base=PositiveFinite)``; a value outside is refused with the key path and the range::

    plant.Km: must be between 1e-6 and 1e6 (rad/s)/(N*m), got 1e+308

The ranges are wide -- far beyond any real manipulator joint -- and exist so that every accepted
value can be computed in double precision: products of poles and gains, step counts and
durations stay finite and do not underflow.  What cannot be computed whatever the bounds is
refused by a rule of its own (:func:`check_poles`: the spread of a pole set).  The README's
table of ranges is generated from these declarations (:func:`markdown_table`, run
``python -m designkit.spec.ranges``) and a test keeps it in step.

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
    "ANGLE", "DURATION", "LENGTH", "POLE_MODULUS", "POLE_SPREAD", "PARAMETER", "Range", "RangeRow", "Ranged",
    "RangedInt", "RangedPerJoint", "TORQUE", "check_interval", "check_poles", "declared_ranges", "fmt_number",
    "fmt_value",
    "markdown_table", "range_of",
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
    found = [r for _, r in _ranges_in(info.annotation, info.metadata, "")]
    return found[0] if found else None


# ----------------------------------------------------------------------------- the table


@dataclass(frozen=True)
class RangeRow:
    """One declared range.

    Parameters
    ----------
    path : str
        Key path of the value: ``[]`` stands for any index, ``[0..2]`` for some, ``<name>`` for any key.
    where : tuple of str
        The ``kind`` of each enclosing section of a union, e.g. ``("plant: link",)``.
    range : Range
        The declared range.
    """

    path: str
    where: tuple[str, ...]
    range: Range


def _indices(indices: list[int], size: int) -> str:
    if len(indices) == size:
        return "[]"
    return f"[{indices[0]}]" if len(indices) == 1 else f"[{indices[0]}..{indices[-1]}]"


def _ranges_in(tp: Any, metadata: Sequence[Any], path: str) -> Iterator[tuple[str, Range]]:
    for m in metadata:
        if isinstance(m, Range):
            yield path, m
    origin = get_origin(tp)
    if origin is Annotated:
        inner, *meta = get_args(tp)
        yield from _ranges_in(inner, meta, path)
    elif origin in (typing.Union, types.UnionType):
        for member in get_args(tp):
            yield from _ranges_in(member, (), path)
    elif origin is tuple and Ellipsis not in get_args(tp):  # fixed length: group the entries sharing a range
        members = get_args(tp)
        groups: dict[Range, list[int]] = {}
        for k, member in enumerate(members):
            for _, rng in _ranges_in(member, (), ""):
                groups.setdefault(rng, []).append(k)
        for rng, indices in groups.items():
            yield f"{path}{_indices(indices, len(members))}", rng
    elif origin in (list, tuple):
        for member in get_args(tp):
            if member is not Ellipsis:
                yield from _ranges_in(member, (), f"{path}[]")
    elif origin is dict:
        yield from _ranges_in(get_args(tp)[1], (), f"{path}.<name>")


def _models_in(tp: Any, path: str) -> Iterator[tuple[str, type[BaseModel]]]:
    origin = get_origin(tp)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        yield path, tp
    elif origin is not None:
        for arg in get_args(tp):
            sub = f"{path}[]" if origin in (list, tuple) else path
            if arg is not Ellipsis and not isinstance(arg, Range):
                yield from _models_in(arg, sub)


def _walk(model: type[BaseModel], path: str, where: tuple[str, ...]) -> Iterator[RangeRow]:
    kind = model.model_fields.get("kind")
    if kind is not None and get_origin(kind.annotation) is typing.Literal:
        section = path.rsplit(".", 1)[-1].removesuffix("[]")
        where = (*where, f"{section}: {' / '.join(get_args(kind.annotation))}")
    for name, info in model.model_fields.items():
        sub = f"{path}.{name}" if path else name
        for p, r in _ranges_in(info.annotation, info.metadata, sub):
            yield RangeRow(p, where, r)
        for p, m in _models_in(info.annotation, sub):
            yield from _walk(m, p, where)


def declared_ranges() -> tuple[RangeRow, ...]:
    """Every range declared in the spec format, walking :class:`~designkit.spec.schema.Spec` (every family)."""
    from designkit.spec.schema import Spec

    rows: list[RangeRow] = []
    for row in _walk(Spec, "", ()):
        if row not in rows:
            rows.append(row)
    return tuple(rows)


_RULES = (
    ("`controller.poles`, every pole (and the error poles that `damping` and `natural_frequency` give)",
     f"\\|p\\| in {POLE_MODULUS.interval()}", POLE_MODULUS.unit),
    ("`controller.poles`, all together", f"max \\|p\\| / min \\|Re p\\| ≤ {fmt_number(POLE_SPREAD)}", ""),
    ("`plant.uncertainty.<name>`: `[low, high]`", "low ≤ high, both in the range of the parameter (`Km`, `tau`, "
     "the elastic joint's fields; else `plant.parameters.<name>`)", ""),
)


def markdown_table() -> str:
    """The README's table of ranges (markdown), generated from the declarations.

    Rows with the same key and range are merged; the kinds they apply to are named unless the row
    holds for every kind of its section (e.g. ``plant.uncertainty.seed``).
    """
    merged: dict[tuple[str, Range], list[tuple[str, ...]]] = {}
    for row in declared_ranges():
        merged.setdefault((row.path, row.range), []).append(row.where)
    lines = ["| key | range | unit |", "|---|---|---|"]
    for (path, rng), wheres in merged.items():
        kinds: dict[str, list[str]] = {}
        for where in wheres:
            for w in where:
                section, names = w.split(": ", 1)
                kinds.setdefault(section, []).extend(n for n in names.split(" / ") if n not in kinds.get(section, []))
        shown = [f"{section}: {', '.join(names)}" for section, names in kinds.items() if len(wheres) == 1 or
                 not all(any(w.startswith(f"{section}: ") for w in where) for where in wheres) or
                 len(names) < len(_kinds_of(section))]
        ctx = f" ({'; '.join(shown)})" if shown else ""
        unit = rng.unit + (f" ({rng.note})" if rng.note else "")
        lines.append(f"| `{path}`{ctx} | {rng.interval()} | {unit} |")
    lines += [f"| {key} | {text} | {unit} |" for key, text, unit in _RULES]
    return "\n".join(lines)


def _kinds_of(section: str) -> tuple[str, ...]:
    """Every ``kind`` of a union section of the spec (``plant``, ``controller``, ``nonlinearity``, ``trajectory``)."""
    from designkit.families import FAMILIES
    from designkit.spec import plants, sections

    unions = {"plant": plants.PlantSpec, "nonlinearity": sections.Nonlinearity, "trajectory": sections.Trajectory}
    if section == "controller":
        return tuple(FAMILIES)
    if section not in unions:
        return ()
    members = get_args(get_args(unions[section])[0])
    return tuple(k for m in members for k in get_args(m.model_fields["kind"].annotation))


if __name__ == "__main__":  # pragma: no cover - prints the README table (from the imported module: its classes)
    from designkit.spec import ranges

    print(ranges.markdown_table())
