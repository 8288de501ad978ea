"""The LP core's certificates, re-checked in NumPy: a lower bound by weak duality, a feasible point, a Farkas vector.

The solver's numbers are proposals; each certificate's :meth:`recheck` recomputes in NumPy what it
claims, with the floating-point error of its sums bounded (:func:`designkit.verification.lp.gamma`),
and the re-check decides (:mod:`designkit.verification.lp` states the inequalities).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from designkit.verification.certificate import Recheck, array_from_json, to_json
from designkit.verification.lp import _readonly, gamma
from designkit.verification.tolerances import FARKAS_TOL, LP_EPS

__all__ = ["FarkasCertificate", "FeasiblePointCertificate", "LowerBoundCertificate"]


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
        rounding = 2.0 * gamma(len(b) + len(c) + 3) * float(terms)
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
        rounding = gamma(len(x) + 1) * (np.abs(h) + np.abs(G) @ np.abs(x))
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
        rounding = gamma(len(h) + 1) * float(np.abs(h) @ y)
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


