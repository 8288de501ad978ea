"""Robust linear conditions: ``c0 + c . theta > 0`` for every ``theta`` of a parameter polytope, on the LP core.

The LP ``min c . theta`` over the polytope proposes a worst case and multipliers; the weak-duality
:class:`~designkit.verification.lp_certificates.LowerBoundCertificate`, re-checked in NumPy, decides
(the inequality is in :mod:`designkit.verification.lp`).  A condition fails only on a counterexample
NumPy computes: the LP's minimiser pulled inside the polytope, or a vertex of a box.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.synthesis.design import LinearCondition
from designkit.verification.certificate import to_json
from designkit.verification.check import Check
from designkit.verification.lp import _MAX_VERTEX_DIM, Polytope, solve_lp
from designkit.verification.lp_certificates import LowerBoundCertificate
from designkit.verification.lp_feasibility import linear_feasibility
from designkit.verification.tolerances import LP_EPS, LP_SOLVER_OK

__all__ = ["robust_linear_conditions"]


def _named(names: Sequence[str], theta: np.ndarray) -> dict[str, float]:
    return {n: float(v) for n, v in zip(names, theta, strict=True)}


def _point_words(names: Sequence[str], theta: np.ndarray) -> str:
    """``"Km = 1.4, tau = 0.35"`` for a message."""
    return ", ".join(f"{n} = {float(v):.6g}" for n, v in zip(names, theta, strict=True))


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
                detail=f"{cond.label}: value {v:.6g}{unit} <= 0 at the {source} {_point_words(names, theta)}",
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


