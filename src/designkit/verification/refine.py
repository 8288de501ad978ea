"""A lattice of a parameter box refined by bisection until the stability margin between neighbours is resolved.

A lattice judges a box at its points only: with ``grid: 2`` a box is judged at its corners, and a region where the
loop is unstable between two stable corners is not seen.  :func:`refine` bisects the lattice between neighbours
(two points that differ along one axis by one lattice step) wherever the stability margin ``m`` (1/s, minus the
spectral abscissa; NaN where the loop is undecided) is not **resolved** between them:

* both margins are finite, of the same sign, and differ by at most :data:`RESOLVED_FRACTION` of the smaller
  magnitude, ``|m_a - m_b| <= RESOLVED_FRACTION * min(|m_a|, |m_b|)``; so a pair is resolved only when the margin
  changes by less than half its own size between the neighbours -- near the stability boundary (small
  ``|m|``) the lattice is refined finely, far from it coarsely;
* or the pair is no wider than :data:`MIN_WIDTH_FRACTION` of the box along their axis (the finest bisection).

Every pair of the lattice is bisected at least once (a verdict over a box never rests on its corners alone); then
each round evaluates the midpoints of the unresolved pairs (largest change of the margin first) and replaces each
pair by its two halves; the rounds stop when every pair is resolved or when ``cap`` plants were added, and the
result says how many pairs were left unresolved.  The refinement is sampling, not proof: a margin that dips and
recovers between two resolved neighbours is not seen.  The lattice checks say so in their verdicts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["MAX_REFINED_PLANTS", "MIN_WIDTH_FRACTION", "RESOLVED_FRACTION", "Refinement", "lattice_pairs",
           "refine", "resolved"]

RESOLVED_FRACTION = 0.5
"""Neighbours are resolved when their margins differ by at most this fraction of the smaller magnitude."""
MIN_WIDTH_FRACTION = 1e-3
"""Pairs no wider than this fraction of the box (along their axis) are not bisected (about ten bisections of a
two-point axis)."""
MAX_REFINED_PLANTS = 2000
"""At most this many plants are added to a lattice by the refinement."""


@dataclass(frozen=True)
class Refinement:
    """The plants a refinement added.

    Parameters
    ----------
    theta : ndarray, shape (M, k)
        The added parameter vectors, in the order evaluated.
    rounds : int
        Bisection rounds made.
    unresolved : int
        Neighbour pairs still unresolved (and wider than the finest bisection) when the cap stopped the rounds.
    finest : int
        Pairs left unresolved at the finest bisection (a margin that changes faster than the lattice can follow
        there, such as a stability boundary or a point with no equilibrium).
    """

    theta: np.ndarray
    rounds: int
    unresolved: int
    finest: int

    @property
    def plants(self) -> int:
        """How many plants were added."""
        return int(self.theta.shape[0])


def resolved(m_a: np.ndarray, m_b: np.ndarray) -> np.ndarray:
    """Which neighbour pairs have a resolved margin (module docstring); NaN (undecided) is never resolved.

    Examples
    --------
    >>> resolved(np.array([1.0, 1.0, 1.0, -1.0, np.nan]), np.array([1.2, 1.6, -1.0, -1.1, 1.0])).tolist()
    [True, False, False, True, False]
    """
    m_a, m_b = np.asarray(m_a, dtype=float), np.asarray(m_b, dtype=float)
    with np.errstate(invalid="ignore"):
        same = np.sign(m_a) == np.sign(m_b)
        small = np.abs(m_a - m_b) <= RESOLVED_FRACTION * np.minimum(np.abs(m_a), np.abs(m_b))
    return np.isfinite(m_a) & np.isfinite(m_b) & same & small & (m_a != 0) & (m_b != 0)


def lattice_pairs(shape: tuple[int, ...]) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """``(axis, a, b)`` for every axis with more than one point: the flat indices (``ij`` order) of the lattice
    points ``a`` and of their neighbours ``b`` one step further along that axis.

    Examples
    --------
    >>> [(j, a.tolist(), b.tolist()) for j, a, b in lattice_pairs((2, 3))]
    [(0, [0, 1, 2], [3, 4, 5]), (1, [0, 1, 3, 4], [1, 2, 4, 5])]
    """
    idx = np.arange(int(np.prod(shape))).reshape(shape)
    out = []
    for j, n in enumerate(shape):
        if n > 1:
            out.append((j, np.take(idx, range(n - 1), axis=j).ravel(), np.take(idx, range(1, n), axis=j).ravel()))
    return out


def refine(theta: np.ndarray, margin: np.ndarray, shape: tuple[int, ...], span: np.ndarray,
           evaluate: Callable[[np.ndarray], np.ndarray], *, cap: int = MAX_REFINED_PLANTS) -> Refinement:
    """Bisect the lattice ``theta`` between neighbours until the margin is resolved (module docstring).

    Parameters
    ----------
    theta : ndarray, shape (G, k)
        The lattice (``ij`` order, the first parameter varying slowest), ``G = prod(shape)``.
    margin : ndarray, shape (G,)
        The stability margin at each lattice point (1/s; NaN undecided).
    shape : tuple of int
        Points per axis.
    span : ndarray, shape (k,)
        The box's width along each axis (parameter units).
    evaluate : callable
        ``theta (N, k) -> margin (N,)``: the margin at a batch of plants.
    cap : int
        Most plants to add.

    Returns
    -------
    Refinement
    """
    theta = np.asarray(theta, dtype=float)
    margin = np.asarray(margin, dtype=float)
    span = np.asarray(span, dtype=float)
    A, B, MA, MB, axis = [], [], [], [], []
    for j, a, b in lattice_pairs(tuple(shape)):
        A.append(theta[a])
        B.append(theta[b])
        MA.append(margin[a])
        MB.append(margin[b])
        axis.append(np.full(a.size, j))
    k = theta.shape[1]
    if not A:
        return Refinement(np.zeros((0, k)), 0, 0, 0)
    a_pts, b_pts = np.vstack(A), np.vstack(B)
    m_a, m_b, ax = np.concatenate(MA), np.concatenate(MB), np.concatenate(axis)
    fresh = np.ones(ax.size, dtype=bool)  # a pair of the lattice itself: bisected at least once
    added: list[np.ndarray] = []
    count = rounds = 0
    finest = left = 0
    while True:
        width = np.abs(b_pts[np.arange(ax.size), ax] - a_pts[np.arange(ax.size), ax])
        wide = width > MIN_WIDTH_FRACTION * span[ax]
        open_ = fresh | ~resolved(m_a, m_b)
        finest += int(np.count_nonzero(open_ & ~wide))
        todo = np.flatnonzero(open_ & wide)
        if todo.size == 0 or count >= cap:
            return Refinement(np.vstack(added) if added else np.zeros((0, k)), rounds, int(todo.size) + left, finest)
        change = np.abs(m_a[todo] - m_b[todo])
        order = todo[np.argsort(-np.where(np.isfinite(change), change, np.inf), kind="stable")]
        todo, left = order[: cap - count], left + max(0, order.size - (cap - count))
        mid = 0.5 * (a_pts[todo] + b_pts[todo])
        m_mid = np.asarray(evaluate(mid), dtype=float).reshape(-1)
        added.append(mid)
        count += mid.shape[0]
        rounds += 1
        a_pts = np.vstack([a_pts[todo], mid])
        b_pts = np.vstack([mid, b_pts[todo]])
        m_a, m_b = np.concatenate([m_a[todo], m_mid]), np.concatenate([m_mid, m_b[todo]])
        ax = np.concatenate([ax[todo], ax[todo]])
        fresh = np.zeros(ax.size, dtype=bool)
