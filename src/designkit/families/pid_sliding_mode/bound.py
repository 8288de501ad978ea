"""The bound ``sup |xi|`` the relay must dominate (notes §5.4), over the parameter box and the sliding motion.

On ``slm = 0`` the motion is the plant-independent one of
:func:`~designkit.families.pid_sliding_mode.surface.ideal_motion`, so ``x2(t)`` and the PID part ``u0(t)`` are
known from the reference alone.  A true link ``(Km, tau)`` of the box adds (referred to its own input gain)
``xi_p = (tau/Km)[(1/tau0 - 1/tau) x2 + (Km/tau - Km0/tau0) u0]``, and
``Km xi_p = tau (x2/tau0 - (Km0/tau0) u0) - x2 + Km u0`` is affine in ``(Km, tau)`` for each ``(x2, u0)`` and
linear in ``(x2, u0)`` for each plant: its largest modulus over the box and the motion is at a corner of the box
and a vertex of the convex hull of the points ``(x2(t), u0(t))``, so at most its value at the vertices of any
polygon enclosing them (:func:`hull_points`: 48 sides, at most 0.2 % beyond the hull).  The relay conditions
``Km (M - xi_e) -+ (tau (x2/tau0 - (Km0/tau0) u0) - x2 + Km u0) > 0`` at every polygon vertex (affine,
certified on the LP core) then give ``M > sup|xi_p| + xi_e`` on the box and the motion, ``xi_e`` the external
bound.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import ModelError, SpecError
from designkit.families.pid_sliding_mode.surface import Surface, ideal_motion, perturbation_of_change
from designkit.verification.conditions import Condition, ConditionSet

__all__ = ["PARAMETERS", "PerturbationBound", "design_box", "hull_points", "perturbation_bound", "relay_set"]

PARAMETERS = ("Km", "tau")
Box = Mapping[str, tuple[float, float]]


def design_box(spec: Any, plant: Any) -> tuple[dict[str, tuple[float, float]], list[str]]:
    """The ``(Km, tau)`` box (``plant.uncertainty``, widened to hold the nominal plant and
    ``simulation.plant_change``), and notes saying where it was widened."""
    unc = spec.plant.uncertainty
    intervals = unc.intervals if unc is not None else {}
    change = spec.simulation.plant_change
    if change is not None:
        try:
            plant.with_params(**change.values)
        except ModelError as exc:
            raise SpecError(f"simulation.plant_change.values.{exc.field}", exc.message) from None
    box, notes = {}, []
    for name in PARAMETERS:
        nominal = float(plant.parameter(name).value)
        lo, hi = intervals.get(name, (nominal, nominal))
        values = [lo, hi, nominal] + ([float(change.values[name])] if change and name in change.values else [])
        box[name] = (min(values), max(values))
        if box[name] != (lo, hi) and (name in intervals or box[name][0] != box[name][1]):
            notes.append(f"The {name} interval was widened from [{lo:g}, {hi:g}] to [{box[name][0]:g}, "
                         f"{box[name][1]:g}] to hold the nominal plant and the plant change the run meets.")
    return box, notes


def corners(box: Box) -> np.ndarray:
    """The corners ``(Km, tau)`` of ``box``."""
    return np.array(list(itertools.product(*[sorted({float(box[n][0]), float(box[n][1])}) for n in PARAMETERS])))


def pid_part(form: str, gains: Mapping[str, float], x1: np.ndarray, x2: np.ndarray, x3: np.ndarray,
             ref: np.ndarray, Km0: float, tau0: float) -> np.ndarray:
    """``u0`` (N*m), the PID part of the command: servo ``-K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD``, tracking
    ``(tau0/Km0) xD'' + x2/Km0 - K1 dx1 - K2 dx2 - K3 x3``."""
    K1, K2, K3 = (float(gains[k]) for k in ("K1", "K2", "K3"))
    if form == "tracking":
        return (tau0 / Km0) * ref[:, 2] + x2 / Km0 - K1 * (x1 - ref[:, 0]) - K2 * (x2 - ref[:, 1]) - K3 * x3
    K4 = float(gains["K4"])
    return -K1 * (x1 - ref[:, 0]) - K2 * x2 - K3 * x3 + K3 * K4 * ref[:, 0]


SIDES = 48
"""Sides of the polygon enclosing the motion's points ``(x2, u0)``: its support in every direction exceeds the
points' by at most ``1/cos(pi/SIDES) - 1`` (0.2 %) of the points' extent (in the scaled coordinates)."""


def hull_points(x2: np.ndarray, u0: np.ndarray, sides: int = SIDES) -> np.ndarray:
    """The vertices of a ``sides``-gon that contains every point ``(x2, u0)``: the support lines of the points
    (scaled to unit extent per coordinate) in ``sides`` equally spaced directions, intersected in turn.  Every
    point is inside, so a condition linear in ``(x2, u0)`` that holds at the vertices holds on the motion."""
    pts = np.column_stack([x2, u0]).astype(float)
    centre = (pts.max(axis=0) + pts.min(axis=0)) / 2
    scale = np.maximum(np.ptp(pts, axis=0) / 2, 1e-9 * (1.0 + np.abs(centre)))
    z = (pts - centre) / scale
    ang = 2 * np.pi * np.arange(sides) / sides
    d = np.column_stack([np.cos(ang), np.sin(ang)])
    h = np.max(z @ d.T, axis=0)
    verts = []
    for k in range(sides):
        j = (k + 1) % sides
        verts.append(np.linalg.solve(np.array([d[k], d[j]]), np.array([h[k], h[j]])))
    return np.array(verts) * scale + centre


@dataclass(frozen=True)
class PerturbationBound:
    """``sup |xi|`` on the box: ``parameter`` (§5.4, N*m; its largest value on the enclosing polygon's vertices
    ``points``, at the box's ``corner``), ``external`` (N*m), and ``sampled``: the largest value on the motion's
    samples themselves (at time ``at``, s), which ``parameter`` exceeds by the polygon's enclosure only."""

    parameter: float
    external: float
    corner: tuple[float, float]
    at: float
    points: tuple[tuple[float, float], ...]
    x2_max: float
    u0_max: float
    sampled: float = 0.0

    @property
    def total(self) -> float:
        """``sup|xi_p| + xi_e`` (N*m)."""
        return self.parameter + self.external


def perturbation_bound(sf: Surface, form: str, gains: Mapping[str, float], t: np.ndarray, ref: np.ndarray,
                       box: Box, Km0: float, tau0: float, external: float, start: float) -> PerturbationBound:
    """The bound over the box's corners and the sliding motion sampled at ``t`` from rest at ``start`` (rad)
    (module docstring)."""
    x1, x2, x3 = ideal_motion(sf, t, ref, form, start=start)
    u0 = pid_part(form, gains, x1, x2, x3, ref, Km0, tau0)
    pts = hull_points(x2, u0)
    sampled, at = 0.0, 0.0
    best, corner = 0.0, (Km0, tau0)
    for Km, tau in corners(box):
        xi = np.abs(perturbation_of_change(x2, u0, Km, tau, Km0, tau0))
        k = int(np.argmax(xi))
        if xi[k] > sampled:
            sampled, at = float(xi[k]), float(t[k])
        on_polygon = float(np.max(np.abs(perturbation_of_change(pts[:, 0], pts[:, 1], Km, tau, Km0, tau0))))
        if on_polygon > best:
            best, corner = on_polygon, (float(Km), float(tau))
    return PerturbationBound(best, float(external), corner, at, tuple(map(tuple, pts.tolist())),
                             float(np.max(np.abs(x2))), float(np.max(np.abs(u0))), sampled)


def relay_set(M: float, bound: PerturbationBound, Km0: float, tau0: float) -> ConditionSet:
    """``M > sup|xi_p| + xi_e`` as affine conditions on the box, two per hull vertex (module docstring)."""
    a0, b0, xe = 1.0 / tau0, Km0 / tau0, bound.external
    conds = []
    for i, (x2, u0) in enumerate(bound.points):
        for sign, side in ((1.0, "−"), (-1.0, "+")):
            conds.append(Condition(
                f"Km (M − ξe) {side} Km ξp > 0 at vertex {i + 1} (x2 = {x2:.4g} rad/s, u0 = {u0:.4g} N·m)",
                lambda p, x2=x2, u0=u0, sign=sign: ((M - xe) * p["Km"]
                                                    - sign * (p["tau"] * (a0 * x2 - b0 * u0) - x2 + p["Km"] * u0)),
                "rad/s",
                "the relay dominates the input-equivalent perturbation of the parameter change and the load"))
    return ConditionSet(title="the relay above the input-equivalent perturbation (notes section 5.4)",
                        parameters=PARAMETERS, conditions=tuple(conds))
