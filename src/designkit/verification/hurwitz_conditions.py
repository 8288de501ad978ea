"""Routh-Hurwitz conditions of a design: the cubic coefficient conditions and their gain form.

For a cubic the Routh array (:mod:`designkit.verification.routh`) reduces to the classical
conditions ``a0 > 0, a1 > 0, a3 > 0, a1 a2 > a0 a3``.  For the PID link families, whose
characteristic polynomials are ``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3`` (servo) and
``tau s^3 + Km K2 s^2 + Km K1 s + Km K3`` (tracker on its nominal plant), each condition is
solved for the gain entering it, using slopes read off the family's ``characteristic`` (no
formula is retyped here); for the servo this reproduces the notes' ``K3 > 0``, ``K2 > -1/Km``,
``K1 > tau K3/(1 + Km K2)`` and for the tracker ``K3 > 0``, ``K2 > 0``, ``K1 > tau K3/(Km K2)``.
:func:`routh_hurwitz_design` is the ``"routh_hurwitz"`` check of a design: the verdict of the
generic array, with these conditions, their values, thresholds and margins as certificate.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.verification.check import Check
from designkit.verification.routh import routh_hurwitz

GAIN_UNITS = {"K1": "N*m/rad", "K2": "N*m*s/rad", "K3": "N*m/(rad*s)", "K4": "1"}
"""Units of the PID gains of the link families (see :mod:`designkit.synthesis.pid`)."""

CUBIC_GAINS = {
    "pid_servo": {"a1": "K2", "a2": "K1", "a3": "K3"},
    "pid_tracking": {"a1": "K2", "a2": "K1", "a3": "K3"},
}
"""For each family, the gain that enters each coefficient of ``a0 s^3 + a1 s^2 + a2 s + a3``."""


@dataclass(frozen=True)
class Condition:
    """One stability inequality ``value > threshold`` with its margin ``value - threshold``.

    Parameters
    ----------
    condition : str
        The inequality in words, e.g. ``"K2 > -1/Km"``.
    value, threshold : float or None
        Both sides (in ``unit``); None when the threshold is undefined (a prerequisite fails).
    margin : float or None
        ``value - threshold`` (in ``unit``), positive when the inequality holds.
    unit : str
    """

    condition: str
    value: float | None
    threshold: float | None
    margin: float | None
    unit: str

    def to_dict(self) -> dict[str, Any]:
        """JSON form for the certificate."""
        return dataclasses.asdict(self)


def cubic_conditions(a0: float, a1: float, a2: float, a3: float) -> tuple[Condition, ...]:
    """Hurwitz conditions of ``a0 s^3 + a1 s^2 + a2 s + a3`` (``a0 > 0`` assumed after a sign flip).

    ``a0 > 0, a1 > 0, a3 > 0, a1 a2 - a0 a3 > 0``; together they imply ``a2 > 0``.
    """
    if a0 < 0:
        a0, a1, a2, a3 = -a0, -a1, -a2, -a3
    return (
        Condition("a0 > 0", a0, 0.0, a0, "coefficient"),
        Condition("a1 > 0", a1, 0.0, a1, "coefficient"),
        Condition("a3 > 0", a3, 0.0, a3, "coefficient"),
        Condition("a1 a2 > a0 a3", a1 * a2, a0 * a3, a1 * a2 - a0 * a3, "coefficient^2"),
    )


def _coefficients(design: Any, family: Any, Km: float, tau: float, gains: dict[str, float] | None = None):
    d = design if gains is None else dataclasses.replace(design, gains=gains)
    return tuple(float(np.asarray(c)) for c in family.characteristic(d, np.asarray(Km), np.asarray(tau)))


def _slope(design: Any, family: Any, Km: float, tau: float, gain: str, index: int) -> float:
    """``d a_index / d gain`` by a central difference (exact for coefficients affine in the gain)."""
    g = dict(design.gains)
    h = max(1.0, abs(g[gain]))
    up = _coefficients(design, family, Km, tau, {**g, gain: g[gain] + h})[index]
    down = _coefficients(design, family, Km, tau, {**g, gain: g[gain] - h})[index]
    return (up - down) / (2.0 * h)


def gain_conditions(design: Any, family: Any, Km: float, tau: float) -> tuple[Condition, ...]:
    """The cubic conditions solved for the gains entering ``a3``, ``a1`` and ``a2`` (in that order).

    Each coefficient of ``family.characteristic`` is affine in one gain (table
    :data:`CUBIC_GAINS`); its slope is measured on the characteristic itself, so the thresholds
    follow the family's own formula.  With ``a0 > 0`` and positive slopes:

    - ``a3 > 0``          <=>  ``K3 > K3 - a3/s3``
    - ``a1 > 0``          <=>  ``K2 > K2 - a1/s1``
    - ``a1 a2 > a0 a3``   <=>  ``K1 > K1 - (a2 - a0 a3/a1)/s2``  (defined when ``a1 > 0``)

    Returns an empty tuple for a family not in :data:`CUBIC_GAINS` or a non-cubic characteristic.
    """
    names = CUBIC_GAINS.get(design.kind)
    a = _coefficients(design, family, Km, tau)
    if names is None or len(a) != 4:
        return ()
    a0, a1, a2, a3 = a
    g = dict(design.gains)
    out = []
    pretty = {
        "pid_servo": {"a3": "K3 > 0", "a1": "K2 > -1/Km", "a2": "K1 > tau K3/(1 + Km K2)"},
        "pid_tracking": {"a3": "K3 > 0", "a1": "K2 > (Km/Km0 - 1)/Km", "a2": "K1 > tau K3/(1 - Km/Km0 + Km K2)"},
    }.get(design.kind, {})
    for coef in ("a3", "a1", "a2"):
        gain = names[coef]
        idx = int(coef[1])
        s = _slope(design, family, Km, tau, gain, idx)
        excess = {"a3": a3, "a1": a1, "a2": (a2 - a0 * a3 / a1) if a1 > 0 else None}[coef]
        label = pretty.get(coef, f"{coef} condition on {gain}")
        if excess is None or s == 0:
            out.append(Condition(label + " (undefined: needs a1 > 0)", g[gain], None, None, GAIN_UNITS[gain]))
            continue
        threshold = g[gain] - excess / s
        margin = (g[gain] - threshold) if s > 0 else (threshold - g[gain])
        if s < 0:
            label = label.replace(">", "<")
        out.append(Condition(label, g[gain], threshold, margin, GAIN_UNITS[gain]))
    return tuple(out)


def routh_hurwitz_design(design: Any, family: Any, plant: Any = None) -> Check:
    """Check ``"routh_hurwitz"`` of a design's closed loop on ``plant`` (default: its nominal plant).

    The verdict comes from the generic Routh array of ``family.characteristic`` at the plant;
    the certificate adds the cubic coefficient conditions and their gain form (notes 3.2),
    each with value, threshold and margin.  If the closed-form conditions and the array
    disagree (only possible within rounding of the boundary) the check is undecided.

    Parameters
    ----------
    design : Design
    family : ControllerFamily
    plant : LinkPlant, optional
        Plant (Km in (rad/s)/(N*m), tau in s) on which the gains act.
    """
    plant = design.plant if plant is None else plant
    Km, tau = float(plant.Km), float(plant.tau)
    coeffs = _coefficients(design, family, Km, tau)
    labels = {
        "pid_servo": ("tau", "1 + Km K2", "Km K1", "Km K3"),
        "pid_tracking": ("tau", "1 - Km/Km0 + Km K2", "Km K1", "Km K3"),
    }.get(design.kind)
    base = routh_hurwitz(coeffs, labels)
    cert = dict(base.certificate)
    cert["plant"] = {"Km": Km, "tau": tau}
    passed = base.passed
    detail = base.detail
    if len(coeffs) == 4:
        cubic = cubic_conditions(*coeffs)
        gains = gain_conditions(design, family, Km, tau)
        cert["coefficient_conditions"] = [c.to_dict() for c in cubic]
        cert["conditions"] = [c.to_dict() for c in gains]
        closed_form = all(c.margin is not None and c.margin > 0 for c in cubic)
        if passed is not None and closed_form != passed:
            passed = None
            detail = "Routh array and cubic conditions disagree (within rounding of the boundary): undecided"
        failing = [c.condition for c in gains if c.margin is None or c.margin <= 0]
        if failing and passed is False:
            detail += "; failing: " + ", ".join(failing)
    return dataclasses.replace(base, passed=passed, detail=detail, certificate=cert)
