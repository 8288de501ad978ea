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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from designkit.synthesis.design import LinearCondition
from designkit.verification.certificate import Recheck, array_from_json, to_json
from designkit.verification.check import Check
from designkit.verification.tolerances import FARKAS_TOL, LP_EPS, LP_SOLVER_OK

__all__ = [
    "FarkasCertificate",
    "FeasiblePointCertificate",
    "LinearCondition",
    "LinearFeasibility",
    "LowerBoundCertificate",
    "LpSolution",
    "Polytope",
    "linear_feasibility",
    "robust_linear_conditions",
    "solve_lp",
]

_MAX_VERTEX_DIM = 12
"""Boxes of up to this many parameters have their 2^n vertices evaluated for counterexamples."""

_U = float(np.finfo(float).eps) / 2.0


def _gamma(k: int) -> float:
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
    import cvxpy as cp

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


# ----------------------------------------------------------------------------- certificates


@dataclass(frozen=True)
class LowerBoundCertificate:
    """``c0 + c . theta > 0`` on ``{A theta <= b}``, by weak duality with multipliers ``lam``.

    The re-check (NumPy) computes ``r = A'lam + c`` and the lower bound
    ``c0 - b . lam + sum_j min(r_j lo_j, r_j hi_j)`` minus its rounding bound, valid for every
    ``theta`` of the polytope because ``[lo, hi]`` contains it.  It holds iff ``lam >= 0`` and the
    bound is at least ``eps (|c0| + sum_j |c_j| max(|lo_j|, |hi_j|))`` (and positive); the
    margin is their difference (unit of the condition).

    Parameters
    ----------
    constant : float
    coefficients : ndarray, shape (n,)
    A : ndarray, shape (m, n)
    b : ndarray, shape (m,)
    lam : ndarray, shape (m,)
    lo, hi : ndarray, shape (n,)
        A box containing the polytope (:meth:`Polytope.bounding_box`).
    eps : float
        Relative margin.
    """

    kind: ClassVar[str] = "lp_lower_bound"
    constant: float
    coefficients: np.ndarray
    A: np.ndarray
    b: np.ndarray
    lam: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    eps: float = LP_EPS

    def __post_init__(self) -> None:
        object.__setattr__(self, "constant", float(self.constant))
        for name, ndim in (("coefficients", 1), ("A", 2), ("b", 1), ("lam", 1), ("lo", 1), ("hi", 1)):
            object.__setattr__(self, name, _readonly(getattr(self, name), ndim))
        object.__setattr__(self, "eps", float(self.eps))

    def recheck(self) -> Recheck:
        """Weak-duality bound with the residual and rounding accounted for (class docstring)."""
        c, A, b, lam, lo, hi = self.coefficients, self.A, self.b, self.lam, self.lo, self.hi
        size = np.maximum(np.abs(lo), np.abs(hi))
        scale = float(abs(self.constant) + np.sum(np.abs(c) * size))
        required = self.eps * scale if scale > 0 else float(np.finfo(float).tiny)
        if not (np.all(np.isfinite(lam)) and np.all(lam >= 0)):
            min_lam = float(np.min(lam)) if lam.size else float("nan")
            return Recheck(False, -np.inf, "multipliers are not all finite and >= 0", {"min_lambda": min_lam})
        r = A.T @ lam + c
        with np.errstate(invalid="ignore"):
            box_min = np.where(r == 0, 0.0, np.minimum(r * lo, r * hi))
        bound = float(self.constant - b @ lam + np.sum(box_min))
        terms = abs(self.constant) + np.abs(b) @ lam + np.sum((np.abs(r) + np.abs(A).T @ lam + np.abs(c)) * size)
        rounding = 2.0 * _gamma(len(b) + len(c) + 3) * float(terms)
        lower = bound - rounding
        margin = lower - required
        ok = bool(margin >= 0 and lower > 0)
        if not ok and margin >= 0:
            margin = -float(np.finfo(float).tiny)
        values = {
            "lower_bound": lower,
            "required": required,
            "scale": scale,
            "dual_bound": float(self.constant - b @ lam),
            "residual_inf_norm": float(np.max(np.abs(r))) if r.size else 0.0,
            "residual_correction": float(np.sum(box_min)),
            "rounding": rounding,
            "min_lambda": float(np.min(lam)) if lam.size else 0.0,
        }
        detail = (
            f"certified lower bound {lower:.6g} "
            + (">=" if ok else "<")
            + f" required {required:.3g} (eps {self.eps:g} x size {scale:.3g})"
        )
        return Recheck(ok, margin if np.isfinite(margin) else -np.inf, detail, values)

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable data (infinite bounds become ``None``)."""
        out: dict[str, Any] = {"kind": self.kind, "constant": self.constant}
        out.update({n: to_json(getattr(self, n)) for n in ("coefficients", "A", "b", "lam", "lo", "hi")})
        out["eps"] = self.eps
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> LowerBoundCertificate:
        """Inverse of :meth:`to_dict` (``None`` read back as NaN: an unbounded box does not re-check)."""
        arrays = {n: array_from_json(data[n]) for n in ("coefficients", "A", "b", "lam", "lo", "hi")}
        if arrays["A"].size == 0:
            arrays["A"] = arrays["A"].reshape(len(arrays["b"]), len(arrays["coefficients"]))
        return cls(float(data["constant"]), eps=float(data["eps"]), **arrays)


def _row_norms(G: np.ndarray) -> np.ndarray:
    return np.linalg.norm(G, axis=1)


@dataclass(frozen=True)
class FeasiblePointCertificate:
    """``G x <= h`` is feasible: the point ``x`` itself.

    The re-check computes the slacks ``h - G x`` in NumPy, subtracts their rounding bound
    ``gamma_{n+1} (|h| + |G| |x|)`` and divides by the row norms: the margin is the smallest
    distance (units of ``x``) from ``x`` to a constraint boundary, non-negative iff every
    constraint holds.  Rows of zeros count as satisfied iff ``h_i >= 0``.
    """

    kind: ClassVar[str] = "feasible_point"
    G: np.ndarray
    h: np.ndarray
    x: np.ndarray

    def __post_init__(self) -> None:
        for name, ndim in (("G", 2), ("h", 1), ("x", 1)):
            object.__setattr__(self, name, _readonly(getattr(self, name), ndim))

    def recheck(self) -> Recheck:
        """Slacks ``h - G x`` minus rounding, as distances (class docstring)."""
        G, h, x = self.G, self.h, self.x
        if not np.all(np.isfinite(x)):
            return Recheck(False, -np.inf, "x is not finite", {})
        slack = h - G @ x
        rounding = _gamma(len(x) + 1) * (np.abs(h) + np.abs(G) @ np.abs(x))
        norms = _row_norms(G)
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.where(norms > 0, (slack - rounding) / norms, np.where(h >= 0, np.inf, -np.inf))
        margin = float(np.min(dist)) if dist.size else np.inf
        ok = bool(margin >= 0)
        k = int(np.argmin(dist)) if dist.size else -1
        detail = (
            f"x satisfies all {len(h)} constraints; nearest boundary at distance {margin:.3g}"
            if ok
            else f"x violates constraint {k} (slack {slack[k]:.3g}, rounding {rounding[k]:.2g})"
        )
        return Recheck(ok, margin, detail, {"slacks": slack, "distances": dist, "min_distance": margin})

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable data."""
        return {"kind": self.kind, "G": to_json(self.G), "h": to_json(self.h), "x": to_json(self.x)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> FeasiblePointCertificate:
        """Inverse of :meth:`to_dict`."""
        x = array_from_json(data["x"])
        G = array_from_json(data["G"]).reshape(-1, len(x))
        return cls(G, array_from_json(data["h"]), x)


@dataclass(frozen=True)
class FarkasCertificate:
    """``G x <= h`` has no solution (with ``||x||_2`` below the reported radius): Farkas vector ``y``.

    The re-check (NumPy) needs ``y >= 0``, ``s = sum_i y_i ||G_i|| > 0``,
    ``||G'y||_2 <= tol s`` and ``h . y`` negative beyond its rounding bound.  Then every ``x``
    with ``G x <= h`` satisfies ``(G'y) . x <= h . y < 0``, so ``||x||_2 >= -h . y / ||G'y||_2``
    (the radius, infinite when ``G'y = 0``).  The margin is ``-h . y / s`` minus rounding (units
    of ``x``: how far the constraints are from meeting), replaced by ``tol - ||G'y|| / s`` when
    that is negative.
    """

    kind: ClassVar[str] = "farkas"
    G: np.ndarray
    h: np.ndarray
    y: np.ndarray
    tol: float = FARKAS_TOL

    def __post_init__(self) -> None:
        for name, ndim in (("G", 2), ("h", 1), ("y", 1)):
            object.__setattr__(self, name, _readonly(getattr(self, name), ndim))
        object.__setattr__(self, "tol", float(self.tol))

    def recheck(self) -> Recheck:
        """The Farkas conditions of the class docstring."""
        G, h, y = self.G, self.h, self.y
        if not (np.all(np.isfinite(y)) and np.all(y >= 0)):
            return Recheck(False, -np.inf, "y is not finite and >= 0", {})
        s = float(y @ _row_norms(G))
        if not s > 0:
            return Recheck(False, -np.inf, "y puts no weight on a non-zero row", {})
        gty = G.T @ y
        rho = float(np.linalg.norm(gty) / s)
        hy = float(h @ y)
        rounding = _gamma(len(h) + 1) * float(np.abs(h) @ y)
        gap = (-hy - rounding) / s
        radius = float(-hy / np.linalg.norm(gty)) if np.linalg.norm(gty) > 0 else np.inf
        margin = gap if rho <= self.tol else min(gap, self.tol - rho)
        ok = bool(margin >= 0) and gap > 0
        if not ok and margin >= 0:
            margin = -float(np.finfo(float).tiny)
        values = {"h_dot_y": hy, "relative_residual": rho, "gap": gap, "radius": radius, "weight": s}
        detail = (
            f"Farkas: y >= 0, ||G'y|| / sum y_i ||G_i|| = {rho:.2g} <= {self.tol:g}, h . y = {hy:.4g} < 0; "
            f"no solution with ||x|| < {radius:.3g}"
            if ok
            else f"not a Farkas certificate: h . y = {hy:.4g}, ||G'y|| / sum y_i ||G_i|| = {rho:.2g} (tol {self.tol:g})"
        )
        return Recheck(ok, margin, detail, values)

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable data."""
        return {"kind": self.kind, "G": to_json(self.G), "h": to_json(self.h), "y": to_json(self.y), "tol": self.tol}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> FarkasCertificate:
        """Inverse of :meth:`to_dict`."""
        y = array_from_json(data["y"])
        G = array_from_json(data["G"]).reshape(len(y), -1)
        return cls(G, array_from_json(data["h"]), y, float(data["tol"]))


# ----------------------------------------------------------------------------- robust linear conditions


def _named(names: Sequence[str], theta: np.ndarray) -> dict[str, float]:
    return {n: float(v) for n, v in zip(names, theta, strict=True)}


def _pull_inside(poly: Polytope, theta: np.ndarray, solver: str) -> np.ndarray | None:
    """``theta`` if NumPy finds it in the polytope, else the nearest point towards a re-checked
    interior point that is (the LP's minimiser may sit outside a face by rounding), else None."""
    if poly.contains(theta):
        return theta
    centre = linear_feasibility(poly.A, poly.b, names=poly.names, solver=solver)
    if centre.feasible is not True or centre.x is None:
        return None
    for step in 10.0 ** np.arange(-14, 1):
        moved = theta + step * (centre.x - theta)
        if poly.contains(moved):
            return moved
    return None


def _assess(cond: LinearCondition, poly: Polytope, eps: float, solver: str) -> dict[str, Any]:
    """One condition: counterexample search (NumPy), LP, and the re-checked dual bound."""
    names = poly.names
    c = cond.vector(names)
    lo, hi = poly.bounding_box()
    size = np.maximum(np.abs(lo), np.abs(hi))
    scale = float(abs(cond.constant) + np.sum(np.where(c == 0, 0.0, np.abs(c) * size)))
    entry: dict[str, Any] = {
        "label": cond.label,
        "unit": cond.unit,
        "constant": float(cond.constant),
        "coefficients": _named(names, c),
        "scale": to_json(scale),
    }
    sol = solve_lp(c, poly.A, poly.b, solver=solver)
    entry.update(solver_status=sol.status, solver_value=sol.value)
    candidates: list[tuple[float, str, np.ndarray]] = []
    if sol.x is not None and np.all(np.isfinite(sol.x)):
        theta = _pull_inside(poly, np.clip(sol.x, lo, hi), solver)  # clipping is exact for a box
        if theta is not None:
            v = cond.at(theta, names)
            entry.update(worst_theta=_named(names, theta), value_at_worst=v)
            candidates.append((v, "LP minimiser", theta))
    if poly.is_box and len(names) <= _MAX_VERTEX_DIM and np.all(lo <= hi):
        verts = poly.vertices()
        vals = cond.constant + verts @ c
        k = int(np.argmin(vals))
        entry.update(vertex_min=float(vals[k]), vertex_argmin=_named(names, verts[k]))
        candidates.append((float(vals[k]), "vertex", verts[k]))
    if candidates:
        v, source, theta = min(candidates, key=lambda item: item[0])
        if v <= 0:
            unit = f" {cond.unit}" if cond.unit else ""
            entry.update(
                passed=False,
                margin=v,
                relative_margin=v / scale if 0 < scale < np.inf else v,
                evidence={"theta": _named(names, theta), "value": v, "source": source},
                detail=f"{cond.label}: value {v:.6g}{unit} <= 0 at the {source} {_named(names, theta)}",
            )
            return entry
    if sol.status not in LP_SOLVER_OK or sol.dual is None:
        entry.update(passed=None, margin=None, relative_margin=None,
                     detail=f"{cond.label}: undecided, solver status {sol.status!r} and no counterexample")
        return entry
    cert = LowerBoundCertificate(cond.constant, c, poly.A, poly.b, np.maximum(sol.dual, 0.0), lo, hi, eps)
    rc = cert.recheck()
    entry.update(
        **{"lambda": cert.lam.tolist()},
        certified_lower_bound=rc.values.get("lower_bound"),
        recheck=rc.to_dict(),
        margin=rc.margin,
        relative_margin=rc.margin / scale if scale > 0 and np.isfinite(scale) else None,
    )
    if rc.ok:
        entry.update(passed=True, detail=f"{cond.label}: {rc.detail}")
    else:
        why = "" if np.all(np.isfinite(lo) & np.isfinite(hi)) else " (no finite bounding box for the residual)"
        entry.update(passed=None, detail=f"{cond.label}: undecided, {rc.detail}{why}")
    return entry


def robust_linear_conditions(
    name: str,
    conditions: Sequence[LinearCondition],
    polytope: Polytope,
    *,
    eps: float = LP_EPS,
    solver: str = "CLARABEL",
) -> Check:
    """Check ``name``: every ``c0 + c . theta > 0`` for every ``theta`` in ``polytope``.

    Parameters
    ----------
    name : str
        Name of the returned check.
    conditions : sequence of LinearCondition
    polytope : Polytope
        Parameter set; its single-parameter rows give the box that bounds the dual residual.
    eps : float
        Relative margin (module docstring).
    solver : str
        cvxpy solver name.

    Returns
    -------
    Check
        True: every condition certified by a re-checked dual bound.  False: some condition is
        ``<= 0`` at a point of the polytope computed by NumPy (``certificate["evidence"]``).
        None: otherwise.  ``achieved`` and ``margin`` are relative to the size of each condition's
        terms (the smallest over the conditions); per condition ``certificate["conditions"]``
        holds ``worst_theta``, ``value_at_worst``, ``vertex_min``, ``certified_lower_bound``,
        ``margin`` (unit of the condition), ``lambda`` and the re-check.
    """
    entries = [_assess(cond, polytope, eps, solver) for cond in conditions]
    cert: dict[str, Any] = {
        "parameters": list(polytope.names),
        "A": polytope.A.tolist(),
        "b": polytope.b.tolist(),
        "eps": eps,
        "conditions": to_json(entries),
    }
    target = f"c0 + c . theta > 0 on the polytope (certified lower bound >= {eps:g} x size of the terms)"
    unit = "1 (relative to |c0| + sum |c_j| max|theta_j|)"
    failed = [e for e in entries if e["passed"] is False]
    if failed:
        worst = min(failed, key=lambda e: e["relative_margin"])
        cert["evidence"] = dict(worst["evidence"], condition=worst["label"])
        rel = float(worst["relative_margin"])
        return Check(name=name, passed=False, target=target, achieved=rel, margin=rel, unit=unit,
                     detail=f"fails: {worst['detail']}", certificate=cert)
    rels = [e["relative_margin"] for e in entries if e.get("relative_margin") is not None]
    margin = float(min(rels)) if rels else None
    achieved = None if margin is None else margin + eps
    undecided = [e for e in entries if e["passed"] is None]
    if undecided:
        return Check(name=name, passed=None, target=target, achieved=achieved, margin=margin, unit=unit,
                     detail=f"undecided: {undecided[0]['detail']}", certificate=cert)
    return Check(name=name, passed=True, target=target, achieved=achieved, margin=margin, unit=unit,
                 detail=f"{len(entries)} linear condition(s) certified over the polytope by re-checked dual bounds",
                 certificate=cert)


# ----------------------------------------------------------------------------- linear feasibility


@dataclass(frozen=True)
class LinearFeasibility:
    """Outcome of :func:`linear_feasibility`.

    Parameters
    ----------
    feasible : bool or None
        True: ``x`` re-checked.  False: Farkas vector re-checked.  None: undecided.
    names : tuple of str
        Names of the unknowns.
    x : ndarray or None
        The solver's point (the Chebyshev-like centre, margin ``t``).
    slacks : ndarray or None
        ``h - G x`` computed by NumPy.
    t : float or None
        The solver's uniform margin (units of ``x``; capped at ``t_max``).
    point : FeasiblePointCertificate or None
    farkas : FarkasCertificate or None
    recheck : Recheck or None
        The re-check that decided (or the last one tried).
    status : str
    solver : str
    detail : str
    """

    feasible: bool | None
    names: tuple[str, ...]
    x: np.ndarray | None
    slacks: np.ndarray | None
    t: float | None
    point: FeasiblePointCertificate | None
    farkas: FarkasCertificate | None
    recheck: Recheck | None
    status: str
    solver: str
    detail: str

    def to_check(self, name: str = "linear_feasibility", *, required: bool = True) -> Check:
        """The outcome as a :class:`Check` (True feasible, False infeasible, None undecided)."""
        cert: dict[str, Any] = {"parameters": list(self.names), "solver": self.solver, "solver_status": self.status,
                                "t": self.t}
        if self.x is not None:
            cert["x"] = to_json(_named(self.names, self.x))
        if self.slacks is not None:
            cert["slacks"] = to_json(self.slacks)
        if self.recheck is not None:
            cert["recheck"] = self.recheck.to_dict()
        if self.feasible is False and self.farkas is not None:
            cert["evidence"] = {"farkas_y": to_json(self.farkas.y), **dict(self.recheck.values)}
        margin = None if self.recheck is None or self.feasible is None else self.recheck.margin
        if self.feasible is False and margin is not None:
            margin = -margin  # the constraints miss each other by this much
        return Check(name=name, passed=self.feasible, target="G x <= h has a solution", achieved=margin,
                     margin=margin, unit="units of x", detail=self.detail, certificate=cert, required=required)


def _polish_farkas(G: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Reduce ``G'y`` of the solver's dual in NumPy; only a proposal, the re-check decides.

    Candidates: on the support ``{i : y_i > delta max y}`` (``delta`` = 1e-6, 1e-3; the rest set
    to zero), ``y`` projected onto ``null(G_S')`` by least squares; and alternate projections onto
    ``null(G')`` and clipping at zero.  The candidate with the smallest ``||G'y|| / sum y_i ||G_i||``
    among those that stay ``>= 0`` is returned (``y`` itself if none is better).
    """
    norms = _row_norms(G)

    def residual(v: np.ndarray) -> float:
        weight = float(v @ norms)
        return float(np.linalg.norm(G.T @ v)) / weight if weight > 0 and np.all(v >= 0) else np.inf

    candidates = [y]
    top = float(np.max(y)) if y.size else 0.0
    for delta in (1e-6, 1e-3):
        support = y > delta * top
        if np.any(support):
            v = np.zeros_like(y)
            ys, Gs = y[support], G[support]
            v[support] = ys - Gs @ np.linalg.lstsq(Gs, ys, rcond=None)[0]
            candidates.append(v)
    v = y
    for _ in range(3):
        v = np.maximum(v - G @ np.linalg.lstsq(G, v, rcond=None)[0], 0.0)
        candidates.append(v)
    return min(candidates, key=residual)


def linear_feasibility(
    G: np.ndarray,
    h: np.ndarray,
    *,
    names: Sequence[str] | None = None,
    solver: str = "CLARABEL",
    t_max: float = 1.0,
) -> LinearFeasibility:
    """Decide ``G x <= h`` by the max-margin LP and re-check its primal or Farkas certificate.

    Parameters
    ----------
    G : ndarray, shape (m, n)
    h : ndarray, shape (m,)
    names : sequence of str, optional
        Names of the unknowns (default ``x0, x1, ...``).
    solver : str
        cvxpy solver name.
    t_max : float
        Cap on the margin ``t`` (units of ``x``), so that unbounded feasible sets keep the LP bounded.

    Returns
    -------
    LinearFeasibility
        Feasible iff the solver is optimal and ``x`` re-checks; infeasible iff the solver is
        optimal and its normalised dual re-checks as a Farkas vector; a zero row with ``h_i < 0`` is
        infeasible without the solver.  Anything else is undecided.
    """
    G = np.atleast_2d(np.asarray(G, dtype=float))
    h = np.asarray(h, dtype=float).reshape(-1)
    m, n = G.shape
    if h.shape != (m,):
        raise ValueError(f"h must have {m} entries, got {h.shape}")
    names = tuple(names) if names is not None else tuple(f"x{j}" for j in range(n))
    if len(names) != n:
        raise ValueError(f"{len(names)} names for {n} unknowns")
    norms = _row_norms(G)
    zero = norms == 0
    bad = np.flatnonzero(zero & (h < 0))
    if bad.size:
        y = np.zeros(m)
        y[bad[0]] = 1.0
        far = FarkasCertificate(G, h, y)
        rc = far.recheck()
        return LinearFeasibility(False, names, None, None, None, None, far, rc, "not solved", solver,
                                 f"infeasible: row {bad[0]} reads 0 <= {h[bad[0]]:.6g}")
    keep = ~zero
    Gn, hn = G[keep] / norms[keep, None], h[keep] / norms[keep]
    k = len(hn)
    Gz = np.block([[Gn, np.ones((k, 1))], [np.zeros((1, n)), np.ones((1, 1))]])
    hz = np.concatenate([hn, [t_max]])
    cz = np.concatenate([np.zeros(n), [-1.0]])
    sol = solve_lp(cz, Gz, hz, solver=solver)
    x = None if sol.x is None else sol.x[:n]
    t = None if sol.x is None else float(sol.x[n])
    slacks = None if x is None else h - G @ x
    if sol.status not in LP_SOLVER_OK or x is None:
        return LinearFeasibility(None, names, x, slacks, t, None, None, None, sol.status, solver,
                                 f"undecided: solver status {sol.status!r}")
    point = FeasiblePointCertificate(G, h, x)
    farkas = None
    if sol.dual is not None:
        y = np.zeros(m)
        y[keep] = np.maximum(sol.dual[:k], 0.0) / norms[keep]
        y = _polish_farkas(G, y)
        farkas = FarkasCertificate(G, h, y) if np.any(y > 0) else None
    order = ("point", "farkas") if t is not None and t >= 0 else ("farkas", "point")
    tried: Recheck | None = None
    for which in order:
        if which == "point":
            tried = point.recheck()
            if tried.ok:
                return LinearFeasibility(True, names, x, slacks, t, point, farkas, tried, sol.status, solver,
                                         f"feasible: {tried.detail}")
        elif farkas is not None:
            tried = farkas.recheck()
            if tried.ok:
                return LinearFeasibility(False, names, x, slacks, t, point, farkas, tried, sol.status, solver,
                                         f"infeasible: {tried.detail}")
    return LinearFeasibility(None, names, x, slacks, t, point, farkas, tried, sol.status, solver,
                             f"undecided: margin t = {t:.3g} and neither x nor the Farkas vector re-checks")
