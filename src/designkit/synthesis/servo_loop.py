"""The one-link PID position servo as a design: its gains, characteristic polynomial, law and closed loop.

Plant: the simplified link ``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)``.  Law, with the integral
``x3' = x1 - xD``::

    u = -K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD

Gains from three closed-loop poles and the zero of ``x1/xD`` by matching the characteristic polynomial
(:mod:`designkit.synthesis.pid`); K1 N*m/rad, K2 N*m*s/rad, K3 N*m/(rad*s), K4 s.  A servo family places one such
loop; a decentralized controller places one per joint, on that joint's simplified link.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from designkit.synthesis import pid
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Characteristic, Design, Gain, Gains
from designkit.synthesis.law import Law, integral_law

__all__ = ["CHARACTERISTIC_LABELS", "servo_characteristic", "servo_design", "servo_gains", "servo_law"]

CHARACTERISTIC_LABELS = ("tau", "1 + Km K2", "Km K1", "Km K3")
"""The coefficients of the servo's characteristic polynomial in words, highest power first."""


def servo_gains(plant: Any, poles: Sequence[complex], zero: float | None) -> Gains:
    """The servo's named gains with units on the link ``plant`` (:func:`designkit.synthesis.pid.servo_gains`).

    Parameters
    ----------
    plant : LinkPlant
        Nominal link (``Km`` in (rad/s)/(N*m), ``tau`` in s).
    poles : sequence of 3 complex
        Closed-loop poles (1/s); complex ones in conjugate pairs.
    zero : float or None
        Zero of ``x1/xD`` (1/s); ``None`` means ``K4 = 0``.

    Returns
    -------
    Gains
        ``K1`` (N*m/rad), ``K2`` (N*m*s/rad), ``K3`` (N*m/(rad*s)), ``K4`` (s).
    """
    values = pid.servo_gains(plant, poles, zero)
    return Gains.of(Gain(k, v, *pid.GAIN_INFO[k]) for k, v in values.items())


def servo_characteristic() -> Characteristic:
    """``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3`` as a function of ``(Km, tau)`` (Km in (rad/s)/(N*m), tau in
    s), with its Hurwitz conditions affine in them (:func:`designkit.synthesis.pid.servo_conditions`)."""
    return Characteristic(
        parameters=("Km", "tau"),
        coefficients=lambda g, Km, tau: pid.servo_characteristic(dict(g), Km, tau),
        labels=CHARACTERISTIC_LABELS,
        gain_labels={"a1": ("K2", "K2 > -1/Km"), "a2": ("K1", "K1 > tau K3/(1 + Km K2)"), "a3": ("K3", "K3 > 0")},
        linear_conditions=lambda g: pid.servo_conditions(dict(g)),
    )


def servo_law(design: Design, anti_windup: Any = None) -> Law:
    """``u = -K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD``, ``x3' = x1 - xD`` (N*m), of the design's kind.

    Parameters
    ----------
    design : Design
        Its gains ``K1``..``K4`` and its plant (the link's velocity state is read).
    anti_windup : AntiWindup or None
        The spec's ``simulation.anti_windup`` (the integral's clamp), or none.
    """
    K1, K2, K3, K4 = (float(design.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    v = design.plant.velocities[0]
    return integral_law(
        design.kind, design.plant, [K3], anti_windup,
        lambda y, xc, r, e: -K1 * e[0] - K2 * y[v] - K3 * xc[0] + K3 * K4 * r[0],
        {"gains": design.gains.to_json()},
    )


def servo_design(plant: Any, poles: Sequence[complex], zero: float | None = None, *, kind: str,
                 notes: tuple[str, ...] = (), extra: dict | None = None) -> Design:
    """The PID servo of the link ``plant`` placing ``poles`` (1/s) and ``zero`` (1/s), with its closed loop.

    Parameters
    ----------
    plant : LinkPlant
        Nominal link (``Km`` in (rad/s)/(N*m), ``tau`` in s).
    poles : sequence of 3 complex
        Closed-loop poles (1/s); complex ones in conjugate pairs.
    zero : float or None
        Zero of ``x1/xD`` (1/s); ``None``: ``K4 = 0``, the zero falls at ``-K3/K1`` (said in a note).
    kind : str
        The design's (and its law's) controller kind.
    notes : tuple of str
        Notes to carry; the zero's is appended.
    extra : dict or None
        Entries the generic layers read by name to carry (:attr:`Design.extra`: the requirements' ``zeta`` and
        ``wn``).

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> d = servo_design(LinkPlant(Km=2.0, tau=0.5), [-4, -5, -20], -3.0, kind="servo")
    >>> [round(float(d.gains[k]), 6) for k in ("K1", "K2", "K3", "K4")]
    [50.0, 6.75, 100.0, -0.166667]
    >>> sorted(round(float(p.real), 6) for p in d.closed_loop.poles)
    [-20.0, -5.0, -4.0]
    """
    g = servo_gains(plant, poles, zero)
    notes_out = list(notes)
    if zero is None:
        z = -float(g["K3"]) / float(g["K1"])
        notes_out.append(f"No zero given: K4 = 0, so x1/xD has its zero at -K3/K1 = {z:.6g} 1/s.")
    else:
        z = zero
    d = Design(
        kind=kind, plant=plant, gains=g, poles=tuple(poles), zeros=(complex(z),), reference="step",
        characteristic=servo_characteristic(), formulas=pid.SERVO_FORMULAS, notes=tuple(notes_out),
        extra=extra or {},
    )
    return with_closed_loop(d, servo_law(d), [0.0, 0.0, 0.0], field="controller.poles")
