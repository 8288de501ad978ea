"""Routh-Hurwitz conditions of a design: the cubic coefficient conditions and their gain form.

For a cubic the Routh array (:mod:`designkit.verification.routh`) reduces to the classical
conditions ``a0 > 0, a1 > 0, a3 > 0, a1 a2 > a0 a3``.  A design that exposes its characteristic
polynomial in closed form (:class:`~designkit.synthesis.design.Characteristic`, e.g. the PID
link families' ``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3``) also says which gain each
coefficient is affine in; each condition is then solved for that gain, using slopes read off the
characteristic itself (no formula is retyped here).  For the servo this reproduces the notes'
``K3 > 0``, ``K2 > -1/Km``, ``K1 > tau K3/(1 + Km K2)`` and for the tracker ``K3 > 0``,
``K2 > 0``, ``K1 > tau K3/(Km K2)``.  :func:`routh_hurwitz_design` is the ``"routh_hurwitz"``
check of a design: the verdict of the generic array, with these conditions, their values,
thresholds and margins as certificate.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.verification.check import Check
from designkit.verification.routh import routh_hurwitz


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


def _theta(design: Any, plant: Any) -> dict[str, float]:
    return {name: float(plant.parameter(name).value) for name in design.characteristic.parameters}


def _coefficients(design: Any, plant: Any, gains: Any = None) -> tuple[float, ...]:
    ch = design.characteristic
    g = design.gains if gains is None else gains
    return tuple(float(np.asarray(c)) for c in ch.coefficients(g, **_theta(design, plant)))


def _slope(design: Any, plant: Any, gain: str, index: int) -> float:
    """``d a_index / d gain`` by a central difference (exact for coefficients affine in the gain)."""
    g = dict(design.gains)
    h = max(1.0, abs(float(g[gain])))
    up = _coefficients(design, plant, {**g, gain: float(g[gain]) + h})[index]
    down = _coefficients(design, plant, {**g, gain: float(g[gain]) - h})[index]
    return (up - down) / (2.0 * h)


def gain_conditions(design: Any, plant: Any = None) -> tuple[Condition, ...]:
    """The cubic conditions solved for the gains entering ``a3``, ``a1`` and ``a2`` (in that order).

    Each coefficient of the design's characteristic is affine in one gain (its
    ``gain_labels``); the slope is measured on the characteristic itself, so the thresholds
    follow the family's own formula.  With ``a0 > 0`` and positive slopes:

    - ``a3 > 0``          <=>  ``K3 > K3 - a3/s3``
    - ``a1 > 0``          <=>  ``K2 > K2 - a1/s1``
    - ``a1 a2 > a0 a3``   <=>  ``K1 > K1 - (a2 - a0 a3/a1)/s2``  (defined when ``a1 > 0``)

    Returns an empty tuple for a design without a cubic characteristic.
    """
    plant = design.plant if plant is None else plant
    ch = design.characteristic
    if ch is None or not ch.gain_labels:
        return ()
    a = _coefficients(design, plant)
    if len(a) != 4:
        return ()
    a0, a1, a2, a3 = a
    g = dict(design.gains)
    out = []
    for coef in ("a3", "a1", "a2"):
        gain, label = ch.gain_labels[coef]
        idx = int(coef[1])
        s = _slope(design, plant, gain, idx)
        excess = {"a3": a3, "a1": a1, "a2": (a2 - a0 * a3 / a1) if a1 > 0 else None}[coef]
        unit = design.gains.unit(gain)
        value = float(g[gain])
        if excess is None or s == 0:
            out.append(Condition(label + " (undefined: needs a1 > 0)", value, None, None, unit))
            continue
        threshold = value - excess / s
        margin = (value - threshold) if s > 0 else (threshold - value)
        if s < 0:
            label = label.replace(">", "<")
        out.append(Condition(label, value, threshold, margin, unit))
    return tuple(out)


def routh_hurwitz_design(design: Any, plant: Any = None) -> Check:
    """Check ``"routh_hurwitz"`` of a design's closed loop on ``plant`` (default: its nominal plant).

    The verdict comes from the generic Routh array of the design's characteristic at the plant;
    the certificate adds the cubic coefficient conditions and their gain form (notes 3.2),
    each with value, threshold and margin.  If the closed-form conditions and the array
    disagree (only possible within rounding of the boundary) the check is undecided.

    Parameters
    ----------
    design : Design
        With a ``characteristic``.
    plant : Plant, optional
        Plant on which the gains act (its parameters named by the characteristic).
    """
    plant = design.plant if plant is None else plant
    coeffs = _coefficients(design, plant)
    base = routh_hurwitz(coeffs, design.characteristic.labels or None)
    cert = dict(base.certificate)
    cert["plant"] = _theta(design, plant)
    passed = base.passed
    detail = base.detail
    if len(coeffs) == 4:
        cubic = cubic_conditions(*coeffs)
        gains = gain_conditions(design, plant)
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
