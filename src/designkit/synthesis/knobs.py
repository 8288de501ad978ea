"""What a family lets a study vary and measure: its knobs and its meaningful metrics.

A **knob** is a setting a study may change, everything else equal: a spec setting (``controller.gamma``, an
adaptation gain; ``controller.learning.alpha``, a learning gain) or a gain of the design (``K1`` of a PID, all
joints scaled at once).  A family declares its knobs on its :class:`~designkit.synthesis.family.Family`, with
the range a study may take them over (the values the family's design and its run are meant for) and their
role: a fixed ``gain``, an ``adaptation`` or ``learning`` gain, a ``forgetting`` factor, a ``switching``
amplitude.  A study (:mod:`designkit.studies`) changes one knob, runs the result through the family's own run
(its trials, its adaptation, its held step) with the family's own checks, and measures it with the family's
**metrics**: the numbers that are meaningful for the law (the error against the reference model of an MRAC,
the last trial's error of a learning law, the settled error of a switching law), each a function of the run.
A **variant** is a named change of the spec that is not a number to scale: another form of the law (an ad hoc
modification of an adaptive rule, its safeguards turned off), sized from the run it varies; a study runs it
through the family's own run as it runs a knob's value.

Nothing here runs anything: these are declarations, read above the families.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["COMMAND_VARIATION", "GAIN_FACTORS", "ROLES", "SETTLED_ERROR", "VARIANT_ROLES", "Knob", "Metric",
           "Variant", "gain_knobs"]

ROLES = ("gain", "adaptation", "learning", "forgetting", "switching")
"""What a knob is to its law: a fixed gain, an adaptation gain, a learning gain, a forgetting factor (its
complement ``1 - lambda`` is what a study scales), or a switching amplitude."""


@dataclass(frozen=True)
class Knob:
    """A setting a study may vary (module docstring).

    Parameters
    ----------
    name : str
        How the report names it (``"γ"``, ``"K1"``, ``"α"``).
    unit : str
        Its SI unit (``"1/s"``, ``"N*m/rad"``; ``""`` when dimensionless).
    meaning : str
        What it does, in a few words (``"adaptation gain of the gradient rule"``).
    low, high : float
        The range a study may take it over (its unit; for a ``gain`` knob, factors of the design's value).
    path : str
        The spec key path it sets (``"controller.gamma"``); ``""`` for a design gain.
    gain : str
        The design gain it scales (``"K1"``, every joint at once); ``""`` for a spec setting.
    role : str
        One of :data:`ROLES`.
    boundary : bool
        A study seeks where the loop's required checks stop passing as it varies (an adaptation, learning or
        switching gain), on a grid over ``[low, high]``.
    factors : tuple of float
        The gain study's factors on the value in use (default halved and doubled); for a ``forgetting`` knob
        they apply to ``1 - lambda``.
    current : callable or None
        ``design -> float``: the value in use when the spec leaves the setting out (a learning gain the family
        computes); None reads the spec (or the design's gain).
    search : callable or None
        ``design -> (low, high)``: where a boundary study searches by default, when the declared range is wider than
        the scenario needs and the family knows the scale from the design (a learning gain's ``1/sigma_max(H)^2``);
        a function of the design's scenario only, never of the knob's own value, so two specs that differ only in
        it search the same range.  None: the declared range.
    when : callable or None
        ``design -> bool``: whether the knob applies to this design (a learning gain of one update form only).
    """

    name: str
    unit: str
    meaning: str
    low: float
    high: float
    path: str = ""
    gain: str = ""
    role: str = "gain"
    boundary: bool = False
    factors: tuple[float, ...] = (0.5, 2.0)
    current: Callable[[Any], float] | None = None
    search: Callable[[Any], tuple[float, float]] | None = None
    when: Callable[[Any], bool] | None = None

    def __post_init__(self) -> None:
        if bool(self.path) == bool(self.gain):
            raise ValueError(f"knob {self.name!r}: give exactly one of path (a spec setting) or gain (a design gain)")
        if self.role not in ROLES:
            raise ValueError(f"knob {self.name!r}: role must be one of {ROLES}, got {self.role!r}")
        if not (math.isfinite(self.low) and math.isfinite(self.high) and 0 < self.low < self.high):
            raise ValueError(f"knob {self.name!r}: needs 0 < low < high, got [{self.low}, {self.high}]")
        if self.role == "forgetting" and self.high > 1:
            raise ValueError(f"knob {self.name!r}: a forgetting factor lies in (0, 1]")
        object.__setattr__(self, "factors", tuple(float(f) for f in self.factors))
        if not self.factors or any(not (math.isfinite(f) and f > 0) or f == 1.0 for f in self.factors):
            raise ValueError(f"knob {self.name!r}: factors must be positive, finite and other than 1")

    def applies(self, design: Any) -> bool:
        """Whether the knob applies to ``design`` (:attr:`when`)."""
        return self.when is None or bool(self.when(design))

    @property
    def key(self) -> str:
        """The name a spec's ``studies`` section and ``--json`` use: the spec path's last key or the gain."""
        return self.gain or self.path.rsplit(".", 1)[-1]

    def scaled(self, value: float, factor: float) -> float:
        """``value`` moved by ``factor`` (a ``forgetting`` factor: ``1 - (1 - value) * factor``)."""
        if self.role == "forgetting":
            return 1.0 - (1.0 - value) * factor
        return value * factor

    def inside(self, value: complex) -> bool:
        """Whether ``|value|`` lies in the declared range (a ``gain`` knob's range is of factors; a pole's of its
        modulus)."""
        return self.low * (1 - 1e-12) <= abs(value) <= self.high * (1 + 1e-12)


VARIANT_ROLES = ("modification",)
"""What a variant is to its law: an ad hoc ``modification`` of the off-the-shelf algorithm (a normalised or dead-zoned
adaptation, a projection of the adapted parameters, a safeguard turned on or off)."""

GAIN_FACTORS = (0.01, 100.0)
"""The range of a design gain's knob, as factors on the designed value."""


def gain_knobs(info: Any, names: Any) -> tuple[Knob, ...]:
    """One ``gain`` knob per design gain in ``names``, unit and meaning from ``info`` (name -> ``(unit,
    meaning)``), each over :data:`GAIN_FACTORS` of its designed value."""
    return tuple(Knob(n, info[n][0], info[n][1], *GAIN_FACTORS, gain=n) for n in names)


@dataclass(frozen=True)
class Metric:
    """A number meaningful for a family's law, measured on a run.

    Parameters
    ----------
    key : str
        Its name in ``--json`` (``"model_error_rms"``).
    label : str
        How the report names it (``"RMS error against the reference model"``).
    unit : str
        Its unit (``"rad"``; ``""`` when dimensionless).
    measure : callable
        ``run -> float | None``: the value on a run (the runner's value: ``design``, ``simulation``,
        ``trials``, ``checks``); None when the run does not define it.
    meaning : str
        How it is computed, one sentence.
    better : {"lower", "higher"}
    """

    key: str
    label: str
    unit: str
    measure: Callable[[Any], float | None]
    meaning: str = ""
    better: str = "lower"

    def __post_init__(self) -> None:
        if self.better not in ("lower", "higher"):
            raise ValueError(f"metric {self.key!r}: better must be 'lower' or 'higher'")

    def value(self, run: Any) -> float | None:
        """The metric on ``run``: a finite float, ``inf`` for a run that diverged, or None when undefined."""
        try:
            v = self.measure(run)
        except (ValueError, ArithmeticError):  # a diverged run's empty or overflowing record
            return None
        if v is None:
            return None
        v = float(v)
        return v if math.isfinite(v) else math.inf


SETTLED_FRACTION = 0.1
"""The settled error is measured over this last fraction of the run."""


def _settled(run: Any) -> float | None:
    import numpy as np

    sim = run.simulation
    if sim is None:
        return None
    t = np.asarray(sim.time, dtype=float)
    e = np.abs(np.asarray(sim.tracking_errors, dtype=float).reshape(t.size, -1))
    tail = e[t >= t[-1] - SETTLED_FRACTION * (t[-1] - t[0])]
    return float(np.max(np.mean(tail, axis=0))) if np.all(np.isfinite(tail)) else math.inf


def _variation(run: Any) -> float | None:
    import numpy as np

    sim = run.simulation
    if sim is None:
        return None
    t = np.asarray(sim.time, dtype=float)
    u = np.asarray(sim.u_command, dtype=float).reshape(t.size, -1)
    if not np.all(np.isfinite(u)) or t[-1] <= t[0]:
        return math.inf
    return float(np.max(np.sum(np.abs(np.diff(u, axis=0)), axis=0)) / (t[-1] - t[0]))


SETTLED_ERROR = Metric("settled_error", "settled error", "rad", _settled,
                       f"mean |x − xD| over the last {SETTLED_FRACTION:.0%} of the run, the largest over the "
                       "tracked coordinates: the precision a switching law holds")
"""The precision a law holds at the end of its run (a switching law's sliding precision)."""
COMMAND_VARIATION = Metric("command_variation", "command variation per second", "input/s", _variation,
                           "total variation of the command over the run divided by its length, the largest over "
                           "the inputs: how hard the actuator works (a chattering relay's cost)")
"""How hard the actuator works: the command's total variation per second."""


@dataclass(frozen=True)
class Variant:
    """A named change of the spec a study may run (module docstring).

    Parameters
    ----------
    key : str
        Its name in ``--json`` and in the report's tables (``"normalized"``).
    label : str
        The variant in words (``"normalised gradient rule"``).
    meaning : str
        What it changes and how it was sized, one sentence with the formula.
    changes : callable
        ``run -> tuple of (key path, value)``: the spec's settings to set (a value of None removes the key), sized
        from ``run`` (the run varied: its spec, design and simulation); an empty tuple when the variant does not
        apply to that run (the spec already has it).
    role : str
        One of :data:`VARIANT_ROLES`.
    """

    key: str
    label: str
    meaning: str
    changes: Callable[[Any], tuple[tuple[str, Any], ...]]
    role: str = "modification"

    def __post_init__(self) -> None:
        if self.role not in VARIANT_ROLES:
            raise ValueError(f"variant {self.key!r}: role must be one of {VARIANT_ROLES}, got {self.role!r}")

    def changes_for(self, run: Any) -> tuple[tuple[str, Any], ...]:
        """The key paths and values that make ``run``'s spec this variant (empty: it does not apply)."""
        return tuple((str(path), value) for path, value in self.changes(run))
