"""Theorem 3's switching gains over the uncertainty box: ``l_i(p)``, their proven ranges, the conditions.

**Equivalent-control gains.**  With ``sigma = c x`` and ``x' = A x + B u + D d``:
``sigma' = c A x + c B u + c D d``.  On ``sigma' = 0`` (``d = 0``) the equivalent control is
``u_eq = -(cB)^-1 c A x = sum_i l_i x_i`` with

    l_i(p) = -(c A(p))_i / (c B(p))        (input units per unit of x_i).

**Reaching condition.**  With the law ``u = sum_i psi_i x_i - delta sign(sigma)``::

    sigma sigma' = cB sum_i (psi_i - l_i) x_i sigma - cB delta |sigma| + cD d sigma.

With ``cB > 0`` (the normalisation of :mod:`~designkit.families.vsc.surface`) and the convention of the notes'
figure 5.3 -- ``psi_i = alpha_i`` where ``x_i sigma > 0``, ``beta_i`` where ``x_i sigma < 0`` -- every term
``(psi_i - l_i) x_i sigma`` is ``<= 0`` exactly when ``alpha_i < l_i < beta_i``, and the last two are
``<= -(cB delta - |cD| d_bar)|sigma| < 0`` when ``delta > |cD| d_bar / cB`` (``|d| <= d_bar``).  So

    alpha_i < l_i(p) < beta_i    for every p of the box,      delta > d_bar sup_box |cD(p)|/cB(p)

give ``sigma sigma' <= -(cB delta - |cD| d_bar)|sigma|`` everywhere: ``sigma`` reaches 0 in finite time
``<= |sigma(0)| / min_box(cB delta - |cD| d_bar)`` and stays (theorem 3 with ``delta > 0``).

**Form over the box.**  ``l_i`` is a ratio (``1/Km``, ``1/J1``, ``1/J2``, ``1/tau2`` on the elastic joint), not
multi-affine.  :func:`rational_forms` writes each as ``N_i(p)/M_i(p)`` with ``M_i`` a positive monomial (derived by
hand per plant kind, checked against the plant's own linearisation in the tests), and each condition is certified
multiplied by ``M_i``, e.g. ``Km (l_2 - alpha_2) = 1 - c_1 tau1 - alpha_2 Km`` (affine) or
``Km J1 J2 (l_1 - alpha_1) = tau1 KR (R1^2 J2 - c4 R2^2 J1) - alpha_1 Km J1 J2`` (multi-affine while
``R1, R2`` are fixed).  When the cleared form is multi-affine in the box's parameters, ``min_box l_i`` and
``max_box l_i`` are attained at vertices (``N_i - a M_i`` is multi-affine for every number ``a``; its minimum is
at a vertex, so ``a = min_vertices l_i`` keeps it ``>= 0`` on the box) and the condition-certificate core certifies
them exactly.  Otherwise (``R1`` or ``R2`` uncertain: ``R1^2``) the range is the proven enclosure of
:func:`designkit.bounds.enclose`, and the certificate is that enclosure.

**Design with a margin** ``m``: ``alpha_i = min l_i - m S_i``, ``beta_i = max l_i + m S_i`` with
``S_i = max(max_box |l_i|, |c_i| rho / cB_nom)`` (``rho`` the fastest sliding pole, so that a gain whose ``l_i`` is
identically 0 -- the link's ``l_1`` -- still gets a margin in its own unit); ``delta = (1 + m) d_bar sup|cD|/cB``
(``d_bar`` the perturbation bound), or the spec's ``delta``.
These are the minimal-switching gains: the jump of ``u`` across ``sigma = 0`` is
``sum_i (beta_i - alpha_i)|x_i| + 2 delta``, which each bound minimises separately.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.verification.conditions import Condition, ConditionSet, form_of

__all__ = ["LINEAR", "Bound", "VscGains", "bound_ranges", "condition_sets", "design_gains", "l_expressions",
           "linear_forms", "rational_forms"]

ENCLOSE_TOL = 1e-6
"""Relative tolerance of the proven enclosures (when a cleared condition is not multi-affine)."""

Box = Mapping[str, tuple[float, float]]


@dataclass(frozen=True)
class VscGains:
    """``alpha``, ``beta`` (input units per state unit), ``delta`` (input units), ``c`` (sigma per state unit)."""

    alpha: tuple[float, ...]
    beta: tuple[float, ...]
    delta: float
    c: tuple[float, ...]


@dataclass(frozen=True)
class Bound:
    """The range of one expression of the plant parameters over the box.

    Attributes
    ----------
    label : str
        ``"l_1"``, ``"|cD|/cB"``.
    lower, upper : float
        Its range: exact (at vertices) for ``method == "vertices"``, proven bounds for ``"enclosure"``.
    argmin, argmax : dict
        Where the ends are attained (a vertex or the enclosure's witness).
    method : str
        ``"vertices"`` (the cleared form is affine or multi-affine) or ``"enclosure"``.
    form : str
        The cleared form: ``"constant"``, ``"affine"``, ``"multiaffine"`` or ``"general"``.
    min_value, max_value : float or None
        The values attained at ``argmin`` and ``argmax`` (equal to ``lower``, ``upper`` at vertices; within the
        enclosure's tolerance of them otherwise).
    """

    label: str
    lower: float
    upper: float
    argmin: dict[str, float]
    argmax: dict[str, float]
    method: str
    form: str
    min_value: float | None = None
    max_value: float | None = None


LINEAR = ("transfer_function", "state_space")
"""The general linear plant kinds: their forms come from the plant's own matrices (:func:`linear_forms`)."""


def linear_forms(model: Any, c: Sequence[float], rest: tuple[Sequence[float], float] | None = None,
                 reference_max: float = 0.0) -> dict[str, tuple[Any, Any]]:
    """The forms of a ``transfer_function`` or ``state_space`` plant, cleared by ``cB(p)`` (certified positive on
    the box by the orientation set): ``l_i = -(c A)_i / cB``, ``cB = cB/1``, ``cD/cB = 1`` (the disturbance is
    input-equivalent, ``D = B``, :mod:`designkit.models.linear_plant`) and, with ``rest = (x*, u*)``
    (the nominal plant's rest per unit of reference), ``rest = c (A x* + B u*) X / cB``: the share of ``sigma'`` a
    plant of the box leaves at the nominal rest at the largest reference ``X`` (zero on the nominal plant)."""
    cv = ca.DM(np.asarray(c, float)).T
    cA = cv @ model.A
    cB = (cv @ model.B)[0, 0]
    names = list(model.names)

    def at(expr: Any) -> Any:
        def f(p: Mapping[str, Any]) -> Any:
            if not names:
                return ca.SX(expr) + 0.0 * next(iter(p.values()), 0.0) if p else ca.SX(expr)
            return ca.substitute(ca.SX(expr), model.p, ca.vertcat(*[ca.SX(p[n]) for n in names]))
        return f

    forms = {f"l_{i + 1}": (at(-cA[0, i]), at(cB)) for i in range(model.A.size1())}
    forms["cB"] = (at(cB), at(ca.SX(1.0)))
    forms["cD/cB"] = (at(ca.SX(1.0)), at(ca.SX(1.0)))  # the disturbance is input-equivalent: D = B
    if rest is not None:
        x_star, u_star = np.asarray(rest[0], float), float(rest[1])
        m = (cv @ (model.A @ ca.DM(x_star) + model.B * u_star))[0, 0] * float(reference_max)
        forms["rest"] = (at(m), at(cB))
    return forms


def rational_forms(plant_kind: str, c: Sequence[float], model: Any = None,
                   rest: tuple[Sequence[float], float] | None = None,
                   reference_max: float = 0.0) -> dict[str, tuple[Any, Any]]:
    """``{label: (N, M)}`` with ``label`` = ``N(p)/M(p)`` and ``M`` a positive monomial of the parameters: the
    ``l_i``, ``cB`` and ``cD/cB`` of the plant kinds this family designs for, written cleared of their
    denominators (derived in the module docstring of :mod:`designkit.families.vsc`; the tests check each against
    ``-(cA)_i/(cB)`` of the plant's own linearisation).  ``N`` and ``M`` take a mapping name -> value or symbol.
    On a linear plant kind they are :func:`linear_forms` of ``model`` (``M = cB``, positive on the box by the
    orientation condition), with the rest mismatch when ``rest`` is given."""
    if plant_kind in LINEAR:
        return linear_forms(model, c, rest, reference_max)
    c = [float(v) for v in c]
    if plant_kind == "link":
        c1 = c[0] / c[1]  # c normalised: c[1] = 1
        return {
            "l_1": (lambda p: 0.0 * p["Km"], lambda p: p["Km"]),
            "l_2": (lambda p: 1.0 - c1 * p["tau"], lambda p: p["Km"]),
            "cB": (lambda p: p["Km"], lambda p: p["tau"]),
            "cD/cB": (lambda p: 1.0 + 0.0 * p["Km"], lambda p: 1.0 + 0.0 * p["Km"]),
        }
    c1, c2, c3, c4 = c
    if c2 != 1.0:
        raise ValueError("c must be normalised with c2 = 1")
    return {
        "l_1": (lambda p: p["tau1"] * p["KR"] * (p["R1"] * p["R1"] * p["J2"] - c4 * p["R2"] * p["R2"] * p["J1"]),
                lambda p: p["Km"] * p["J1"] * p["J2"]),
        "l_2": (lambda p: 1.0 - c1 * p["tau1"], lambda p: p["Km"]),
        "l_3": (lambda p: -p["tau1"] * (p["KR"] * p["R1"] * p["R1"] * p["J2"]
                                        - c4 * (p["KR"] * p["R2"] * p["R2"] + p["mgl"]) * p["J1"]),
                lambda p: p["Km"] * p["J1"] * p["J2"]),
        "l_4": (lambda p: p["tau1"] * (c4 - c3 * p["tau2"]), lambda p: p["Km"] * p["tau2"]),
        "cB": (lambda p: p["Km"], lambda p: p["tau1"]),
        "cD/cB": (lambda p: c4 * p["R2"] * p["tau1"], lambda p: p["J2"] * p["Km"]),
    }


def _point(model: Any, box: Box, syms: Mapping[str, Any]) -> dict[str, Any]:
    """Every parameter: its box symbol, or its nominal value."""
    return {n: syms[n] if n in syms else float(model.nominal[i]) for i, n in enumerate(model.names)}


def _vertices(names: Sequence[str], box: Box) -> list[dict[str, float]]:
    axes = [sorted({float(box[n][0]), float(box[n][1])}) for n in names]
    return [dict(zip(names, v, strict=True)) for v in itertools.product(*axes)]


def box_names(model: Any, box: Box) -> tuple[str, ...]:
    """The box's parameters in the plant's order."""
    return tuple(n for n in model.names if n in box)


def bound_ranges(forms: Mapping[str, tuple[Any, Any]], model: Any, box: Box) -> dict[str, Bound]:
    """The range of each ``N/M`` over ``box`` (module docstring: at the vertices when ``N - a M`` is affine or
    multi-affine in the box's parameters, else the proven enclosure)."""
    from designkit.bounds import enclose

    names = box_names(model, box)
    syms = {n: ca.SX.sym(n) for n in names}
    theta = ca.vertcat(*syms.values())
    a = ca.SX.sym("a")
    out = {}
    for label, (num, den) in forms.items():
        p = _point(model, box, syms)
        N, M = ca.SX(num(p)), ca.SX(den(p))
        form = form_of(N - a * M, theta)
        f = ca.Function("f", [theta], [N / M], ["p"], ["o"])
        if form in ("affine", "multiaffine"):
            verts = _vertices(names, box)
            vals = [float(f(list(v.values()))) for v in verts]
            i, j = int(np.argmin(vals)), int(np.argmax(vals))
            out[label] = Bound(label, vals[i], vals[j], verts[i], verts[j], "vertices", form, vals[i], vals[j])
        elif not ca.depends_on(N / M, theta) if names else True:  # a constant: its range is its value, exactly
            v = float(ca.Function("v", [theta], [N / M])(np.array([box[n][0] for n in names], float)))
            at = {n: float(box[n][0]) for n in names}
            out[label] = Bound(label, v, v, at, at, "enclosure", form, v, v)
        else:
            lo = np.array([box[n][0] for n in names], float)
            hi = np.array([box[n][1] for n in names], float)
            enc = enclose(f, {"p": (lo, hi)}, rel_tol=ENCLOSE_TOL)
            amin = dict(zip(names, np.asarray(enc.argmin["p"]).ravel().tolist(), strict=True))
            amax = dict(zip(names, np.asarray(enc.argmax["p"]).ravel().tolist(), strict=True))
            out[label] = Bound(label, float(enc.lower), float(enc.upper), amin, amax, "enclosure", form,
                               float(enc.min_value), float(enc.max_value))
    return out


def l_expressions(model: Any, c: Sequence[float]) -> tuple[dict[str, ca.SX], ca.SX, ca.SX]:
    """``({"l_i": -(cA)_i/(cB)}, cB, cD)`` as expressions of the plant parameters, from the plant's own
    linearisation (the generic route, used to check :func:`rational_forms` and for the recorded ``u_eq``)."""
    cv = ca.DM(np.asarray(c, float)).T
    cA = cv @ model.A
    cB = (cv @ model.B)[0, 0]
    cD = (cv @ model.D)[0, 0] if model.D.numel() else ca.SX(0.0)
    return {f"l_{i + 1}": -cA[0, i] / cB for i in range(model.A.size1())}, cB, cD


def design_gains(bounds: Mapping[str, Bound], c: Sequence[float], rho: float, cB_nominal: float, margin: float,
                 fixed_alpha: Sequence[float] | None, fixed_beta: Sequence[float] | None,
                 ) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """``(alpha, beta, S)``: the minimal-switching gains with margin ``m`` (module docstring), or the given ones."""
    n = len(c)
    S = []
    alpha, beta = [], []
    for i in range(n):
        b = bounds[f"l_{i + 1}"]
        s = max(abs(b.lower), abs(b.upper), abs(c[i]) * rho / cB_nominal)
        S.append(s)
        alpha.append(b.lower - margin * s)
        beta.append(b.upper + margin * s)
    if fixed_alpha is not None:
        alpha = [float(v) for v in fixed_alpha]
    if fixed_beta is not None:
        beta = [float(v) for v in fixed_beta]
    return tuple(alpha), tuple(beta), tuple(S)


def condition_sets(g: VscGains, forms: Mapping[str, tuple[Any, Any]], model: Any, box: Box,
                   bounds: Mapping[str, Bound], d_bar: float) -> dict[str, ConditionSet]:
    """The sets the certificate checks: ``gains`` (``N_i - alpha_i M_i > 0`` and ``beta_i M_i - N_i > 0``, i.e.
    ``alpha_i < l_i < beta_i`` cleared by the positive ``M_i``), ``relay`` (``(delta -+ d_bar cD/cB) M > 0``, or
    ``delta > 0`` without a perturbation; on a linear plant ``delta cB -+ d_bar cD -+ c (A x* + B u*) X > 0``, the
    rest mismatch included) and ``orientation`` (``cB > 0``).  Conditions on a bound whose cleared
    form is general are left out of the sets (certified on the enclosure instead)."""
    names = box_names(model, box)

    def full(p: Mapping[str, Any]) -> dict[str, Any]:
        return {n: p[n] if n in p else float(model.nominal[i]) for i, n in enumerate(model.names)}

    conds = []
    for i in range(len(g.c)):
        key = f"l_{i + 1}"
        if bounds[key].method != "vertices":
            continue
        num, den = forms[key]
        al, be = g.alpha[i], g.beta[i]
        conds.append(Condition(
            f"N_{i + 1} - alpha_{i + 1} M_{i + 1} > 0 (alpha_{i + 1} = {al:.6g} < l_{i + 1} = N_{i + 1}/M_{i + 1})",
            lambda p, num=num, den=den, al=al: num(full(p)) - al * den(full(p)), "",
            f"where x_{i + 1} sigma > 0 the gain alpha_{i + 1} turns sigma' against sigma"))
        conds.append(Condition(
            f"beta_{i + 1} M_{i + 1} - N_{i + 1} > 0 (beta_{i + 1} = {be:.6g} > l_{i + 1})",
            lambda p, num=num, den=den, be=be: be * den(full(p)) - num(full(p)), "",
            f"where x_{i + 1} sigma < 0 the gain beta_{i + 1} turns sigma' against sigma"))
    sets = {"gains": ConditionSet("theorem 3's gain conditions alpha_i < l_i < beta_i", names, tuple(conds))}
    num, den = forms["cD/cB"]
    if "rest" in forms:
        if bounds["rest"].method == "vertices":
            rnum, rden = forms["rest"]
            conds = []
            for sd, sr in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                conds.append(Condition(
                    f"(delta {'-' if sd > 0 else '+'} d_bar) cB {'-' if sr > 0 else '+'} c (A x* + B u*) X > 0 "
                    f"(delta = {g.delta:.6g}, d_bar = {d_bar:.6g})",
                    lambda p, sd=sd, sr=sr, rnum=rnum, rden=rden: ((g.delta - sd * d_bar) * rden(full(p))
                                                                  - sr * rnum(full(p))), "",
                    "the relay dominates the perturbation and the rest mismatch of the plant in sigma'"))
            sets["relay"] = ConditionSet("the relay delta above the perturbation's and the rest mismatch's share of "
                                         "sigma'", names, tuple(conds))
    elif d_bar > 0 and bounds["cD/cB"].method == "vertices":
        sets["relay"] = ConditionSet("the relay delta above the perturbation's share of sigma'", names, (
            Condition(f"delta M - d_bar N > 0 (delta = {g.delta:.6g}, d_bar = {d_bar:.6g}, cD/cB = N/M)",
                      lambda p, num=num, den=den: g.delta * den(full(p)) - d_bar * num(full(p)), "",
                      "the relay dominates a perturbation d >= 0 in sigma'"),
            Condition(f"delta M + d_bar N > 0 (delta = {g.delta:.6g}, d_bar = {d_bar:.6g})",
                      lambda p, num=num, den=den: g.delta * den(full(p)) + d_bar * num(full(p)), "",
                      "the relay dominates a perturbation d <= 0 in sigma'")))
    else:
        sets["relay"] = ConditionSet("the relay delta > 0", names, (
            Condition(f"delta > 0 (delta = {g.delta:.6g})", lambda p: g.delta + 0.0 * p[names[0]], "",
                      "finite-time reaching near the origin"),))
    num, den = forms["cB"]
    if bounds["cB"].method != "vertices":  # certified on the proven range of cB instead
        return sets
    sets["orientation"] = ConditionSet("the orientation cB > 0 the gain conditions are written for", names, (
        Condition("N_B M_B > 0 (cB = N_B/M_B)", lambda p: num(full(p)) * den(full(p)), "",
                  "alpha_i < l_i < beta_i (not the reverse) turns sigma' against sigma"),))
    return sets
