"""Why no tuning meets every requirement: the conflicting pair, and the actuator's minimum-time bound.

**The conflicting pair.**  At the best compromise the requirement with the smallest margin is the *active* one
(``a``).  Among every certified candidate run, the one where ``a`` had its best margin is where pushing ``a`` led;
the requirement with the smallest margin *there* is the one ``a`` trades against (``b``).  For each requirement the
result gives the best margin seen alone (over every certified candidate: a lower bound on what the requirement
alone could reach) and its margin at the compromise.

**The minimum-time bound** (a link ``x1' = x2``, ``x2' = -x2/tau + (Km/tau) u`` with ``|u| <= U``, ``U`` the
smaller of ``requirements.max_control`` and a saturation's limit).  From rest, full command ``+U`` gives
``x1(t) = Km U (t - tau (1 - exp(-t/tau)))``, the fastest any law can move; it reaches a level ``D`` at
``t = tau (d + 1 + W0(-exp(-(1 + d))))`` with ``d = D / (Km U tau)`` (Lambert's ``W0``).  No law settles a step
``A`` to the band ``beta`` before it enters the band, so ``t(A (1 - beta))`` is a lower bound on the settling
time; a requirement below it is infeasible for every controller.  The rest-to-rest minimum time (bang–bang, one
switch), ``tau ln((1 + r) / (1 - r))`` with ``r = sqrt(1 - exp(-A / (Km U tau)))``, is stated beside it.  On a
double integrator (``tau -> inf``, ``a = Km U / tau``) they tend to ``sqrt(2 D / a)`` and ``2 sqrt(A / a)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Conflict", "MinimumTime", "conflict", "minimum_time", "reach_time", "rest_to_rest_time"]


@dataclass(frozen=True)
class Conflict:
    """The requirements that trade off at the best compromise (module docstring).

    Parameters
    ----------
    active : str
        The requirement with the smallest margin at the compromise.
    against : str or None
        The requirement it trades against (None with a single requirement: it is limited by the certificates or
        the ranges alone).
    alone : dict
        Requirement -> the best normalised margin seen over every certified candidate.
    compromise : dict
        Requirement -> its normalised margin at the compromise.
    """

    active: str
    against: str | None
    alone: dict[str, float]
    compromise: dict[str, float]

    @property
    def sentence(self) -> str:
        """The conflict in words."""
        a, b = self.active, self.against
        if b is None:
            return (f"{a} cannot be met: its best normalised margin over every certified candidate is "
                    f"{self.alone[a]:.3g}.")
        return (f"{a} and {b} conflict: {a} alone reaches a normalised margin of {self.alone[a]:.3g} and {b} alone "
                f"{self.alone[b]:.3g}, but at the best compromise they are {self.compromise[a]:.3g} and "
                f"{self.compromise[b]:.3g}.")


def conflict(evaluations: tuple[Any, ...], best: Any) -> Conflict | None:
    """The conflicting pair of a search's candidates (None when no candidate was certified)."""
    certified = [e for e in evaluations if e.certified is not False and e.score > -20]
    if not certified or not best.margins:
        return None
    names = tuple(best.margins)
    alone = {n: max(e.margins[n] for e in certified) for n in names}
    a = best.active
    where = max(certified, key=lambda e: e.margins[a])
    others = [n for n in names if n != a]
    b = min(others, key=lambda n: where.margins[n]) if others else None
    return Conflict(a, b, alone, dict(best.margins))


@dataclass(frozen=True)
class MinimumTime:
    """The minimum-time bound of a link under a command limit (module docstring).

    Parameters
    ----------
    amplitude : float
        The step ``A`` (rad).
    limit : float
        The command limit ``U`` (N*m), and where it comes from (``source``).
    source : str
        ``requirements.max_control`` or ``simulation.nonlinearity.limit``.
    band : float
        The settling band ``beta`` (fraction of the step).
    reach : float
        The least time to enter the band (s): a lower bound on the settling time of any law.
    rest_to_rest : float
        The bang–bang minimum time to move ``A`` and stop (s).
    settling_time : float or None
        The settling-time requirement (s), None when the spec gives none.
    """

    amplitude: float
    limit: float
    source: str
    band: float
    reach: float
    rest_to_rest: float
    settling_time: float | None

    @property
    def proves(self) -> bool:
        """The settling-time requirement is below the bound: no controller meets it."""
        return self.settling_time is not None and self.settling_time < self.reach

    @property
    def sentence(self) -> str:
        """The bound in words."""
        text = (f"With |u| ≤ {self.limit:g} N·m ({self.source}), the link cannot enter the {100 * self.band:g} % "
                f"band of a {self.amplitude:g} rad step before {self.reach:.4g} s (full command from rest), nor "
                f"move it and stop before {self.rest_to_rest:.4g} s (bang–bang, one switch)")
        if self.settling_time is None:
            return text + "."
        if self.proves:
            return text + (f": the settling time of {self.settling_time:g} s asked for is infeasible for every "
                           "controller.")
        return text + f": the settling time of {self.settling_time:g} s asked for is not excluded by this bound."


def reach_time(distance: float, Km: float, tau: float, limit: float) -> float:
    """Least time (s) to move ``distance`` (rad) from rest under ``|u| <= limit`` (module docstring)."""
    from scipy.special import lambertw

    d = distance / (Km * limit * tau)
    return float(tau * (d + 1.0 + np.real(lambertw(-math.exp(-(1.0 + d)), 0))))


def rest_to_rest_time(distance: float, Km: float, tau: float, limit: float) -> float:
    """Bang–bang minimum time (s) to move ``distance`` (rad) from rest to rest under ``|u| <= limit``."""
    r = math.sqrt(1.0 - math.exp(-distance / (Km * limit * tau)))
    return float(tau * math.log((1.0 + r) / (1.0 - r)))


def minimum_time(spec: Any) -> MinimumTime | None:
    """The bound for a spec on a ``link`` plant with a command limit (requirement or saturation), else None."""
    if spec.plant.kind != "link":
        return None
    limits = []
    req = spec.requirements
    if req is not None and req.max_control is not None:
        limits.append((float(np.min(req.max_control)), "requirements.max_control"))
    nl = spec.simulation.nonlinearity
    if nl is not None and getattr(nl, "kind", "") == "saturation":
        limits.append((float(np.min(nl.limit)), "simulation.nonlinearity.limit"))
    if not limits:
        return None
    limit, source = min(limits)
    amplitude = abs(float(np.max(np.abs(np.atleast_1d(spec.simulation.step)))))
    band = float(req.settling_band) if req is not None else 0.02
    Km, tau = float(spec.plant.Km), float(spec.plant.tau)
    return MinimumTime(amplitude, limit, source, band, reach_time(amplitude * (1 - band), Km, tau, limit),
                       rest_to_rest_time(amplitude, Km, tau, limit),
                       None if req is None or req.settling_time is None else float(req.settling_time))
