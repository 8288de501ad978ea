"""Condition certificates: named inequalities over plant parameters, certified over an uncertainty box.

A :class:`ConditionSet` is a family's statement of what makes its design work -- "the sliding mode
exists and is reached", "the joint loop is Hurwitz" -- as inequalities ``g_k(theta) > 0`` in named
plant parameters ``theta`` (the gains fixed), each written once as a CasADi expression.  Its form is
read off the expression, not declared:

* **affine** (the Hessian is structurally zero): ``g = c0 + c . theta``, certified on the LP core
  (:func:`designkit.verification.robust_linear.robust_linear_conditions`: a weak-duality lower bound
  re-checked in NumPy);
* **multi-affine** (affine in each parameter separately: every ``d^2 g / d theta_i^2`` is zero, e.g.
  ``4 alpha Km tau - 1``): certified at the box's vertices.  *Theorem.*  A multi-affine function
  attains its minimum over a box ``[lo, hi]`` at a vertex.  *Proof.*  Fix every parameter but
  ``theta_i``: ``g`` is affine in ``theta_i``, so on ``[lo_i, hi_i]`` its minimum is at an end; replacing
  ``theta_i`` of a minimiser by that end keeps it a minimiser; doing so for ``i = 1..k`` gives a vertex.
  So ``min_box g = min_vertices g`` exactly (the tests check it against a dense grid).  The vertex
  values are computed twice: by CasADi on the expression, and by NumPy on the expansion
  ``g = sum_S c_S prod_{i in S} theta_i`` whose coefficients ``c_S`` are CasADi's mixed partial
  derivatives at ``theta = 0``; the NumPy values, less their rounding bound (Higham's
  ``gamma_m sum |c_S prod theta_i|``), decide, and the two routes must agree to that bound;
* a set over no parameter (a plant whose entries are all numbers) is judged at its one point, as at a vertex;
* anything else (``1/tau`` uncleared, ``Km^2``): not certified here -- undecided, naming the
  condition and its form, never a pass.

A condition holds when its certified minimum is at least ``eps`` times the size of its terms
(:data:`~designkit.verification.tolerances.LP_EPS`); it fails only on a vertex (or an LP minimiser)
where NumPy computes ``g <= 0``.  The check is labelled by what the conditions are (``title``), with
each condition's slack -- its minimum over the box, in the condition's unit -- and where it occurs.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.verification.certificate import to_json
from designkit.verification.check import Check
from designkit.verification.tolerances import LP_EPS

__all__ = ["Condition", "ConditionSet", "certify", "form_of"]

MAX_PARAMETERS = 12
"""Most parameters of a box whose ``2^k`` vertices are enumerated."""
_U = float(np.finfo(float).eps) / 2.0


@dataclass(frozen=True)
class Condition:
    """One inequality ``g(theta) > 0``.

    Parameters
    ----------
    label : str
        The inequality in words and symbols (``"alpha Km - c + c^2 tau > 0"``).
    expression : callable
        ``Mapping[name, casadi.SX] -> casadi.SX``: ``g`` in the named parameters (gains as numbers).
    unit : str
        Unit of ``g``.
    meaning : str
        What it ensures (``"the sliding mode exists where x1 s > 0"``).
    """

    label: str
    expression: Callable[[Mapping[str, ca.SX]], ca.SX]
    unit: str = ""
    meaning: str = ""


@dataclass(frozen=True)
class ConditionSet:
    """Named inequalities over the plant parameters ``parameters``, certified together.

    Parameters
    ----------
    title : str
        What the conditions are, for the report (``"the sliding-mode existence and reaching conditions"``).
    parameters : tuple of str
        The plant parameters the conditions depend on (the box's axes).
    conditions : tuple of Condition
    """

    title: str
    parameters: tuple[str, ...]
    conditions: tuple[Condition, ...]


def _symbols(names: Sequence[str]) -> tuple[ca.SX, dict[str, ca.SX]]:
    theta = ca.SX.sym("theta", len(names))
    return theta, {n: theta[i] for i, n in enumerate(names)}


def _is_zero(expr: ca.SX) -> bool:
    """Structurally zero (or a zero constant) after CasADi's simplification."""
    expr = ca.simplify(ca.densify(expr)) if expr.numel() else expr
    return bool(expr.nnz() == 0 or (expr.is_constant() and np.all(np.asarray(ca.DM(expr)) == 0)))


def form_of(expr: ca.SX, theta: ca.SX) -> str:
    """``"affine"``, ``"multiaffine"`` or ``"general"`` in the symbols ``theta`` (see the module docstring)."""
    grad = ca.gradient(expr, theta)
    hess = ca.jacobian(grad, theta)
    if _is_zero(hess):
        return "affine"
    if all(_is_zero(hess[i, i]) for i in range(theta.numel())):
        return "multiaffine"
    return "general"


def _expansion(expr: ca.SX, theta: ca.SX) -> list[tuple[tuple[int, ...], float]]:
    """``[(S, c_S)]`` of the multi-affine ``expr = sum_S c_S prod_{i in S} theta_i`` (mixed partials at 0)."""
    k = theta.numel()
    zero = ca.DM.zeros(k)
    out = []
    for size in range(k + 1):
        for subset in itertools.combinations(range(k), size):
            d = expr
            for i in subset:
                d = ca.jacobian(d, theta[i])
            value = float(ca.Function("c", [theta], [d])(zero))
            if value != 0.0:
                out.append((subset, value))
    return out


def _numpy_values(terms: list[tuple[tuple[int, ...], float]], points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``g`` at ``points`` (rows) from the expansion, and a bound on its rounding error (Higham's gamma)."""
    values = np.zeros(points.shape[0])
    sizes = np.zeros(points.shape[0])
    depth = 1
    for subset, c in terms:
        prod = np.full(points.shape[0], c)
        for i in subset:
            prod = prod * points[:, i]
        values = values + prod
        sizes = sizes + np.abs(prod)
        depth = max(depth, len(subset) + 1)
    m = len(terms) + depth
    return values, sizes * (m * _U / (1.0 - m * _U))


def _words(point: Mapping[str, float]) -> str:
    """``"Km = 1.4, tau = 0.35"``."""
    return ", ".join(f"{n} = {v:.6g}" for n, v in point.items())


def _vertex_entry(cond: Condition, f: ca.Function, terms: list, names: Sequence[str], verts: np.ndarray,
                  eps: float) -> dict[str, Any]:
    via_casadi = np.asarray(f(verts.T), dtype=float).ravel()
    values, rounding = _numpy_values(terms, verts)
    sizes = np.array([sum(abs(c) * np.prod(np.abs(v[list(s)])) for s, c in terms) for v in verts])
    k = int(np.argmin(values - rounding))
    certified = float(values[k] - rounding[k])
    scale = float(sizes[k]) if sizes[k] > 0 else 1.0
    agree = bool(np.all(np.abs(values - via_casadi) <= 2 * rounding + 8 * _U * sizes))
    entry: dict[str, Any] = {
        "label": cond.label, "unit": cond.unit, "meaning": cond.meaning, "form": "multiaffine",
        "method": "vertices (minimum of a multi-affine function over a box)",
        "expansion": [{"monomial": [names[i] for i in s], "coefficient": c} for s, c in terms],
        "vertex_values": values.tolist(), "vertices": verts.tolist(),
        "minimum": float(values[k]), "at": {n: float(v) for n, v in zip(names, verts[k], strict=True)},
        "certified_lower_bound": certified, "rounding_bound": float(rounding[k]), "scale": scale,
        "routes_agree": agree, "margin": certified, "relative_margin": certified / scale,
    }
    unit = f" {cond.unit}" if cond.unit else ""
    if not agree:
        entry.update(passed=None, detail=f"{cond.label}: undecided, CasADi and the NumPy expansion disagree")
    elif values[k] + rounding[k] <= 0:
        entry.update(passed=False, evidence={"theta": entry["at"], "value": float(values[k]), "source": "vertex"},
                     detail=f"{cond.label}: value {values[k]:.6g}{unit} <= 0 at the vertex {_words(entry['at'])}")
    elif certified >= eps * scale:
        entry.update(passed=True, detail=f"{cond.label}: minimum {values[k]:.6g}{unit} over the box, at the "
                                         f"vertex {_words(entry['at'])}")
    else:
        entry.update(passed=None, detail=f"{cond.label}: undecided, minimum {values[k]:.3g}{unit} is within "
                                         "rounding of 0")
    return entry


def _affine_entry(cond: Condition, expr: ca.SX, theta: ca.SX, names: Sequence[str], lo: np.ndarray,
                  hi: np.ndarray, eps: float, solver: str) -> dict[str, Any]:
    from designkit.synthesis.design import LinearCondition
    from designkit.verification.lp import Polytope
    from designkit.verification.robust_linear import robust_linear_conditions

    zero = ca.DM.zeros(theta.numel())
    c0 = float(ca.Function("c0", [theta], [expr])(zero))
    grad = np.asarray(ca.Function("c", [theta], [ca.gradient(expr, theta)])(zero), dtype=float).ravel()
    linear = LinearCondition(cond.label, c0, dict(zip(names, grad.tolist(), strict=True)), cond.unit)
    check = robust_linear_conditions("condition", [linear], Polytope.box(tuple(names), lo, hi), eps=eps,
                                     solver=solver)
    entry = dict(check.certificate["conditions"][0])
    entry.update(meaning=cond.meaning, form="affine", method="LP on the box with a re-checked dual bound",
                 minimum=entry.get("vertex_min", entry.get("value_at_worst")),
                 at=entry.get("vertex_argmin", entry.get("worst_theta")))
    return entry


def certify(name: str, conditions: ConditionSet, box: Mapping[str, tuple[float, float]], *, eps: float = LP_EPS,
            solver: str = "CLARABEL") -> Check:
    """Check ``name``: every condition of ``conditions`` on the whole ``box`` (module docstring).

    Parameters
    ----------
    name : str
        Name of the returned check.
    conditions : ConditionSet
    box : Mapping
        ``{parameter: (lo, hi)}`` for every parameter of the set (a degenerate interval is one value).
    eps : float
        Relative margin a certified minimum must clear.
    solver : str
        cvxpy solver of the affine conditions' LPs.

    Returns
    -------
    Check
        True: every condition certified.  False: one is ``<= 0`` at a point of the box computed by NumPy
        (``certificate["evidence"]``).  None: otherwise (rounding, a general form, a solver failure).
        ``achieved`` and ``margin``: the smallest relative slack over the conditions (1).

    Raises
    ------
    ValueError
        A parameter without an interval, ``lo > hi``, or more than :data:`MAX_PARAMETERS` parameters.
    """
    names = tuple(conditions.parameters)
    missing = [n for n in names if n not in box]
    if missing:
        raise ValueError(f"no interval for {missing}")
    if len(names) > MAX_PARAMETERS:
        raise ValueError(f"at most {MAX_PARAMETERS} parameters, got {len(names)}")
    lo = np.array([float(box[n][0]) for n in names])
    hi = np.array([float(box[n][1]) for n in names])
    if np.any(lo > hi):
        raise ValueError("every interval needs lo <= hi")
    theta, sym = _symbols(names)
    verts = np.array(list(itertools.product(*[sorted({a, b}) for a, b in zip(lo, hi, strict=True)])), dtype=float)
    entries = []
    for cond in conditions.conditions:
        expr = ca.SX(cond.expression(sym))
        form = form_of(expr, theta) if names else "multiaffine"  # no parameter: one plant, its one "vertex"
        if form == "affine":
            entries.append(_affine_entry(cond, expr, theta, names, lo, hi, eps, solver))
        elif form == "multiaffine":
            f = ca.Function("g", [theta], [expr]).map(verts.shape[0])
            entries.append(_vertex_entry(cond, f, _expansion(expr, theta), names, verts, eps))
        else:
            entries.append({"label": cond.label, "unit": cond.unit, "meaning": cond.meaning, "form": "general",
                            "passed": None, "detail": f"{cond.label}: undecided, neither affine nor multi-affine in "
                            f"({', '.join(names)}): a box certificate needs an interval enclosure"})
    forms = sorted({e["form"] for e in entries})
    cert: dict[str, Any] = {"title": conditions.title, "parameters": list(names),
                            "box": {n: [float(a), float(b)] for n, a, b in zip(names, lo, hi, strict=True)},
                            "forms": forms, "eps": eps, "conditions": to_json(entries)}
    target = f"{conditions.title} on the whole box"
    unit = "1 (relative to the size of the terms)"
    where = ", ".join(f"{n} in [{a:.4g}, {b:.4g}]" for n, a, b in zip(names, lo, hi, strict=True))
    failed = [e for e in entries if e["passed"] is False]
    if failed:
        worst = min(failed, key=lambda e: e.get("relative_margin", 0.0))
        cert["evidence"] = dict(worst["evidence"], condition=worst["label"])
        rel = worst.get("relative_margin")
        return Check(name=name, passed=False, target=target, achieved=rel, margin=rel, unit=unit,
                     detail=f"{conditions.title}: not every condition holds on the box ({where}): {worst['detail']}",
                     certificate=cert)
    rels = [e["relative_margin"] for e in entries if e.get("relative_margin") is not None]
    margin = float(min(rels)) if rels else None
    undecided = [e for e in entries if e["passed"] is None]
    if undecided:
        return Check(name=name, passed=None, target=target, achieved=margin, margin=margin, unit=unit,
                     detail=f"{conditions.title}: {undecided[0]['detail']}", certificate=cert)
    slacks = "; ".join(f"{e['label']}: min {e['minimum']:.4g}{(' ' + e['unit']) if e['unit'] else ''}"
                       for e in entries if e.get("minimum") is not None)
    return Check(name=name, passed=True, target=target, achieved=margin, margin=margin, unit=unit,
                 detail=f"{conditions.title}: {'every condition holds' if len(entries) > 1 else 'holds'} on the whole "
                        f"box ({where}; {' and '.join(forms)} in {', '.join(names)}, so the minimum over the box is "
                        f"certified): {slacks}",
                 certificate=cert)
