"""The sliding-mode conditions of the link servo, over a box of ``(Km, tau)``: derived in the package docstring.

With ``a = 1/tau``, ``b = Km/tau`` and the bound ``k = (a - c) c / b = c (1 - c tau)/Km`` (N*m/rad), the
conditions, each multiplied by ``Km > 0`` or ``4 Km tau > 0`` so that it is affine or multi-affine in
``(Km, tau)`` (:mod:`designkit.verification.conditions` certifies those forms exactly over a box):

* existence, ``psi = alpha`` side: ``alpha > k``        <=>  ``alpha Km - c + c^2 tau > 0``  (1/s, affine);
* existence, ``psi = beta`` side:  ``beta < k``         <=>  ``c - c^2 tau - beta Km > 0``   (1/s, affine);
* perturbation: ``M > sup |xi|``                         <=>  ``M - xi_bar > 0``               (N*m, constant);
* reaching (the ``alpha`` structure is a focus): ``alpha > a^2/(4 b)``  <=>  ``4 alpha Km tau - 1 > 0``
  (1, multi-affine).

Bounds the run uses (all maxima of convex functions of ``(a, b)`` over the image of the box, a convex
quadrilateral whose vertices are the images of the box's corners, so attained at a corner):

* ``|s'| <= sdot_max = |c - a| delta + max(|c(c - a) + b alpha|, |c(c - a) + b beta|) e_max + b (M + xi_bar)``
  wherever ``|s| <= delta`` and ``|e| <= e_max`` (:func:`sdot_bound`);
* ``s s' <= (c - a) s^2 - b (M - xi_bar) |s|``: ``|s|`` decreases at least at ``eta = b_min (M - xi_bar)`` near
  the line (:func:`reaching_rate`), everywhere when ``c tau <= 1``, else in the strip
  ``|s| < Km_lo (M - xi_bar)/(c tau_hi - 1)`` (:func:`strip_width`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from designkit.verification.conditions import Condition, ConditionSet

__all__ = ["PARAMETERS", "SlidingGains", "condition_sets", "existence_bound", "focus_bound", "reaching_rate",
           "sdot_bound", "strip_width", "vertices"]

PARAMETERS = ("Km", "tau")
"""The link parameters the conditions depend on (the box's axes)."""

Box = Mapping[str, tuple[float, float]]


@dataclass(frozen=True)
class SlidingGains:
    """The law's gains: ``alpha``, ``beta`` (N*m/rad), ``M`` (N*m), ``c`` (1/s)."""

    alpha: float
    beta: float
    M: float
    c: float


def vertices(box: Box) -> np.ndarray:
    """The corners ``(Km, tau)`` of ``box``, shape ``(4, 2)`` (fewer for a degenerate interval)."""
    return np.array(list(itertools.product(*[sorted({float(box[n][0]), float(box[n][1])}) for n in PARAMETERS])))


def existence_bound(c: float, Km: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``k = (a - c) c / b = c (1 - c tau)/Km`` (N*m/rad): ``alpha > k > beta`` for the sliding mode to exist."""
    return c * (1.0 - c * np.asarray(tau, float)) / np.asarray(Km, float)


def focus_bound(Km: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``a^2/(4 b) = 1/(4 Km tau)`` (N*m/rad): ``alpha`` above it makes ``e'' + a e' + b alpha e`` a focus."""
    return 1.0 / (4.0 * np.asarray(Km, float) * np.asarray(tau, float))


def condition_sets(g: SlidingGains, xi_bar: float) -> dict[str, ConditionSet]:
    """The three labelled sets the certificate checks: ``existence``, ``reaching``, ``perturbation``."""
    al, be, M, c = g.alpha, g.beta, g.M, g.c
    existence = ConditionSet(
        title="the existence conditions of the sliding mode on s = 0",
        parameters=PARAMETERS,
        conditions=(
            Condition(f"alpha Km - c + c^2 tau > 0 (alpha = {al:.6g} > c (1 - c tau)/Km)",
                      lambda p: al * p["Km"] - c + c * c * p["tau"], "1/s",
                      "where e s > 0 the structure alpha turns s' against s: u_eq >= u+ on s = 0"),
            Condition(f"c - c^2 tau - beta Km > 0 (beta = {be:.6g} < c (1 - c tau)/Km)",
                      lambda p: c - c * c * p["tau"] - be * p["Km"], "1/s",
                      "where e s < 0 the structure beta turns s' against s: u_eq <= u- on s = 0"),
        ),
    )
    reaching = ConditionSet(
        title="the reaching conditions (the alpha structure a focus)",
        parameters=PARAMETERS,
        conditions=(
            Condition(f"4 alpha Km tau - 1 > 0 (alpha = {al:.6g} > a^2/(4 b) = 1/(4 Km tau))",
                      lambda p: 4.0 * al * p["Km"] * p["tau"] - 1.0, "1",
                      "the structure alpha is a focus: every trajectory in e s > 0 turns onto s = 0 in finite time"),
        ),
    )
    perturbation = ConditionSet(
        title="the perturbation conditions (the relay above sup|xi|)",
        parameters=PARAMETERS,
        conditions=(
            Condition(f"M - sup|xi| > 0 (M = {M:.6g} N*m, sup|xi| = {xi_bar:.6g} N*m)",
                      lambda p: M - xi_bar + 0.0 * p["Km"], "N*m",
                      "the relay dominates the perturbation: the sliding mode exists at e = 0 and |s| shrinks "
                      "near the line"),
        ),
    )
    return {"existence": existence, "reaching": reaching, "perturbation": perturbation}


def sdot_bound(g: SlidingGains, xi_bar: float, box: Box, e_max: float, band: float = 0.0) -> float:
    """``max |s'|`` (rad/s^2) over the box where ``|s| <= band`` (rad/s) and ``|e| <= e_max`` (rad).

    ``s' = (c - a) s - (c (c - a) + b psi) e - b M sign(s) + b xi`` on the link, so
    ``|s'| <= |c - a| band + max_psi |c (c - a) + b psi| e_max + b (M + xi_bar)``, a convex function of
    ``(a, b)``: its maximum over the box is at a corner (module docstring).
    """
    v = vertices(box)
    a, b = 1.0 / v[:, 1], v[:, 0] / v[:, 1]
    c = g.c
    k = np.maximum(np.abs(c * (c - a) + b * g.alpha), np.abs(c * (c - a) + b * g.beta))
    return float(np.max(np.abs(c - a) * band + k * e_max + b * (abs(g.M) + xi_bar)))


def reaching_rate(M: float, xi_bar: float, box: Box) -> float:
    """``eta = b_min (M - xi_bar)`` (rad/s^2, ``b_min = Km_lo/tau_hi``): the rate ``|s|`` shrinks at near the line
    (negative when the relay is weaker than the perturbation)."""
    v = vertices(box)
    return float(np.min(v[:, 0] / v[:, 1]) * (M - xi_bar))


def strip_width(M: float, xi_bar: float, c: float, box: Box) -> float:
    """Half-width (rad/s) of the strip about ``s = 0`` where ``s s' <= (c - a) s^2 - b (M - xi_bar) |s| < 0``:
    ``Km_lo (M - xi_bar)/(c tau_hi - 1)``, infinite when ``c tau_hi <= 1``, 0 when ``M <= xi_bar``."""
    if M - xi_bar <= 0:
        return 0.0
    km_lo, tau_hi = float(box["Km"][0]), float(box["tau"][1])
    if c * tau_hi <= 1.0:
        return math.inf
    return km_lo * (M - xi_bar) / (c * tau_hi - 1.0)
