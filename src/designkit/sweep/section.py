"""The optional ``sweep:`` section of a spec, and reading a spec that carries one.

The section is the sweep's own (``designkit synth`` does not read it): it is taken out of the YAML
before the rest is validated as a design spec, so the worst cases written back are plain design specs.

Keys (each ranged; a wrong one is refused with its key path)::

    sweep:
      distribution: uniform     # uniform (on the box) | normal (centred, cut) | corners (the box's corners)
      cut: 3                    # normal: the box's half-width is this many standard deviations (0.5 to 10)
      parameters: {m2: [2, 4]}  # intervals of named plant parameters, added to / replacing plant.uncertainty,
                                # checked as plant.uncertainty's are (designkit.sweep.sampling.check_box)
      initial_position: [[-0.2, 0.2], [-0.1, 0.1]]   # per joint, rad (or m): the run's start, sampled
      payload: {mass: [0, 1.5], link: 2}            # kg at the centre of mass of a link (default the last)
      noise: true               # each sample its own noise seed (needs simulation.noise)
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import Field, field_validator

from designkit.errors import SpecError
from designkit.spec.fields import Section
from designkit.spec.ranges import Ranged, RangedInt

__all__ = ["LoadedSweep", "SweepSection", "load_sweep", "parse_sweep"]

_TOP_KEY = re.compile(r"^[^\s#-][^:]*:")


class Payload(Section):
    """A sampled payload: ``mass`` an interval (kg, 0 to 1e4), ``link`` 1-based (default the last)."""

    mass: list[Ranged(0, 1e4, "kg")] = Field(min_length=2, max_length=2)
    link: RangedInt(1, 1000) | None = None

    @field_validator("mass")
    @classmethod
    def _ordered(cls, v: list[float]) -> list[float]:
        if v[0] > v[1]:
            raise ValueError(f"must be [low, high] with low <= high, got [{v[0]:g}, {v[1]:g}]")
        return v


class SweepSection(Section):
    """What a sweep samples beyond ``plant.uncertainty`` (module docstring)."""

    distribution: Literal["uniform", "normal", "corners"] = "uniform"
    cut: Ranged(0.5, 10, "standard deviations") = 3.0
    parameters: dict[str, Any] = Field(default_factory=dict)
    initial_position: list[list[Ranged(-100, 100, "rad or m")]] | None = None
    payload: Payload | None = None
    noise: bool = False

    @field_validator("initial_position")
    @classmethod
    def _joints(cls, v: list[list[float]] | None) -> list[list[float]] | None:
        for k, interval in enumerate(v or []):
            if len(interval) != 2 or interval[0] > interval[1]:
                raise ValueError(f"[{k}]: must be an interval [low, high] (rad) with low <= high, got {interval!r}")
        return v


@dataclass(frozen=True)
class LoadedSweep:
    """A design spec and its sweep section.

    Parameters
    ----------
    loaded : LoadedSpec
        The spec without its ``sweep:`` section, validated as a design spec.
    section : SweepSection
        The sweep section (its defaults when the spec has none).
    text : str
        The design spec's YAML text (the ``sweep:`` block cut out, comments kept).
    path : str
        Where it was read from.
    """

    loaded: Any
    section: SweepSection
    text: str
    path: str


def _without_block(text: str) -> str:
    """``text`` with its top-level ``sweep:`` block cut out (the lines up to the next top-level key)."""
    out, inside = [], False
    for line in text.splitlines(keepends=True):
        if _TOP_KEY.match(line):
            inside = line.split(":", 1)[0].strip().strip("'\"") == "sweep"
        if not inside:
            out.append(line)
    return "".join(out)


def parse_sweep(text: str, *, path: str = "<string>") -> LoadedSweep:
    """Read YAML text holding a design spec and an optional ``sweep:`` section.

    Raises
    ------
    SpecError
        The design spec's own errors (its key paths), or ``sweep.<key>`` for the section.
    """
    import yaml
    from pydantic import ValidationError

    from designkit.schema.loader import MAX_SPEC_BYTES, load_yaml, parse_spec

    if not isinstance(text, str):
        raise SpecError("text", f"expected the YAML text of a spec (str), got {type(text).__name__}")
    if len(text) > MAX_SPEC_BYTES:
        return LoadedSweep(loaded=parse_spec(text, path=path), section=SweepSection(), text=text, path=path)
    raw = load_yaml(text)  # the spec format's reading (numbers, limits) for the sweep section too
    block = raw.get("sweep") if isinstance(raw, dict) else None
    body = text
    if isinstance(raw, dict) and "sweep" in raw:
        body = _without_block(text)
        try:
            rest = load_yaml(body)
        except SpecError:  # the cut left no valid YAML: the rest is written out again below
            rest = None
        if not isinstance(rest, dict) or "sweep" in rest or rest != {k: v for k, v in raw.items() if k != "sweep"}:
            body = yaml.safe_dump({k: v for k, v in raw.items() if k != "sweep"}, sort_keys=False)
    loaded = parse_spec(body, path=path)
    if block is None:
        block = {}
    if not isinstance(block, dict):
        raise SpecError("sweep", f"must be a mapping of sweep settings, got {type(block).__name__}")
    try:
        section = SweepSection.model_validate(block)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = ".".join(str(p) if not isinstance(p, int) else f"[{p}]" for p in err["loc"]).replace(".[", "[")
        msg = err["msg"].removeprefix("Value error, ")
        raise SpecError(f"sweep.{loc}" if loc else "sweep", msg) from None
    return LoadedSweep(loaded=loaded, section=section, text=body, path=path)


def load_sweep(path: Any) -> LoadedSweep:
    """Read a spec file with an optional ``sweep:`` section (:func:`parse_sweep`)."""
    from pathlib import Path

    from designkit.schema.loader import MAX_SPEC_BYTES, load_spec

    p = Path(path)
    try:
        with p.open("rb") as fh:
            data = fh.read(MAX_SPEC_BYTES + 1)
        text = data.decode("utf-8")
    except (OSError, UnicodeDecodeError):
        load_spec(p)  # names what is wrong with the file, as for any spec
        raise
    if len(data) > MAX_SPEC_BYTES:
        load_spec(p)  # refuses the size, as for any spec
    return parse_sweep(text.replace("\r\n", "\n").replace("\r", "\n"), path=str(p))
