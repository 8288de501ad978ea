"""Hand-derived closed loops of the link PID families: test oracles, independent of the CasADi laws.

The library obtains a design's closed loop by linearizing the plant composed with the family's
CasADi law (:mod:`designkit.synthesis.closed_loop`).  These matrices are written down from the
notes' equations instead (plant ``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)``, integral
``x3' = x1 - xD``), so that a test comparing the two checks the law, the composition and the
linearization at once.  Inputs ``(xD, xD', xD'', xi)``, outputs ``(x1, u)`` as the library's.
"""

from __future__ import annotations

import numpy as np

from designkit.models.linear_system import LinearSystem
from designkit.models.link import LinkPlant

INPUTS = ("xD", "xDd", "xDdd", "xi")


def _loop(plant: LinkPlant, Ku: np.ndarray, Du: np.ndarray) -> LinearSystem:
    a, b = 1.0 / plant.tau, plant.Km / plant.tau
    A = np.array([[0.0, 1.0, 0.0], [0.0, -a, 0.0], [1.0, 0.0, 0.0]])
    Bu = np.array([[0.0], [b], [0.0]])
    B = np.array([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, b], [-1.0, 0.0, 0.0, 0.0]])
    C = np.vstack([[1.0, 0.0, 0.0], Ku])
    D = np.vstack([np.zeros((1, 4)), Du])
    return LinearSystem(A=A + Bu @ Ku, B=B + Bu @ Du, C=C, D=D, states=("x1", "x2", "x3"), inputs=INPUTS,
                        outputs=("x1", "u"))


def servo_closed_loop(gains: dict, plant: LinkPlant) -> LinearSystem:
    """``u = -K1 x1 - K2 x2 - K3 x3 + (K1 + K3 K4) xD`` on ``plant``."""
    K1, K2, K3, K4 = (float(gains[k]) for k in ("K1", "K2", "K3", "K4"))
    return _loop(plant, np.array([[-K1, -K2, -K3]]), np.array([[K1 + K3 * K4, 0.0, 0.0, 0.0]]))


def tracking_closed_loop(gains: dict, plant: LinkPlant, nominal: LinkPlant) -> LinearSystem:
    """``u = (tau0/Km0) xD'' + x2/Km0 - K1 (x1 - xD) - K2 (x2 - xD') - K3 x3`` on ``plant``."""
    K1, K2, K3 = (float(gains[k]) for k in ("K1", "K2", "K3"))
    return _loop(plant, np.array([[-K1, 1.0 / nominal.Km - K2, -K3]]),
                 np.array([[K1, K2, nominal.tau / nominal.Km, 0.0]]))
