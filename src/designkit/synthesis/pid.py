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
from designkit.synthesis.design import Design
from designkit.synthesis.linear_system import LinearSystem


def _symmetric_functions(poles: Sequence[complex]) -> tuple[float, float, float]:
    p1, p2, p3 = (complex(p) for p in poles)
    s1 = p1 + p2 + p3
    s2 = p1 * p2 + p1 * p3 + p2 * p3
    s3 = p1 * p2 * p3
    return s1.real, s2.real, s3.real


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
        ``{"K1": N*m/rad, "K2": N*m*s/rad, "K3": N*m/(rad*s), "K4": rad (dimension of z^-1 K1/K3...)}``.
    """
    s1, s2, s3 = _symmetric_functions(poles)
    Km, tau = plant.Km, plant.tau
    K1 = tau * s2 / Km
    K2 = -(tau * s1 + 1.0) / Km
    K3 = -tau * s3 / Km
    K4 = 0.0 if zero is None else -(K3 + K1 * zero) / (K3 * zero)
    return {"K1": K1, "K2": K2, "K3": K3, "K4": K4}


def tracking_gains(plant: LinkPlant, poles: Sequence[complex]) -> dict[str, float]:
    """Gains K1..K3 of the PID trajectory tracker whose error dynamics have ``poles`` (1/s)."""
    s1, s2, s3 = _symmetric_functions(poles)
    Km, tau = plant.Km, plant.tau
    return {"K1": tau * s2 / Km, "K2": -tau * s1 / Km, "K3": -tau * s3 / Km}


def servo_closed_loop(gains: dict[str, float], plant: LinkPlant) -> LinearSystem:
    """Closed loop of the servo on ``plant``: states (x1, x2, x3), inputs (xD, xi), outputs (x1, u)."""
    K1, K2, K3, K4 = (gains[k] for k in ("K1", "K2", "K3", "K4"))
    a, b = 1.0 / plant.tau, plant.Km / plant.tau
    # u = -K1 x1 - K2 x2 - K3 x3 + (K1 + K3 K4) xD
    Ku = np.array([[-K1, -K2, -K3]])
    Du = np.array([[K1 + K3 * K4, 0.0]])
    A = np.array([[0.0, 1.0, 0.0], [0.0, -a, 0.0], [1.0, 0.0, 0.0]])
    Bu = np.array([[0.0], [b], [0.0]])
    B = np.array([[0.0, 0.0], [0.0, b], [-1.0, 0.0]])
    C = np.vstack([[1.0, 0.0, 0.0], Ku])
    D = np.vstack([[0.0, 0.0], Du])
    return LinearSystem(
        A=A + Bu @ Ku, B=B + Bu @ Du, C=C, D=D, states=("x1", "x2", "x3"), inputs=("xD", "xi"),
        outputs=("x1", "u"),
    )


def tracking_closed_loop(gains: dict[str, float], plant: LinkPlant, nominal: LinkPlant) -> LinearSystem:
    """Closed loop of the tracker designed for ``nominal`` acting on ``plant``.

    States (x1, x2, x3), inputs (xD, xD', xD'', xi), outputs (x1, u).  With ``plant == nominal``
    the error ``x1 - xD`` obeys ``tau e''' + Km K2 e'' + Km K1 e' + Km K3 e = Km xi'``.
    """
    K1, K2, K3 = (gains[k] for k in ("K1", "K2", "K3"))
    a, b = 1.0 / plant.tau, plant.Km / plant.tau
    # u = (tau0/Km0) xDdd + x2/Km0 - K1 (x1 - xD) - K2 (x2 - xDd) - K3 x3
    Ku = np.array([[-K1, 1.0 / nominal.Km - K2, -K3]])
    Du = np.array([[K1, K2, nominal.tau / nominal.Km, 0.0]])
    A = np.array([[0.0, 1.0, 0.0], [0.0, -a, 0.0], [1.0, 0.0, 0.0]])
    Bu = np.array([[0.0], [b], [0.0]])
    B = np.array([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, b], [-1.0, 0.0, 0.0, 0.0]])
    C = np.vstack([[1.0, 0.0, 0.0], Ku])
    D = np.vstack([[0.0, 0.0, 0.0, 0.0], Du])
    return LinearSystem(
        A=A + Bu @ Ku, B=B + Bu @ Du, C=C, D=D, states=("x1", "x2", "x3"),
        inputs=("xD", "xDd", "xDdd", "xi"), outputs=("x1", "u"),
    )


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


def design_servo(
    plant: LinkPlant, poles: Sequence[complex], zero: float | None, *, notes: tuple[str, ...] = (),
    extra: dict | None = None,
) -> Design:
    """Synthesise the PID position servo; see the module docstring for the derivation."""
    gains = servo_gains(plant, poles, zero)
    notes_out = list(notes)
    if zero is None:
        z = -gains["K3"] / gains["K1"]
        notes_out.append(f"No zero given: K4 = 0, so x1/xD has its zero at -K3/K1 = {z:.6g} 1/s.")
    else:
        z = zero
    return Design(
        kind="pid_servo", plant=plant, gains=gains, poles=tuple(complex(p) for p in poles), zeros=(complex(z),),
        closed_loop=servo_closed_loop(gains, plant), formulas=SERVO_FORMULAS, notes=tuple(notes_out),
        extra=dict(extra or {}),
    )


def design_tracking(
    plant: LinkPlant, poles: Sequence[complex], *, notes: tuple[str, ...] = (), extra: dict | None = None
) -> Design:
    """Synthesise the PID trajectory tracker; see the module docstring for the derivation."""
    gains = tracking_gains(plant, poles)
    return Design(
        kind="pid_tracking", plant=plant, gains=gains, poles=tuple(complex(p) for p in poles), zeros=(),
        closed_loop=tracking_closed_loop(gains, plant, plant), formulas=TRACKING_FORMULAS,
        notes=tuple(notes), extra=dict(extra or {}),
    )
