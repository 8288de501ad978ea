"""The README's table of value ranges, generated from the ranges declared on the spec's fields.

It walks the assembled :class:`~designkit.schema.spec.Spec` (every registered family's controller
section), so it sits above the families; the range types themselves are :mod:`designkit.spec.ranges`.
"""

from __future__ import annotations

import typing
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, get_args, get_origin

from pydantic import BaseModel

from designkit.spec.ranges import POLE_MODULUS, POLE_SPREAD, Range, fmt_number, ranges_in

__all__ = ["RangeRow", "declared_ranges", "markdown_table"]

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
        for p, r in ranges_in(info.annotation, info.metadata, sub):
            yield RangeRow(p, where, r)
        for p, m in _models_in(info.annotation, sub):
            yield from _walk(m, p, where)


def declared_ranges() -> tuple[RangeRow, ...]:
    """Every range declared in the spec format, walking :class:`~designkit.schema.spec.Spec` (every family)."""
    from designkit.schema.spec import assembled

    rows: list[RangeRow] = []
    for row in _walk(assembled(), "", ()):
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
    from designkit.schema import ranges_table

    print(ranges_table.markdown_table())
