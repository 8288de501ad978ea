"""The root locus over the gain study: the closed-loop poles as each gain is scaled continuously over [0.5, 2].

The gain study (:mod:`designkit.studies.gains`) re-runs each gain at × 0.5 and × 2; this module follows the
poles in between.  For each gain knob of the family (a design gain, all joints at once), the loop of the true
plant and the family's law with that gain scaled (``family(kind).law(replace(design, gains=...))``) is
linearized at the design's operating point (:func:`designkit.synthesis.closed_loop.linearize`) at
:data:`POINTS` log-spaced scales from :data:`LOW` to :data:`HIGH`.

A law linear in its gains has a closed-loop matrix affine in each gain's scale ``s``:
``A(s) = A(1) + (s - 1) (A(2) - A(1))``.  The three matrices ``A(0.5)``, ``A(1)`` and ``A(2)`` are linearized
exactly; when ``A(0.5)`` equals the affine prediction to :data:`AFFINE_TOLERANCE` (relative to ``|A(1)|``),
the other scales are eigenvalues of the affine ``A(s)``; otherwise every scale is linearized.  The poles at
× 1 are then those of the design's own closed loop and the ends those of the × 0.5 and × 2 runs.
Each locus is ordered by following the poles from one scale to the next (nearest assignment,
:func:`scipy.optimize.linear_sum_assignment`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number

__all__ = ["AFFINE_TOLERANCE", "HIGH", "LOW", "POINTS", "GainLocus", "RootLocus", "root_locus"]

LOW, HIGH = 0.5, 2.0
"""The scale range of the locus (the gain study's ends)."""
POINTS = 41
"""Log-spaced scales per gain (odd, so that × 1 is one of them)."""
AFFINE_TOLERANCE = 1e-9
"""Relative agreement of ``A(0.5)`` with the affine prediction under which the locus is interpolated."""


@dataclass(frozen=True)
class GainLocus:
    """The closed-loop poles of one gain's scale sweep.

    Parameters
    ----------
    name, unit : str
        The gain as the design names it.
    scales : tuple of float
        :data:`POINTS` log-spaced factors from :data:`LOW` to :data:`HIGH`.
    poles : ndarray, shape (len(scales), n)
        Row ``k``: the poles (1/s) at ``scales[k]``; column ``j`` follows one pole along the scales.
    interpolated : bool
        The intermediate scales came from the affine ``A(s)`` (see the module docstring).
    """

    name: str
    unit: str
    scales: tuple[float, ...]
    poles: np.ndarray
    interpolated: bool

    def at(self, scale: float) -> np.ndarray:
        """The poles at the scale nearest ``scale``."""
        return self.poles[int(np.argmin(np.abs(np.log(np.asarray(self.scales) / scale))))]


@dataclass(frozen=True)
class RootLocus:
    """Every gain's locus, the nominal poles and sentences saying what moves where."""

    loci: tuple[GainLocus, ...]
    nominal: np.ndarray
    sentences: tuple[str, ...]


def _follow(rows: list[np.ndarray]) -> np.ndarray:
    """Rows of poles reordered so that column ``j`` moves continuously (nearest assignment, row to row)."""
    from scipy.optimize import linear_sum_assignment

    out = [np.asarray(rows[0], complex)]
    for row in rows[1:]:
        row = np.asarray(row, complex)
        cost = np.abs(out[-1][:, None] - row[None, :])
        _, cols = linear_sum_assignment(cost)
        out.append(row[cols])
    return np.vstack(out)


def _matrix(plant: Any, design: Any, name: str, scale: float, anti_windup: Any, op: dict[str, Any]) -> np.ndarray:
    from designkit.families import family
    from designkit.synthesis.closed_loop import linearize

    value = design.gains[name]
    scaled_value = value * scale if isinstance(value, float) else np.asarray(value, dtype=float) * scale
    scaled = dataclasses.replace(design, gains=design.gains.replace(**{name: scaled_value}))
    law = family(design.kind).law(scaled, anti_windup)
    return np.asarray(linearize(plant, law, op["r"], z0=[*op["x"], *op["xc"]])[0].A, float)


def _rightmost(poles: np.ndarray) -> complex:
    """The pole with the largest real part (the upper one of a pair): the slowest, or the unstable one."""
    return complex(poles[np.lexsort((-poles.imag, -poles.real))[0]])


def _pole(p: complex) -> str:
    if abs(p.imag) <= 1e-6 * max(1.0, abs(p)):  # a double real pole splits by ~sqrt(eps) |p| in eigvals
        return fmt_number(p.real, 3)
    return f"{fmt_number(p.real, 3)} ± {fmt_number(abs(p.imag), 3)}j"


def _sentence(locus: GainLocus) -> str:
    """What scaling the gain moves where: the slowest pole at each end, and the pole that moves most."""
    lo, mid, hi = locus.at(LOW), locus.at(1.0), locus.at(HIGH)
    moved = np.abs(locus.poles[-1] - locus.poles[0])
    if float(np.max(moved)) <= 1e-6 * max(1.0, float(np.max(np.abs(mid)))):
        return f"Scaling {locus.name} moves no closed-loop pole (it acts on the reference path only)."
    text = (f"Doubling {locus.name} moves the rightmost pole from {_pole(_rightmost(mid))} to "
            f"{_pole(_rightmost(hi))} 1/s, halving it to {_pole(_rightmost(lo))} 1/s")
    k = int(np.argmax(moved))
    text += (f"; the pole that moves most goes from {_pole(locus.poles[0][k])} (× 0.5) to "
             f"{_pole(locus.poles[-1][k])} 1/s (× 2)")
    unstable = [s for s, row in zip(locus.scales, locus.poles, strict=True) if np.max(row.real) >= 0]
    if unstable:
        text += f"; the loop is unstable from × {fmt_number(min(unstable), 3)} on"
    return text + "."


def root_locus(result: Any, names: Any = None, points: int = POINTS) -> RootLocus | None:
    """The closed-loop poles of every gain in ``names`` (default every gain of the design) scaled over
    [:data:`LOW`, :data:`HIGH`] (None without an exact linear loop, an operating point or gains, or when a
    linearization fails)."""
    design = result.design
    op = design.operating_point
    plant = result.plant if getattr(result, "plant", None) is not None else design.plant
    names = tuple(design.gains) if names is None else tuple(names)
    if design.closed_loop is None or design.linearization.kind != "exact" or not op or not names:
        return None
    anti_windup = result.loaded.spec.simulation.anti_windup if result.loaded.spec.simulation is not None else None
    scales = np.exp(np.linspace(np.log(LOW), np.log(HIGH), points))
    loci = []
    try:
        base = _matrix(plant, design, names[0], 1.0, anti_windup, op)
        for name in names:
            a_lo = _matrix(plant, design, name, LOW, anti_windup, op)
            a_hi = _matrix(plant, design, name, HIGH, anti_windup, op)
            step = (a_hi - base) / (HIGH - 1.0)
            affine = np.linalg.norm(a_lo - (base + (LOW - 1.0) * step)) <= AFFINE_TOLERANCE * max(
                np.linalg.norm(base), 1.0)
            rows = []
            for s in scales:
                a = base + (s - 1.0) * step if affine else _matrix(plant, design, name, float(s), anti_windup, op)
                rows.append(np.linalg.eigvals(a))
            loci.append(GainLocus(name, design.gains.unit(name), tuple(float(s) for s in scales), _follow(rows),
                                  bool(affine)))
    except (ValueError, RuntimeError, np.linalg.LinAlgError):
        return None
    nominal = np.linalg.eigvals(base)
    return RootLocus(tuple(loci), nominal, tuple(_sentence(locus) for locus in loci))
