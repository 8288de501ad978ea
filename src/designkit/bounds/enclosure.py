"""The proven range of one entry of a CasADi function over a box: :func:`enclose`.

The result is a certified enclosure ``[lower, upper]`` of ``{f(x) : x in box}`` -- every value lies
in it, with outward rounding by Arb ball arithmetic (:mod:`designkit.bounds.tape`) -- and, for
each end, a witness point where ``f`` is evaluated and comes within the tolerance of that end
(:mod:`designkit.bounds.search`).  So a report can state the bound, the best value found and the
gap between them.

Honest limits.  A wide box or an expression in which a variable occurs many times (the dependency
effect) gives wide enclosures that only bisection tightens; the work grows with the number of free
entries ``d`` roughly as ``(1/tol)^(d'/2)``, ``d'`` the entries along which the extremum is not on a
face (the mean-value form's error is quadratic in the width, monotone entries are reduced to a
face).  The search stops at ``max_boxes`` per end: with ``strict`` (the default) that is refused,
naming the tolerance and the gap reached; otherwise the result says ``converged = False`` and its
bounds still hold.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit import arguments
from designkit.bounds.box import Box
from designkit.bounds.forms import ScalarProblem, scalar_expression
from designkit.bounds.search import Side, maximize
from designkit.errors import SpecError

__all__ = ["Enclosure", "enclose", "MAX_BOXES"]

MAX_BOXES = 20000
"""Default work limit: boxes evaluated per end of the range."""


@dataclass(frozen=True, eq=False)
class Enclosure:
    """A proven range of ``f`` over a box, with the witnesses of both ends.

    Parameters
    ----------
    label : str
        What was enclosed (``"M[1, 1]"``).
    box : Box
    low, high : Side
        The minimum's and the maximum's search.
    rel_tol, abs_tol : float
        The requested gap ``bound - value <= abs_tol + rel_tol |value|`` per end.
    seconds : float
        Wall time of the two searches (s).
    """

    label: str
    box: Box
    low: Side
    high: Side
    rel_tol: float
    abs_tol: float
    seconds: float

    @property
    def lower(self) -> float:
        """Proven: ``f(x) >= lower`` for every ``x`` of the box."""
        return self.low.bound

    @property
    def upper(self) -> float:
        """Proven: ``f(x) <= upper`` for every ``x`` of the box."""
        return self.high.bound

    @property
    def min_value(self) -> float:
        """``f(argmin)``: attained, within the gap of ``lower``."""
        return self.low.value

    @property
    def max_value(self) -> float:
        """``f(argmax)``: attained, within the gap of ``upper``."""
        return self.high.value

    @property
    def argmin(self) -> dict[str, np.ndarray]:
        """The minimum's witness, input name -> entries."""
        return self.box.split(self.low.witness)

    @property
    def argmax(self) -> dict[str, np.ndarray]:
        """The maximum's witness, input name -> entries."""
        return self.box.split(self.high.witness)

    @property
    def boxes(self) -> int:
        """Boxes evaluated for both ends."""
        return self.low.boxes + self.high.boxes

    @property
    def converged(self) -> bool:
        """Both ends stopped on the tolerance (or the decision), not on the work limit."""
        return self.low.stop != "work limit" and self.high.stop != "work limit"

    def __repr__(self) -> str:
        return (f"Enclosure({self.label} in [{self.lower:.9g}, {self.upper:.9g}], attained "
                f"[{self.min_value:.9g}, {self.max_value:.9g}], {self.boxes} boxes)")


def _tolerances(rel_tol: float, abs_tol: float, max_boxes: int) -> tuple[float, float, int]:
    return (arguments.number(rel_tol, "rel_tol", positive=True), arguments.number(abs_tol, "abs_tol", low=0.0),
            arguments.integer(max_boxes, "max_boxes", low=1, high=10**9))


def _thresholds(value: object) -> tuple[float | None, float | None]:
    if isinstance(value, str | bytes) or not isinstance(value, tuple | list) or len(value) != 2:
        raise SpecError("thresholds", f"must be a pair (low, high) of numbers or None, got {type(value).__name__}")
    low, high = (None if v is None else arguments.number(v, f"thresholds[{k}]", finite=False)
                 for k, v in enumerate(value))
    return low, high


def enclose(function: Any, box: Mapping[str, Any], *, output: int | str = 0, index: Any = None,
            rel_tol: float = 1e-3, abs_tol: float = 0.0, max_boxes: int = MAX_BOXES, strict: bool = True,
            thresholds: tuple[float | None, float | None] = (None, None)) -> Enclosure:
    """The proven range of one entry of ``function`` over ``box``.

    Parameters
    ----------
    function : casadi.Function
        SX, or MX that expands to SX; every input must be bounded by ``box``.
    box : Mapping
        Input name -> ``(lo, hi)`` or a fixed value (:meth:`designkit.bounds.box.Box.of`), in the inputs' units.
    output : int or str
        Which output (number or name).
    index : int or (int, int), optional
        The entry of that output (omit for a scalar output).
    rel_tol, abs_tol : float
        Per end, ``bound - value <= abs_tol + rel_tol |value|`` (in the output's unit for ``abs_tol``).
    max_boxes : int
        Work limit per end.
    strict : bool
        Refuse (:class:`~designkit.errors.SpecError` naming ``rel_tol``) when the limit is reached
        before the tolerance; otherwise return the unconverged, still valid, enclosure.
    thresholds : (float or None, float or None)
        Decide ``f > low`` and ``f < high`` on the box as well (search each end until decided).

    Returns
    -------
    Enclosure

    Examples
    --------
    The two-link arm's ``D_11 = a + 2 b cos q2`` over ``q2`` in ``[-1, 2]`` rad:

    >>> import casadi as ca
    >>> q = ca.SX.sym("q", 2)
    >>> f = ca.Function("D11", [q], [3.0 + 2 * 0.5 * ca.cos(q[1])], ["q"], ["D11"])
    >>> e = enclose(f, {"q": ([0, -1], [0, 2])}, rel_tol=1e-6)
    >>> round(e.upper, 5), round(e.lower, 5)
    (4.0, 2.58385)
    >>> e.lower <= 3 + ca.cos(2).__float__() <= e.min_value + 1e-12
    True
    """
    import casadi as ca

    if not isinstance(function, ca.Function):
        raise SpecError("function", f"must be a casadi.Function, got {type(function).__name__}")
    rel_tol, abs_tol, max_boxes = _tolerances(rel_tol, abs_tol, max_boxes)
    strict = arguments.flag(strict, "strict")
    thresholds = _thresholds(thresholds)
    the_box = Box.of(function, box)
    expr, x, label = scalar_expression(function, output, index)
    problem = ScalarProblem(expr, x, the_box.free)
    t0 = time.perf_counter()
    low_thr, high_thr = thresholds
    sides = [maximize(problem, the_box.lower, the_box.upper, sign=sign, rel_tol=rel_tol, abs_tol=abs_tol,
                      max_boxes=max_boxes, threshold=thr) for sign, thr in ((-1.0, low_thr), (1.0, high_thr))]
    result = Enclosure(label, the_box, sides[0], sides[1], float(rel_tol), float(abs_tol), time.perf_counter() - t0)
    if strict and not result.converged:
        side = next(s for s in sides if s.stop == "work limit")
        which = "minimum" if side is sides[0] else "maximum"
        raise SpecError("rel_tol", f"{label}: the {which} needs more than {max_boxes} boxes to reach the tolerance "
                        f"{rel_tol:g} (gap {side.gap:.3g} after {side.boxes} boxes); loosen rel_tol or raise max_boxes")
    return result
