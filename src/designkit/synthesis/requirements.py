"""Dominant closed-loop poles from overshoot and settling-time requirements."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from designkit.errors import SpecError


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
    an overshoot below 1e-9 % gives critical damping (``zeta = 1``).
    """
    if overshoot_percent < 1e-9:
        return 1.0
    log_mp = math.log(min(overshoot_percent, 99.999) / 100.0)
    return -log_mp / math.sqrt(math.pi**2 + log_mp**2)


def _step_error(zeta: float, x: float) -> float:
    """``y(x) - 1`` of the unit-DC-gain second-order step response at normalised time ``x = wn t``."""
    if zeta >= 1.0:
        return -(1.0 + x) * math.exp(-x)
    wd = math.sqrt(1.0 - zeta**2)
    return -math.exp(-zeta * x) * (math.cos(wd * x) + zeta / wd * math.sin(wd * x))


def normalised_settling_time(zeta: float, band: float = 0.02) -> float:
    """Exact settling time ``wn * Ts`` (dimensionless) of ``wn^2/(s^2 + 2 zeta wn s + wn^2)``.

    The last instant at which ``|y - 1| = band``: bracketed from the exponential envelope
    ``exp(-zeta x)/sqrt(1 - zeta^2)`` (after which the error stays inside the band), located on a
    fine grid and refined by Brent's method.  Exact, unlike the classic ``4/zeta``.
    """
    zeta = min(max(zeta, 1e-3), 1.0)
    sq = math.sqrt(max(1.0 - zeta**2, 1e-300))
    x_end = max(-math.log(band * sq) / zeta, 1.0) if zeta < 1.0 else 50.0 / zeta
    grid = [x_end * k / 20000 for k in range(20001)]
    outside = [abs(_step_error(zeta, x)) > band for x in grid]
    last = max((k for k, o in enumerate(outside) if o), default=None)
    if last is None or last == len(grid) - 1:
        return grid[-1] if last is not None else 0.0

    def f(x: float) -> float:
        return abs(_step_error(zeta, x)) - band

    from scipy.optimize import brentq

    return brentq(f, grid[last], grid[last + 1], xtol=1e-14)


def natural_frequency_from_settling(zeta: float, settling_time: float, band: float = 0.02) -> float:
    """Natural frequency (rad/s) at which the second-order step response settles into ``band``
    exactly at ``settling_time`` (s); see :func:`normalised_settling_time`."""
    return normalised_settling_time(zeta, band) / settling_time


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


def poles_from_spec(controller: Any, requirements: Any) -> tuple[tuple[complex, ...], tuple[str, ...],
                                                                 dict[str, float]]:
    """The three poles of a pole-placed controller section, given or derived from requirements.

    Parameters
    ----------
    controller : PoleRequirementsController
        ``poles`` (used as given when present), ``design_margin``, ``third_pole_factor``.
    requirements : Requirements or None
        ``overshoot`` (%), ``settling_time`` (s) and ``settling_band`` when the poles are derived.

    Returns
    -------
    poles, notes, extra
        The poles (1/s), a note saying how they were derived, and ``{"zeta", "wn"}``.

    Raises
    ------
    SpecError
        ``controller.poles`` when neither poles nor the two requirements are given.
    """
    if controller.poles is not None:
        return tuple(complex(p) for p in controller.poles), (), {}
    if requirements is None or requirements.overshoot is None or requirements.settling_time is None:
        raise SpecError("controller.poles", "missing; give three poles, or requirements.overshoot and "
                        "requirements.settling_time to derive them")
    tighten = 1.0 - controller.design_margin
    overshoot, settling = tighten * requirements.overshoot, tighten * requirements.settling_time
    dom = dominant_poles(overshoot, settling, third_pole_factor=controller.third_pole_factor,
                         band=requirements.settling_band)
    note = (
        f"Poles derived from requirements tightened by the design margin {controller.design_margin:g}: overshoot "
        f"{overshoot:g} % -> zeta = {dom.zeta:.4f}; settling time {settling:g} s "
        f"({100 * requirements.settling_band:g} % band, exact 2nd-order) -> wn = {dom.wn:.4f} rad/s; "
        f"third pole at {controller.third_pole_factor:g} x Re(p1)."
    )
    return dom.poles, (note,), {"zeta": dom.zeta, "wn": dom.wn}


def poles_or_requirements(spec: Any) -> None:
    """Spec rule of the pole-placed families: ``controller.poles``, or the requirements they are derived from.

    Raises
    ------
    ValueError
        ``"controller.poles: missing; ..."`` (the loader turns it into a SpecError with that key path).
    """
    req = spec.requirements
    if spec.controller.poles is None and (req is None or req.overshoot is None or req.settling_time is None):
        raise ValueError("controller.poles: missing; give the closed-loop poles, or requirements.overshoot and "
                         "requirements.settling_time to derive them")
