"""Integration step and duration of a simulation: defaults, and checks of the user's values.

Defaults (``|p|`` over the requested closed-loop poles, the closed-loop poles on the true
plant, the open-loop plant poles at the operating point and the reference's rate; see
:func:`rates_of` and :mod:`designkit.simulation.reference`):

* ``dt``: ``min(DT_FACTOR / |p|max, duration / MIN_SAMPLES)`` rounded down to a "round" value
  ``{1, 2, 2.5, 5} x 10^k`` (so that round event times fall on the grid), then the largest step
  not above it dividing the sampling period and the delay into whole numbers of steps;
* ``duration``: ``horizon + settle + delay`` with ``settle = 3 * requirements.settling_time``
  when given, else ``10 / |Re p|min`` over the requested poles, and ``horizon`` the reference's
  own duration (0 for a step); extended to ``perturbation.time + settle + delay`` when later.

A user ``dt`` must divide the sampling period and the delay into whole numbers of steps and
satisfy ``dt * |p|max <= MAX_DT_RATE``, else :class:`SpecError` on ``simulation.dt``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.spec.schema import Spec

DT_FACTOR = 0.02
"""Default step as a fraction of the fastest time constant ``1/|p|max``."""
MAX_DT_RATE = 1.0
"""Largest accepted ``dt * |p|max`` (RK4 is unstable beyond 2.78 and inaccurate well before)."""
MIN_SAMPLES = 200
"""The default step gives at least this many steps over the duration."""
MAX_STEPS = 2_000_000
"""Refuse simulations longer than this many steps."""
SETTLE_FACTOR, POLE_HORIZON = 3.0, 10.0


@dataclass(frozen=True)
class Timing:
    """Resolved time grid: ``t_k = k dt``, ``k = 0 .. n_samples - 1``.

    Parameters
    ----------
    dt : float
        Integration step (s).
    n_samples : int
        Number of recorded instants (``n_samples - 1`` steps cover the duration).
    steps_per_sample : int
        Integration steps per sampling period (0: continuous controller).
    delay_steps : int
        Integration steps of control delay.
    settings : dict
        How dt and the duration were chosen, JSON-serialisable.
    """

    dt: float
    n_samples: int
    steps_per_sample: int
    delay_steps: int
    settings: dict[str, Any]


@dataclass(frozen=True)
class Rates:
    """Time scales of a simulated loop.

    Parameters
    ----------
    fast : float
        Fastest rate ``|p|max`` over every relevant pole and the reference (1/s).
    slow : float
        Slowest decay ``|Re p|min`` of the requested (or, without any, the closed-loop) poles (1/s).
    """

    fast: float
    slow: float


def rates_of(requested: Any, *pole_sets: Any, reference_rate: float = 0.0) -> Rates:
    """:class:`Rates` from the requested poles and any further sets of poles (closed and open loop)."""
    requested = [complex(p) for p in requested]
    others = [complex(p) for poles in pole_sets for p in np.asarray(poles).ravel()]
    fast = max([abs(p) for p in (*requested, *others)] + [float(reference_rate)])
    decays = [abs(p.real) for p in requested] or [abs(p.real) for p in others if abs(p.real) > 0]
    slow = min(decays) if decays else 1.0
    return Rates(fast=fast if fast > 0 else 1.0, slow=slow if slow > 0 else 1.0)


def _nice_floor(value: float) -> float:
    """Largest number ``{1, 2, 2.5, 5} x 10^k`` not above ``value`` (1e-9 relative slack)."""
    exp = math.floor(math.log10(value * (1 + 1e-9)))
    for mantissa in (5.0, 2.5, 2.0, 1.0):
        if mantissa * 10.0**exp <= value * (1 + 1e-9):
            return mantissa * 10.0**exp
    return 10.0**exp


def _whole_steps(period: float, dt: float) -> int | None:
    """``period / dt`` when it is a whole number (relative tolerance 1e-6), else None."""
    ratio = period / dt
    n = round(ratio)
    return n if n >= 1 and abs(ratio - n) <= 1e-6 * ratio else None


def _rational_gcd(values: list[float]) -> float | None:
    """Largest ``g`` with every value a whole multiple of ``g`` (values as fractions to 1e-9)."""
    fracs = [Fraction(v).limit_denominator(10**9) for v in values if v > 0]
    if not fracs:
        return None
    den = math.lcm(*(f.denominator for f in fracs))
    return math.gcd(*(f.numerator * (den // f.denominator) for f in fracs)) / den


def _duration(spec: Spec, slow: float, horizon: float) -> tuple[float, str]:
    sim, req = spec.simulation, spec.requirements
    if sim.duration is not None:
        return float(sim.duration), "simulation.duration"
    if req is not None and req.settling_time is not None:
        settle, why = SETTLE_FACTOR * req.settling_time, f"{SETTLE_FACTOR:g} x requirements.settling_time"
    else:
        settle, why = POLE_HORIZON / slow, f"{POLE_HORIZON:g} / |Re p|min"
    start = horizon
    if sim.perturbation is not None:
        start = max(start, sim.perturbation.time)
    return start + settle + sim.delay, f"default: max(reference horizon, perturbation time) + {why} + delay"


def resolve(spec: Spec, rates: Rates, ref_horizon: float) -> Timing:
    """Integration step, number of samples, sampling and delay steps for ``spec.simulation``."""
    sim = spec.simulation
    fast, slow = rates.fast, rates.slow
    duration, duration_source = _duration(spec, slow, ref_horizon)
    periods = {"simulation.sampling_period": sim.sampling_period, "simulation.delay": sim.delay}
    if sim.dt is None:
        target = _nice_floor(min(DT_FACTOR / fast, duration / MIN_SAMPLES))
        g = _rational_gcd(list(periods.values()))
        dt = target if g is None else g / math.ceil(g / target - 1e-9)
        dt_source = (f"default: min({DT_FACTOR:g}/|p|max, duration/{MIN_SAMPLES}) rounded down to "
                     "{1, 2, 2.5, 5} x 10^k, then the largest step not above it that divides the "
                     "sampling period and the delay")
    else:
        dt, dt_source = float(sim.dt), "simulation.dt"
        if dt * fast > MAX_DT_RATE:
            raise SpecError("simulation.dt", f"{dt:g} s is too coarse for the fastest pole |p| = {fast:.4g} 1/s "
                            f"(need dt*|p| <= {MAX_DT_RATE:g}, i.e. dt <= {MAX_DT_RATE / fast:.3g} s; "
                            f"the default would be {DT_FACTOR / fast:.3g} s)")
        for key, period in periods.items():
            if period > 0 and _whole_steps(period, dt) is None:
                raise SpecError("simulation.dt", f"{dt:g} s must divide {key} = {period:g} s into a whole "
                                f"number of steps (got {period / dt:.6g}); try dt = "
                                f"{period / math.ceil(period / dt):.6g} s or leave dt out")
    if dt >= duration:
        raise SpecError("simulation.dt", f"{dt:g} s must be smaller than the duration {duration:g} s")
    n_samples = round(duration / dt) + 1
    if n_samples > MAX_STEPS:
        raise SpecError("simulation.dt", f"{duration:g} s at dt = {dt:g} s needs {n_samples} steps, more than "
                        f"{MAX_STEPS}; shorten simulation.duration or enlarge dt")
    steps_per_sample = _whole_steps(sim.sampling_period, dt) or 0
    delay_steps = _whole_steps(sim.delay, dt) or 0
    settings = {
        "dt": dt, "dt_source": dt_source, "duration": (n_samples - 1) * dt, "duration_requested": duration,
        "duration_source": duration_source, "n_steps": n_samples - 1, "fastest_rate": fast,
        "slowest_rate": slow, "steps_per_sample": steps_per_sample, "delay_steps": delay_steps,
    }
    return Timing(dt, n_samples, steps_per_sample, delay_steps, settings)


def grid(timing: Timing) -> np.ndarray:
    """Recorded instants ``k dt`` (s)."""
    return timing.dt * np.arange(timing.n_samples)
