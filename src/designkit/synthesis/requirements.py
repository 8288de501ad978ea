"""Dominant closed-loop poles from overshoot and settling-time requirements."""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq


@dataclass(frozen=True)
class DominantPoles:
    """Poles of a dominant second-order pair plus a faster real pole.

    Parameters
    ----------
    zeta : float
        Damping ratio of the dominant pair (dimensionless).
    wn : float
        Natural frequency of the dominant pair (rad/s).
    poles : tuple of complex
        ``(p1, p2, p3)`` in 1/s; ``p3 = factor * Re(p1)``.
    """

    zeta: float
    wn: float
    poles: tuple[complex, complex, complex]


def damping_from_overshoot(overshoot_percent: float) -> float:
    """Damping ratio whose second-order step response overshoots by ``overshoot_percent`` (%).

    ``Mp = exp(-pi zeta / sqrt(1 - zeta^2))``, so ``zeta = -ln Mp / sqrt(pi^2 + ln^2 Mp)``;
    0 % gives critical damping (``zeta = 1``).
    """
    if overshoot_percent <= 0.0:
        return 1.0
    log_mp = math.log(min(overshoot_percent, 99.999) / 100.0)
    return -log_mp / math.sqrt(math.pi**2 + log_mp**2)


def natural_frequency_from_settling(zeta: float, settling_time: float, band: float = 0.02) -> float:
    """Natural frequency (rad/s) at which a second-order step response stays within ``band``
    after ``settling_time`` (s).

    For ``zeta < 1`` the exponential envelope ``exp(-zeta wn t)/sqrt(1 - zeta^2) <= band`` is used,
    an upper bound of the true settling time (the classic ``4/(zeta wn)`` ignores the
    ``sqrt(1 - zeta^2)`` factor and can be optimistic).  For ``zeta = 1`` the exact condition
    ``(1 + wn t) exp(-wn t) = band`` is solved.
    """
    if zeta >= 1.0:
        x = brentq(lambda x: (1.0 + x) * math.exp(-x) - band, 1e-9, 100.0)
        return x / settling_time
    return -math.log(band * math.sqrt(1.0 - zeta**2)) / (zeta * settling_time)


def dominant_poles(
    overshoot_percent: float, settling_time: float, *, third_pole_factor: float = 5.0, band: float = 0.02
) -> DominantPoles:
    """Three closed-loop poles meeting overshoot (%) and settling time (s) with a dominant pair.

    The third, real pole is placed ``third_pole_factor`` times further left than the real part
    of the dominant pair (default 5, a common rule so that it barely affects the response).
    """
    zeta = damping_from_overshoot(overshoot_percent)
    wn = natural_frequency_from_settling(zeta, settling_time, band)
    sigma = zeta * wn
    wd = wn * math.sqrt(max(0.0, 1.0 - zeta**2))
    p1, p2 = complex(-sigma, wd), complex(-sigma, -wd)
    p3 = complex(-third_pole_factor * sigma, 0.0)
    return DominantPoles(zeta=zeta, wn=wn, poles=(p1, p2, p3))
