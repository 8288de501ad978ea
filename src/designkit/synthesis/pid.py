"""PID position servo and PID trajectory tracking for the simplified link (notes section 3.2).

Plant: ``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)``; integral state ``x3' = x1 - xD``.

Position servo, ``u = -K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD``.  Eliminating ``u`` gives

    x1/xD = Km ((K1 + K3 K4) s + K3) / (tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3).

Matching the monic denominator with ``(s - p1)(s - p2)(s - p3) = s^3 - S1 s^2 + S2 s - S3``
(``S1 = p1 + p2 + p3``, ``S2 = p1 p2 + p1 p3 + p2 p3``, ``S3 = p1 p2 p3``) gives

    K1 = tau S2 / Km,   K2 = -(tau S1 + 1) / Km,   K3 = -tau S3 / Km,

and the zero ``z = -K3 / (K1 + K3 K4)`` gives ``K4 = -(K3 + K1 z) / (K3 z)``.  The DC gain is 1
whatever the gains.  The notes print ``K2 = -[(p1 + p2 + p3) tau - 1] / Km``: the sign of the
1 is a misprint (with it the x2 coefficient is off by 2/tau; see the tests).

Trajectory tracking, ``u = (tau/Km) xD'' + x2/Km - K1 dx1 - K2 dx2 - K3 dx3`` with
``dx1 = x1 - xD``, ``dx2 = x2 - xD'``, ``dx3 = int dx1``.  The ``x2/Km`` term cancels the
plant damping, so the error dynamics are ``tau s^3 + Km K2 s^2 + Km K1 s + Km K3`` and

    K1 = tau S2 / Km,   K2 = -tau S1 / Km,   K3 = -tau S3 / Km.

The notes state the tracking gains equal the servo gains; they do not (``K2`` differs by
``1/Km``), which the tests check.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from designkit.models.link import LinkPlant
from designkit.synthesis.design import LinearCondition

GAIN_INFO = {
    "K1": ("N*m/rad", "proportional"),
    "K2": ("N*m*s/rad", "derivative (rate feedback)"),
    "K3": ("N*m/(rad*s)", "integral"),
    "K4": ("s", "reference feedforward (places the zero)"),
}
"""Gain name -> (unit, role) of the PID servo's gains; the tracker's ``K1``..``K3`` have the same units and roles."""


def _symmetric_functions(poles: Sequence[complex]) -> tuple[float, float, float]:
    p1, p2, p3 = (complex(p) for p in poles)
    s1 = p1 + p2 + p3
    s2 = p1 * p2 + p1 * p3 + p2 * p3
    s3 = p1 * p2 * p3
    return s1.real, s2.real, s3.real


def servo_pid_gains(Km: float, tau: float, poles: Sequence[complex]) -> tuple[float, float, float]:
    """``(K1, K2, K3)`` of the PID position servo placing the three continuous ``poles`` (1/s) on the
    link ``(Km, tau)`` (module docstring), for any nonzero ``Km``.

    Unlike :func:`servo_gains` this takes bare numbers, not a validated :class:`LinkPlant`: an
    adaptive law (the self-tuning family) calls it on a running estimate whose ``Km`` may be
    negative early in a run.

    Parameters
    ----------
    Km : float
        Link gain, (rad/s)/(N*m); nonzero.
    tau : float
        Link time constant, s.
    poles : sequence of 3 complex
        Closed-loop poles; complex ones in conjugate pairs.

    Returns
    -------
    tuple of float
        ``K1`` (N*m/rad), ``K2`` (N*m*s/rad), ``K3`` (N*m/(rad*s)).
    """
    s1, s2, s3 = _symmetric_functions(poles)
    return tau * s2 / Km, -(tau * s1 + 1.0) / Km, -tau * s3 / Km


def servo_gains(plant: LinkPlant, poles: Sequence[complex], zero: float | None) -> dict[str, float]:
    """Gains K1..K4 of the PID position servo placing ``poles`` (1/s) and ``zero`` (1/s).

    Parameters
    ----------
    plant : LinkPlant
        Nominal link (Km in (rad/s)/(N*m), tau in s).
    poles : sequence of 3 complex
        Closed-loop poles; complex ones in conjugate pairs.
    zero : float or None
        Zero of ``x1/xD``; ``None`` means ``K4 = 0`` (the zero then falls at ``-K3/K1``).

    Returns
    -------
    dict
        ``K1`` (N*m/rad), ``K2`` (N*m*s/rad), ``K3`` (N*m/(rad*s)), ``K4`` (s).
    """
    K1, K2, K3 = servo_pid_gains(plant.Km, plant.tau, poles)
    K4 = 0.0 if zero is None else -(K3 + K1 * zero) / (K3 * zero)
    return {"K1": K1, "K2": K2, "K3": K3, "K4": K4}


def tracking_gains(plant: LinkPlant, poles: Sequence[complex]) -> dict[str, float]:
    """Gains K1..K3 of the PID trajectory tracker whose error dynamics have ``poles`` (1/s)."""
    s1, s2, s3 = _symmetric_functions(poles)
    Km, tau = plant.Km, plant.tau
    return {"K1": tau * s2 / Km, "K2": -tau * s1 / Km, "K3": -tau * s3 / Km}


def servo_characteristic(gains: dict[str, float], Km: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, ...]:
    """Coefficients (highest power first) of ``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3``.

    ``Km`` and ``tau`` may be arrays (broadcast), for robustness sweeps.
    """
    Km, tau = np.asarray(Km, float), np.asarray(tau, float)
    return (tau, 1.0 + Km * gains["K2"], Km * gains["K1"], Km * gains["K3"])


def tracking_characteristic(
    gains: dict[str, float], Km: np.ndarray, tau: np.ndarray, nominal: LinkPlant
) -> tuple[np.ndarray, ...]:
    """Coefficients of ``tau s^3 + (1 - Km/Km0 + Km K2) s^2 + Km K1 s + Km K3`` (plant Km, tau;
    controller designed for ``nominal`` Km0)."""
    Km, tau = np.asarray(Km, float), np.asarray(tau, float)
    return (tau, 1.0 - Km / nominal.Km + Km * gains["K2"], Km * gains["K1"], Km * gains["K3"])


SERVO_FORMULAS = (
    "u = -K1 (x1 - xD) - K2 x2 - K3 ∫(x1 - xD) dt + K3 K4 xD",
    "x1/xD = Km((K1 + K3 K4) s + K3) / (τ s³ + (1 + Km K2) s² + Km K1 s + Km K3)",
    "K1 = τ S2/Km,  K2 = -(τ S1 + 1)/Km,  K3 = -τ S3/Km,  K4 = -(K3 + K1 z)/(K3 z)",
    "S1 = p1+p2+p3,  S2 = p1p2+p1p3+p2p3,  S3 = p1p2p3",
)
TRACKING_FORMULAS = (
    "u = (τ/Km) xD'' + x2/Km - K1 Δx1 - K2 Δx2 - K3 ∫Δx1 dt",
    "Δx1/ξ = (Km/τ) s / ((s-p1)(s-p2)(s-p3))",
    "K1 = τ S2/Km,  K2 = -τ S1/Km,  K3 = -τ S3/Km",
    "S1 = p1+p2+p3,  S2 = p1p2+p1p3+p2p3,  S3 = p1p2p3",
)


def servo_conditions(gains: dict[str, float]) -> tuple[LinearCondition, ...]:
    """The servo's Hurwitz conditions, affine in ``(Km, tau)`` for fixed gains.

    With ``Km, tau > 0`` the cubic ``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3`` is Hurwitz iff
    ``1 + Km K2 > 0``, ``K3 > 0`` and ``(1 + Km K2) Km K1 > tau Km K3``, i.e.
    ``K1 + K1 K2 Km - K3 tau > 0`` (``a2 > 0`` follows).  Each is affine in the plant parameters,
    so its minimum over a box (or any polytope) of ``(Km, tau)`` is a linear program.
    """
    K1, K2, K3 = (float(gains[k]) for k in ("K1", "K2", "K3"))
    return (
        LinearCondition("1 + Km K2 > 0", 1.0, {"Km": K2}, "1"),
        LinearCondition("K3 > 0", K3, {}, "N*m/(rad*s)"),
        LinearCondition("K1 (1 + Km K2) - tau K3 > 0", K1, {"Km": K1 * K2, "tau": -K3}, "N*m/rad"),
    )


def tracking_conditions(gains: dict[str, float], nominal: LinkPlant) -> tuple[LinearCondition, ...]:
    """The tracker's Hurwitz conditions on a plant ``(Km, tau)``, designed for ``nominal`` ``Km0``.

    ``tau s^3 + (1 + Km (K2 - 1/Km0)) s^2 + Km K1 s + Km K3``: ``1 + Km (K2 - 1/Km0) > 0``,
    ``K3 > 0`` and ``K1 (1 + Km (K2 - 1/Km0)) - tau K3 > 0``, each affine in ``(Km, tau)``.
    """
    K1, K2, K3 = (float(gains[k]) for k in ("K1", "K2", "K3"))
    c = K2 - 1.0 / float(nominal.Km)
    return (
        LinearCondition("1 + Km (K2 - 1/Km0) > 0", 1.0, {"Km": c}, "1"),
        LinearCondition("K3 > 0", K3, {}, "N*m/(rad*s)"),
        LinearCondition("K1 (1 + Km (K2 - 1/Km0)) - tau K3 > 0", K1, {"Km": K1 * c, "tau": -K3}, "N*m/rad"),
    )
