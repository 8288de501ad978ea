"""The vertex argument of the ``workspace`` check: affine stability conditions at the ends of a ``tau`` range.

A joint loop's Hurwitz conditions are affine in ``(Km, tau)`` for fixed gains
(:mod:`designkit.families.decentralized_pid.workspace_check` derives them); an affine function is
positive on a segment (a box) iff at its ends (corners).  This module evaluates them there, with
the size each value's rounding is judged against.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from designkit.synthesis.design import LinearCondition
from designkit.verification.tolerances import ROUTH_ZERO_REL

__all__ = ["PARAMETERS", "ConditionValue", "VertexVerdict", "box_verdict", "stable_tau_interval"]

PARAMETERS = ("Km", "tau")
"""The link parameters the joint loops' conditions may depend on."""


@dataclass(frozen=True)
class ConditionValue:
    """One affine condition evaluated at one plant ``(Km, tau)``.

    Parameters
    ----------
    label : str
        The condition in words.
    unit : str
        Unit of ``value`` and ``size``.
    value : float
        ``g = c0 + c_Km Km + c_tau tau``.
    size : float
        ``|c0| + |c_Km Km| + |c_tau tau|``, the scale its rounding is judged against.
    """

    label: str
    unit: str
    value: float
    size: float

    @property
    def relative(self) -> float:
        """``value / size`` (1), in ``[-1, 1]``; 0 when every term vanishes."""
        return self.value / self.size if self.size > 0 else 0.0

    @property
    def status(self) -> int:
        """1 holds, -1 fails, 0 zero within rounding (``|g| <= ROUTH_ZERO_REL size``, ``size > 0``).

        A condition whose terms all vanish is exactly ``0 > 0``: it fails.
        """
        if self.size == 0.0:
            return -1
        if abs(self.value) <= ROUTH_ZERO_REL * self.size:
            return 0
        return 1 if self.value > 0 else -1


@dataclass(frozen=True)
class VertexVerdict:
    """The conditions at one corner ``(Km, tau)`` of a parameter box.

    Parameters
    ----------
    Km : float
        (rad/s)/(N*m) or (m/s)/N.
    tau : float
        s.
    conditions : tuple of ConditionValue
    """

    Km: float
    tau: float
    conditions: tuple[ConditionValue, ...]

    @property
    def passed(self) -> bool | None:
        """True every condition holds, False one fails, None one is zero within rounding."""
        status = [c.status for c in self.conditions]
        if any(s < 0 for s in status):
            return False
        return None if any(s == 0 for s in status) else True

    @property
    def margin(self) -> float:
        """Smallest relative condition value (1)."""
        return min(c.relative for c in self.conditions)

    @property
    def worst(self) -> ConditionValue:
        """The condition with the smallest relative value."""
        return min(self.conditions, key=lambda c: c.relative)


def _evaluate(cond: LinearCondition, Km: float, tau: float) -> ConditionValue:
    unknown = set(cond.coefficients) - set(PARAMETERS)
    if unknown:
        raise ValueError(f"condition {cond.label!r} depends on {sorted(unknown)}, not only on Km and tau")
    terms = [float(cond.constant), float(cond.coefficients.get("Km", 0.0)) * Km,
             float(cond.coefficients.get("tau", 0.0)) * tau]
    return ConditionValue(cond.label, cond.unit, math.fsum(terms), math.fsum(abs(t) for t in terms))


def box_verdict(conditions: Sequence[LinearCondition], Km: tuple[float, float],
                tau: tuple[float, float]) -> tuple[VertexVerdict, ...]:
    """The affine conditions at the corners of the box ``Km x tau`` (module docstring: the corners decide).

    Parameters
    ----------
    conditions : sequence of LinearCondition
        Affine in ``Km`` and ``tau`` only.
    Km : (float, float)
        ``(low, high)``, (rad/s)/(N*m); positive.
    tau : (float, float)
        ``(low, high)``, s; positive.

    Returns
    -------
    tuple of VertexVerdict
        One per distinct corner, ordered ``tau`` high before low and ``Km`` low before high (for
        the servo the largest ``tau`` is the worst corner of C3).  Every condition holds on the
        whole box iff it holds at every corner.

    Raises
    ------
    ValueError
        For an empty or non-positive box, or a condition on another parameter.

    Examples
    --------
    >>> from designkit.synthesis.pid import servo_conditions
    >>> conds = servo_conditions({"K1": 50.0, "K2": 6.75, "K3": 100.0})   # tau_crit = 0.5 (1 + 2 * 6.75) = 7.25 s
    >>> [v.passed for v in box_verdict(conds, (2.0, 2.0), (0.5, 7.0))]
    [True, True]
    >>> [v.passed for v in box_verdict(conds, (2.0, 2.0), (0.5, 7.5))]
    [False, True]
    """
    (k_lo, k_hi), (t_lo, t_hi) = (float(v) for v in Km), (float(v) for v in tau)
    if not (0 < k_lo <= k_hi and 0 < t_lo <= t_hi and math.isfinite(k_hi) and math.isfinite(t_hi)):
        raise ValueError(f"need 0 < Km_low <= Km_high and 0 < tau_low <= tau_high, got Km {Km}, tau {tau}")
    corners = dict.fromkeys((k, t) for t in (t_hi, t_lo) for k in (k_lo, k_hi))
    return tuple(VertexVerdict(k, t, tuple(_evaluate(c, k, t) for c in conditions)) for k, t in corners)


def stable_tau_interval(conditions: Sequence[LinearCondition], Km: float) -> tuple[float, float]:
    """The open interval of ``tau`` (s) where every condition holds at ``Km`` (empty: ``low >= high``).

    Each condition ``c0 + c_Km Km + c_tau tau > 0`` is a half-line in ``tau``; for the servo only C3
    depends on ``tau`` and the interval is ``(0, tau_crit)`` with ``tau_crit = K1 (1 + Km K2)/K3``.

    Examples
    --------
    >>> from designkit.synthesis.pid import servo_conditions
    >>> stable_tau_interval(servo_conditions({"K1": 50.0, "K2": 6.75, "K3": 100.0}), 2.0)
    (0.0, 7.25)
    """
    low, high = 0.0, math.inf
    for cond in conditions:
        rest = float(cond.constant) + float(cond.coefficients.get("Km", 0.0)) * Km
        slope = float(cond.coefficients.get("tau", 0.0))
        if slope > 0:
            low = max(low, -rest / slope)
        elif slope < 0:
            high = min(high, rest / -slope)
        elif rest <= 0:
            return (0.0, 0.0)
    return (low, high)


