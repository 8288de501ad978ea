"""What the tuner moves: the family's knobs that are spec settings, as coordinates in log space.

A knob (:class:`~designkit.synthesis.knobs.Knob`) that sets a key path of the spec (``controller.poles``,
``controller.zero``, ``controller.gamma``, ``controller.M``) is tuned; a design-gain knob (``K1``, every joint
scaled) is not, since a spec cannot carry a gain the family computes, and the tuned spec must be re-runnable as it
is.  A list of poles becomes one coordinate per real pole (``log |p|``) and two per complex pair (``log(-Re p)``,
``log(Im p)``), so that every candidate stays in the left half plane with the pair structure of the starting
poles; a zero or a positive setting becomes ``log |v|``, one coordinate per joint when the spec gives one value
per joint.  A forgetting factor (a value in (0, 1]) is not tuned.

The range of a coordinate is the spec's ``tune.ranges`` for its knob (a pole's or zero's modulus, 1/s; a
setting's value in its unit), else a decade either side of the starting value, inside the knob's declared range.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Coordinate", "Space", "build_space"]

DECADE = 10.0
"""Default range of a coordinate: its starting value divided and multiplied by this factor."""


@dataclass(frozen=True)
class Coordinate:
    """One number the tuner moves.

    Parameters
    ----------
    knob : str
        The knob's key (``poles``, ``zero``, ``gamma``).
    label : str
        The number in words (``poles[0]``, ``Re poles[1]``, ``Im poles[1]``, ``zero[1]``).
    unit : str
        Its unit (1/s for a pole's part).
    initial : float
        Its starting value (positive: a magnitude).
    low, high : float
        Its range (positive, ``low < high``).
    """

    knob: str
    label: str
    unit: str
    initial: float
    low: float
    high: float


@dataclass(frozen=True)
class _Slot:
    """How one knob's coordinates map back to its spec value."""

    knob: str
    path: str
    shape: str  # "poles", "poles_nested", "negative", "positive", "negative_list", "positive_list"
    layout: tuple[Any, ...]  # poles: per group, per entry "r" or "c"; lists: length
    start: int
    count: int


@dataclass(frozen=True)
class Space:
    """The coordinates of a tuning problem and how they become spec changes.

    Parameters
    ----------
    coordinates : tuple of Coordinate
        What is tuned, in order.
    slots : tuple
        One per tuned knob: its key path and how its coordinates rebuild its value.
    fixed : tuple of (str, object)
        Key paths written with a fixed value in every candidate (a derived value the spec left out, such as the
        zero placed on the third pole, which must be written once the poles are).
    kept : tuple of str
        Knobs not tuned, each with the reason.
    """

    coordinates: tuple[Coordinate, ...]
    slots: tuple[_Slot, ...]
    fixed: tuple[tuple[str, Any], ...]
    kept: tuple[str, ...]

    @property
    def x0(self) -> np.ndarray:
        """The starting point (log of each coordinate's value)."""
        return np.log([c.initial for c in self.coordinates])

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds in log space."""
        return (np.log([c.low for c in self.coordinates]), np.log([c.high for c in self.coordinates]))

    def values(self, x: np.ndarray) -> dict[str, Any]:
        """Knob key -> its spec value at the log-space point ``x`` (clipped to the bounds)."""
        lo, hi = self.bounds
        v = np.exp(np.clip(np.asarray(x, dtype=float), lo, hi))
        out: dict[str, Any] = {}
        for slot in self.slots:
            part = v[slot.start:slot.start + slot.count]
            out[slot.knob] = _rebuild(slot, part)
        return out

    def changes(self, x: np.ndarray) -> list[tuple[str, Any]]:
        """The ``(key path, value)`` changes of the spec at ``x``."""
        values = self.values(x)
        return [*self.fixed, *((s.path, values[s.knob]) for s in self.slots)]


def _rebuild(slot: _Slot, part: np.ndarray) -> Any:
    if slot.shape in ("poles", "poles_nested"):
        groups, k = [], 0
        for kinds in slot.layout:
            poles: list[Any] = []
            for kind in kinds:
                if kind == "r":
                    poles.append(-float(part[k]))
                    k += 1
                else:
                    re, im = -float(part[k]), float(part[k + 1])
                    poles += [complex(re, im), complex(re, -im)]
                    k += 2
            groups.append(poles)
        return groups if slot.shape == "poles_nested" else groups[0]
    sign = -1.0 if slot.shape.startswith("negative") else 1.0
    vals = [sign * float(p) for p in part]
    return vals if slot.shape.endswith("_list") else vals[0]


def _pole_layout(poles: list[complex]) -> tuple[str, ...]:
    """``"r"`` per real pole, ``"c"`` per conjugate pair (the pair's upper member kept)."""
    kinds, seen = [], set()
    for i, p in enumerate(poles):
        if i in seen:
            continue
        if abs(p.imag) <= 1e-12 * max(1.0, abs(p)):
            kinds.append(("r", p))
            continue
        j = next((j for j in range(i + 1, len(poles)) if j not in seen and abs(poles[j] - p.conjugate()) <= 1e-9 *
                  max(1.0, abs(p))), None)
        if j is None:
            raise ValueError(f"pole {p} has no conjugate")
        seen.add(j)
        kinds.append(("c", complex(p.real, abs(p.imag))))
    return tuple(kinds)


def _initial(knob: Any, spec: Any, design: Any) -> Any:
    """The knob's value in use: the spec's, the family's computed one, or the design's poles and zero."""
    from designkit.runner.variants import knob_value

    value = knob_value(knob, spec, design)
    if value is not None:
        return value
    key = knob.key
    loops = getattr(design, "loops", ()) or ()
    if key == "poles":
        if design.poles:
            return np.asarray(design.poles)
        if loops and loops[0].poles:
            return np.asarray(loops[0].poles)
    if key == "zero":
        if design.zeros:
            return float(np.real(design.zeros[0]))
        if loops and loops[0].zeros:
            return float(np.real(loops[0].zeros[0]))
    return None


def _range(knob: Any, magnitude: float, ranges: dict[str, list[float]]) -> tuple[float, float]:
    if knob.key in ranges:
        lo, hi = ranges[knob.key]
        return float(lo), float(hi)
    lo, hi = magnitude / DECADE, magnitude * DECADE
    if knob.role != "gain" or knob.path:
        lo, hi = max(lo, knob.low), min(hi, knob.high)
    return lo, hi


def build_space(loaded: Any, design: Any, knobs: tuple[Any, ...], settings: Any) -> Space:
    """The tuning space of a spec (module docstring).

    Parameters
    ----------
    loaded : LoadedSpec
        The spec tuned.
    design : Design
        Its design (the values in use where the spec leaves a knob out).
    knobs : tuple of Knob
        The family's knobs.
    settings : Tune or None
        The spec's ``tune`` section.

    Raises
    ------
    SpecError
        ``tune.fixed[i]`` or ``tune.ranges.<name>`` naming no knob of the family, a range outside the knob's declared
        one, or nothing left to tune.
    """
    from designkit.errors import SpecError

    spec = loaded.spec
    kind = spec.controller.kind
    fixed_names = list(settings.fixed) if settings is not None else []
    ranges = dict(settings.ranges) if settings is not None else {}
    applying = [k for k in knobs if k.applies(design)]
    names = [k.key for k in applying]
    words = ", ".join(names) or "none"
    for i, name in enumerate(fixed_names):
        if name not in names:
            raise SpecError(f"tune.fixed[{i}]", f"the {kind} family has no knob {name!r}; its knobs are {words}")
    for name, (lo, hi) in ranges.items():
        knob = next((k for k in applying if k.key == name), None)
        if knob is None:
            raise SpecError(f"tune.ranges.{name}", f"the {kind} family has no knob {name!r}; its knobs are {words}")
        if knob.path and (lo < knob.low * (1 - 1e-12) or hi > knob.high * (1 + 1e-12)):
            raise SpecError(f"tune.ranges.{name}", f"[{lo:g}, {hi:g}] leaves the knob's declared range "
                            f"[{knob.low:g}, {knob.high:g}] {knob.unit}".rstrip())
    coords: list[Coordinate] = []
    slots: list[_Slot] = []
    fixed: list[tuple[str, Any]] = []
    kept: list[str] = []
    for knob in applying:
        if knob.gain:
            kept.append(f"{knob.key}: a design gain the spec cannot carry (the tuner moves spec settings)")
            continue
        if knob.role == "forgetting":
            kept.append(f"{knob.key}: a forgetting factor, not tuned")
            continue
        value = _initial(knob, spec, design)
        if value is None:
            kept.append(f"{knob.key}: no value in use to start from")
            continue
        given = _given(spec, knob.path)
        if not given and (why := _refused(loaded, knob, value)):
            kept.append(f"{knob.key}: not given in the spec, which cannot carry the value in use ({why}); give it "
                        "in the spec to tune it")
            continue
        if knob.key in fixed_names:
            if not given:
                fixed.append((knob.path, _plain_value(knob, value)))
            kept.append(f"{knob.key}: fixed by tune.fixed")
            continue
        start = len(coords)
        if knob.key.endswith("poles"):
            arr = np.asarray(value)
            nested = arr.ndim == 2
            groups = [list(map(complex, row)) for row in (arr if nested else [arr])]
            layout = []
            for g, poles in enumerate(groups):
                kinds = _pole_layout(poles)
                layout.append(tuple(k for k, _ in kinds))
                for j, (k, p) in enumerate(kinds):
                    where = f"[{g}][{j}]" if nested else f"[{j}]"
                    if k == "r":
                        mag = abs(p.real)
                        coords.append(Coordinate(knob.key, f"{knob.key}{where}", knob.unit, mag, *_range(
                            knob, mag, ranges)))
                    else:
                        for part, mag in (("Re", -p.real), ("Im", p.imag)):
                            coords.append(Coordinate(knob.key, f"{part} {knob.key}{where}", knob.unit, mag,
                                                     *_range(knob, mag, ranges)))
            slots.append(_Slot(knob.key, knob.path, "poles_nested" if nested else "poles", tuple(layout), start,
                               len(coords) - start))
            continue
        arr = np.atleast_1d(np.asarray(value, dtype=float))
        if np.any(arr == 0) or (np.any(arr < 0) and np.any(arr > 0)):
            kept.append(f"{knob.key}: a value of mixed or zero sign, not tuned in log space")
            continue
        sign = "negative" if arr[0] < 0 else "positive"
        listed = np.ndim(value) > 0
        for j, v in enumerate(arr):
            mag = abs(float(v))
            label = f"{knob.key}[{j}]" if listed else knob.key
            coords.append(Coordinate(knob.key, label, knob.unit, mag, *_range(knob, mag, ranges)))
        slots.append(_Slot(knob.key, knob.path, sign + ("_list" if listed else ""), (len(arr),), start,
                           len(coords) - start))
    for c in coords:
        if not c.low < c.high:
            raise SpecError(f"tune.ranges.{c.knob}", f"empty range for {c.label}: [{c.low:g}, {c.high:g}]")
    if not coords:
        raise SpecError("tune", f"nothing to tune: the {kind} family's knobs are {words}; "
                        + ("; ".join(kept) if kept else "none is a spec setting"))
    coords = [Coordinate(c.knob, c.label, c.unit, min(max(c.initial, c.low), c.high), c.low, c.high)
              for c in coords]
    coords = _apart(coords)
    return Space(tuple(coords), tuple(slots), tuple(fixed), tuple(kept))


def _apart(coords: list[Coordinate]) -> list[Coordinate]:
    """A zero the family placed on a pole (the third pole of a derived design) started 1e-6 off it: a spec may not
    name a zero equal to a pole, and the response is the same to that precision."""
    poles = [c.initial for c in coords if c.knob.endswith("poles")]
    out = []
    for c in coords:
        if c.knob == "zero" and any(abs(c.initial - p) <= 1e-9 * p for p in poles):
            c = Coordinate(c.knob, c.label, c.unit, min(c.initial * (1 + 1e-6), c.high), c.low, c.high)
        out.append(c)
    return out


def _refused(loaded: Any, knob: Any, value: Any) -> str:
    """Why the spec cannot carry ``knob`` at the value in use the design gave (the spec sets it another way, as a
    damping and a natural frequency instead of poles, or in another shape); ``""`` when it can."""
    from designkit.errors import SpecError
    from designkit.runner.variants import changed_spec

    try:
        changed_spec(loaded, [(knob.path, _plain_value(knob, value))])
    except SpecError as exc:
        return str(exc)
    return ""


def _given(spec: Any, path: str) -> bool:
    from designkit.runner.variants import spec_value

    return spec_value(spec, path) is not None


def _plain_value(knob: Any, value: Any) -> Any:
    arr = np.asarray(value)
    if np.iscomplexobj(arr) and np.all(np.imag(arr) == 0):
        arr = np.real(arr)
    if arr.ndim == 0:
        v = arr.item()
        return float(v) if not isinstance(v, complex) else v
    return [complex(v) if isinstance(v, complex) and v.imag else float(np.real(v)) for v in arr.tolist()] \
        if arr.ndim == 1 else [[complex(v) if isinstance(v, complex) and v.imag else float(np.real(v)) for v in row]
                               for row in arr.tolist()]
