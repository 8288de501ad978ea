"""The one LP core: linear conditions over parameter polytopes, and linear feasibility, with
duality certificates re-checked in NumPy.

Robust linear conditions.  A condition ``f(theta) = c0 + c . theta > 0`` (unit of the condition)
must hold for every parameter vector ``theta`` in a polytope ``{theta : A theta <= b}``.  The LP
``min c . theta`` over the polytope proposes a worst case ``theta*`` and multipliers
``lam >= 0``.  Weak duality is the certificate: for every ``theta`` in the polytope
``lam . (A theta) <= lam . b``, so with the residual ``r = A'lam + c``::

    f(theta) = c0 - lam . (A theta) + r . theta >= c0 - lam . b + min_{theta in box} r . theta,

where the box ``[lo, hi]`` contains the polytope (read from its single-parameter rows) and the
minimum over the box is exact, ``sum_j min(r_j lo_j, r_j hi_j)``.  The floating-point error of
these sums is bounded (Higham's ``gamma_N``) and subtracted.  The condition is certified when this
lower bound is at least ``eps`` times the size of its terms, ``|c0| + sum_j |c_j| max|theta_j|``
(relative margin :data:`~designkit.verification.tolerances.LP_EPS`).

Linear feasibility.  ``G x <= h`` is decided by the LP ``max t`` subject to
``G_i x + t ||G_i|| <= h_i`` (``t <= t_max``): ``t`` is the distance (units of ``x``) from ``x``
to the nearest constraint boundary.  A feasible system is certified by ``x`` itself, its slacks
``h - G x`` recomputed in NumPy (minus rounding); an infeasible one by a Farkas vector
``y >= 0`` with ``G'y = 0`` and ``h . y < 0`` (no ``x`` can satisfy ``y . (G x) <= y . h < 0 = (G'y) . x``),
the normalised dual of that LP, accepted when ``||G'y||`` is at most
:data:`~designkit.verification.tolerances.FARKAS_TOL` of ``sum_i y_i ||G_i||``.

Who decides.  The solver's numbers are only proposals: :class:`LowerBoundCertificate`,
:class:`FeasiblePointCertificate` and :class:`FarkasCertificate` are re-checked with NumPy and the
re-check decides.  A condition FAILS only on a counterexample computed by NumPy: a point of the
polytope (the LP's minimiser, or a vertex of a box) where ``f <= 0``.  A solver failure, an
inaccurate status or a certificate that does not re-check is UNDECIDED, never a pass.

cvxpy is imported inside :func:`solve_lp` only.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["LpSolution", "Polytope", "gamma", "solve_lp"]

_MAX_VERTEX_DIM = 12
"""Boxes of up to this many parameters have their 2^n vertices evaluated for counterexamples."""

_U = float(np.finfo(float).eps) / 2.0


def gamma(k: int) -> float:
    """Higham's ``gamma_k = k u / (1 - k u)``: relative error bound of a k-term sum of products."""
    return k * _U / (1.0 - k * _U)


def _readonly(x: Any, ndim: int) -> np.ndarray:
    a = np.array(x, dtype=float)
    if a.ndim != ndim:
        raise ValueError(f"expected a {ndim}-d array, got shape {a.shape}")
    a.setflags(write=False)
    return a


# ----------------------------------------------------------------------------- data


