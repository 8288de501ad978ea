"""Branch and bound: a proven bound on the maximum (or minimum) of a scalar over a box, with a witness.

For the maximum of ``f`` over ``X0`` the search keeps

* ``best``: a **rigorous lower bound** of ``max f``, the lower end of ``f``'s ball at an evaluated point
  (the *witness*): the first from a local quasi-Newton search (SciPy L-BFGS-B with CasADi's exact
  gradient) started at the box's centre, then every box's centre as the boxes are evaluated;
* a list of boxes covering every part of ``X0`` where ``f`` may exceed ``best``, each with an upper
  bound of ``f`` on it (:meth:`~designkit.bounds.forms.ScalarProblem.on_box`); a box whose upper
  bound is below ``best`` is dropped (the maximum is not there).

At each step the box with the largest upper bound ``U`` is taken: ``U`` bounds ``f`` on all of
``X0``.  The search stops when ``U - best <= abs_tol + rel_tol |best|`` (the tolerance is met) --
and, when a ``threshold`` is given, it is also decided (``U < threshold``: ``f < threshold`` is
proven on ``X0``; ``best >= threshold``: the witness reaches it) -- or when ``max_boxes`` boxes have
been evaluated (the work limit: the bound holds but the tolerance, or the decision, is not
reached).  Otherwise the box, already reduced to a face wherever the gradient's enclosure has a sign
(monotonicity: the maximum of a box lies where each such coordinate is at its upper end if the
partial derivative is non-negative, at its lower end if it is non-positive), is bisected across the
entry with the largest ``|df/dx_j| w_j`` (the gradient's magnitude times the width, the "smear"
rule of R. B. Kearfott, *Rigorous Global Search*, 1996), and both halves are evaluated.

The minimum is the maximum of ``-f`` (the same boxes, the enclosures negated).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from designkit.bounds.forms import ScalarProblem

__all__ = ["Side", "maximize"]


@dataclass(frozen=True, eq=False)
class Side:
    """One end of a function's range over a box, bounded by :func:`maximize`.

    Parameters
    ----------
    bound : float
        Proven: ``f(x) <= bound`` on the box for the maximum (``>=`` for the minimum).
    value : float
        ``f`` at ``witness`` (attained; its rounding is below the gap).
    witness : ndarray
        The evaluated point (flat, the box's order), read-only.
    boxes : int
        Boxes evaluated.
    stop : str
        ``"tolerance"``, ``"threshold"`` or ``"work limit"``.
    """

    bound: float
    value: float
    witness: np.ndarray
    boxes: int
    stop: str

    def __post_init__(self) -> None:
        w = np.array(self.witness, dtype=float)
        w.setflags(write=False)
        object.__setattr__(self, "witness", w)

    @property
    def gap(self) -> float:
        """``|bound - value|``: how far the proven bound may lie from the best value found."""
        return abs(self.bound - self.value)


def _local(problem: ScalarProblem, lo: np.ndarray, hi: np.ndarray, sign: float, start: np.ndarray) -> np.ndarray:
    """A local maximiser of ``sign f`` in the box from ``start`` (L-BFGS-B, exact gradient)."""
    free = problem.free
    if free.size == 0:
        return start
    from scipy.optimize import minimize

    x = start.copy()

    def fun(z: np.ndarray) -> tuple[float, np.ndarray]:
        x[free] = z
        value, grad = problem.value_and_gradient(x)
        if not math.isfinite(value) or not np.all(np.isfinite(grad)):
            return math.inf, np.zeros_like(z)
        return -sign * value, -sign * grad

    res = minimize(fun, start[free], jac=True, method="L-BFGS-B", bounds=list(zip(lo[free], hi[free], strict=True)),
                   options={"maxiter": 200})
    out = start.copy()
    out[free] = np.clip(res.x, lo[free], hi[free])
    return out


def maximize(problem: ScalarProblem, lo: np.ndarray, hi: np.ndarray, *, sign: float = 1.0, rel_tol: float = 1e-3,
             abs_tol: float = 0.0, max_boxes: int = 20000, threshold: float | None = None) -> Side:
    """A proven upper bound of ``max sign*f`` over ``[lo, hi]`` and a witness (module docstring).

    Parameters
    ----------
    problem : ScalarProblem
    lo, hi : ndarray
        The box (flat).
    sign : float
        ``+1`` for the maximum of ``f``, ``-1`` for its minimum (the returned values are of ``f``).
    rel_tol, abs_tol : float
        Stop when ``bound - value <= abs_tol + rel_tol |value|``.
    max_boxes : int
        Work limit (boxes evaluated).
    threshold : float, optional
        Of ``f``: besides the tolerance, search until ``f`` is proven on the near side of it or a
        witness reaches it.

    Returns
    -------
    Side
        Values of ``f`` (not ``sign f``).
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    thr = None if threshold is None else sign * float(threshold)
    candidates = [0.5 * (lo + hi)]
    candidates.append(_local(problem, lo, hi, sign, candidates[0]))
    best, best_x = -math.inf, candidates[0]
    for c in candidates:
        low_f, _, up_f = problem.point(c)
        s_low = low_f if sign > 0 else -up_f
        if s_low > best:
            best, best_x = s_low, c

    heap: list[tuple[float, int, np.ndarray, np.ndarray, np.ndarray]] = []
    counter = 0

    def push(a: np.ndarray, b: np.ndarray) -> None:
        nonlocal counter, best, best_x
        v = problem.on_box(a, b, sign)
        counter += 1
        if v.centre_lower > best:
            best, best_x = v.centre_lower, v.centre
        if v.upper <= best:
            return
        a, b = a.copy(), b.copy()
        for k, j in enumerate(problem.free):  # monotone entries: the maximum is on a face
            if b[j] > a[j] and v.grad_lower[k] >= 0:
                a[j] = b[j]
            elif b[j] > a[j] and v.grad_upper[k] <= 0:
                b[j] = a[j]
        g = np.maximum(np.abs(v.grad_lower), np.abs(v.grad_upper))
        heapq.heappush(heap, (-v.upper, counter, a, b, np.where(np.isfinite(g), g, 0.0)))

    push(lo, hi)
    stop = "tolerance"
    while heap:
        ub = -heap[0][0]
        met = ub - best <= abs_tol + rel_tol * abs(best)
        if met and (thr is None or ub < thr or best >= thr):
            stop = "tolerance" if thr is None else "threshold"
            break
        if counter >= max_boxes:
            stop = "work limit"
            break
        _, _, a, b, g = heapq.heappop(heap)
        free = problem.free
        smear = g * (b - a)[free]
        if not np.any(smear > 0):
            smear = (b - a)[free]
        if not np.any(smear > 0):  # a point: nothing left to split
            break
        j = int(free[int(np.argmax(smear))])
        m = 0.5 * (a[j] + b[j])
        left_hi, right_lo = b.copy(), a.copy()
        left_hi[j], right_lo[j] = m, m
        push(a, left_hi)
        push(right_lo, b)
    upper = max(-heap[0][0], best) if heap else best
    _, value, _ = problem.point(best_x)
    bound = upper if sign > 0 else -upper
    return Side(bound=bound, value=value, witness=best_x, boxes=counter, stop=stop)