@dataclass(frozen=True)
class Polytope:
    """Parameters ``theta`` with ``A theta <= b``.

    Parameters
    ----------
    names : tuple of str
        Parameter names, in the order of the columns of ``A``.
    A : ndarray, shape (m, n)
    b : ndarray, shape (m,)
    """

    names: tuple[str, ...]
    A: np.ndarray
    b: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(str(n) for n in self.names))
        A, b = _readonly(self.A, 2), _readonly(self.b, 1)
        if A.shape != (len(b), len(self.names)):
            raise ValueError(f"A must be {len(b)} x {len(self.names)}, got {A.shape}")
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "b", b)

    @classmethod
    def box(cls, names: Sequence[str], lo: Sequence[float], hi: Sequence[float]) -> Polytope:
        """``lo_j <= theta_j <= hi_j`` as the rows ``[I; -I] theta <= [hi; -lo]``."""
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        n = len(names)
        if lo.shape != (n,) or hi.shape != (n,):
            raise ValueError("lo and hi need one entry per name")
        return cls(tuple(names), np.vstack([np.eye(n), -np.eye(n)]), np.concatenate([hi, -lo]))

    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        """A box ``[lo, hi]`` containing the polytope, read from its single-parameter rows.

        A row ``a theta_j <= b_i`` bounds ``theta_j`` by ``b_i / a``; the quotient is rounded
        outwards unless ``|a| = 1`` (then it is exact).  Coordinates without such rows get
        ``-inf`` / ``inf``.
        """
        n = len(self.names)
        lo, hi = np.full(n, -np.inf), np.full(n, np.inf)
        for a_row, b_i in zip(self.A, self.b, strict=True):
            nz = np.flatnonzero(a_row)
            if len(nz) != 1:
                continue
            j, a = int(nz[0]), float(a_row[nz[0]])
            q = b_i / a
            if a > 0:
                hi[j] = min(hi[j], q if a == 1.0 else np.nextafter(q, np.inf))
            else:
                lo[j] = max(lo[j], q if a == -1.0 else np.nextafter(q, -np.inf))
        return lo, hi

    @property
    def is_box(self) -> bool:
        """Every row bounds one parameter with coefficient +-1 and every parameter is bounded both ways."""
        single = np.count_nonzero(self.A, axis=1) == 1
        unit = np.all((self.A == 0) | (np.abs(self.A) == 1), axis=1)
        lo, hi = self.bounding_box()
        return bool(np.all(single & unit) and np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)))

    def vertices(self) -> np.ndarray:
        """The ``2^n`` corners of a box, shape ``(2^n, n)``.

        Raises
        ------
        ValueError
            If the polytope is not a box (:attr:`is_box`) or is empty.
        """
        if not self.is_box:
            raise ValueError("vertices() is implemented for boxes only")
        lo, hi = self.bounding_box()
        if np.any(lo > hi):
            raise ValueError("empty box")
        return np.array(list(itertools.product(*zip(lo, hi, strict=True))), dtype=float).reshape(-1, len(lo))

    def contains(self, theta: np.ndarray) -> bool:
        """``A theta <= b`` evaluated in NumPy."""
        return bool(np.all(self.A @ np.asarray(theta, dtype=float) <= self.b))


# ----------------------------------------------------------------------------- the solve


@dataclass(frozen=True)
class LpSolution:
    """Raw outcome of ``min c . x`` subject to ``G x <= h`` (before any re-check).

    Parameters
    ----------
    x : ndarray or None
        Minimiser proposed by the solver.
    value : float or None
        Solver's optimal value.
    dual : ndarray or None
        Multipliers of the rows (``>= 0``; at the optimum ``G'dual = -c``).
    status : str
        cvxpy status or ``"solver_error: ..."``.
    solver : str
    """

    x: np.ndarray | None
    value: float | None
    dual: np.ndarray | None
    status: str
    solver: str


def solve_lp(c: np.ndarray, G: np.ndarray, h: np.ndarray, *, solver: str = "CLARABEL") -> LpSolution:
    """``min c . x`` subject to ``G x <= h`` with cvxpy (the one LP of this module).

    Solved in the solver process when the command line started one
    (:mod:`designkit.verification.solver_process`), else here.
    """
    from designkit.verification import solver_process

    done, remote = solver_process.call("lp", c, G, h, solver=solver)
    if done:
        return remote
    cp = solver_process.cvxpy()

    c, G, h = np.asarray(c, dtype=float), np.asarray(G, dtype=float), np.asarray(h, dtype=float)
    x = cp.Variable(len(c))
    con = G @ x <= h
    prob = cp.Problem(cp.Minimize(c @ x), [con])
    try:
        prob.solve(solver=solver)
    except cp.error.SolverError as exc:
        return LpSolution(None, None, None, f"solver_error: {exc}", solver)
    xv = None if x.value is None else np.array(x.value, dtype=float)
    dual = None if con.dual_value is None else np.array(con.dual_value, dtype=float).reshape(-1)
    value = None if prob.value is None or not np.isfinite(prob.value) else float(prob.value)
    return LpSolution(xv, value, dual, str(prob.status), solver)

