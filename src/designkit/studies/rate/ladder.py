"""The ladder of sampling rates and the spec change each rung is: which key holds the command's sampling period,
and which integration step goes with it.

The command of a switching law is computed once per sampling period and held in between; the spec key that says so
is :data:`SAMPLING_KEYS`'s first unless the spec already samples its command through another (the key its run was
sampled by, :func:`sampling_key`).  The default ladder (:func:`default_rates`) is :data:`DEFAULT_RATES` for a law
designed in continuous time; a law that declares its own sampling period (a key of its controller section, such as
the sliding-mode identification's ``controller.sampling_period``) was designed for that rate, and its default
ladder is :data:`OWN_FACTORS` times it.  The integration step ``simulation.dt`` must divide the period into whole steps:
left out, the simulator's default does (it takes the largest step not above its rule that divides the sampling
period); given, it is kept where it divides the period and otherwise replaced, for that rung, by the largest step
not above it that does (:func:`rung_changes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from designkit.studies.core.members import amount

__all__ = ["DEFAULT_RATES", "OWN_FACTORS", "SAMPLING_KEYS", "Rung", "default_rates", "divides", "own_rate",
           "rung_changes", "sampling_key"]

DEFAULT_RATES = (20_000.0, 10_000.0, 5_000.0, 2_000.0, 1_000.0, 500.0)
"""The rates run when the spec's ``studies.rate.rates`` is not given (Hz), for a law designed in continuous time."""
OWN_FACTORS = (4.0, 2.0, 1.0, 0.5, 0.25)
"""The default ladder of a law that declares its own sampling period: these multiples of its own rate (a law designed
for 500 Hz is run at 2 kHz, 1 kHz, 500 Hz, 250 Hz and 125 Hz)."""

SAMPLING_KEYS = ("implementation.sampling_period", "simulation.sampling_period")
"""Where a spec gives the period its command is computed at and held over (s); the study sets the first when the
spec samples its command through none of them."""


@dataclass(frozen=True)
class Rung:
    """One rate of the ladder: ``rate`` (Hz), its ``period`` (s), the spec ``changes`` that run it (key path, value)
    and ``dt_note``, what was done to the integration step (empty: the spec's step or the default, left as is)."""

    rate: float
    period: float
    changes: tuple[tuple[str, Any], ...]
    dt_note: str = ""


def divides(step: float, period: float) -> bool:
    """Whether ``step`` (s) divides ``period`` (s) into a whole number of steps (to 1e-9 relative)."""
    n = period / step
    return abs(n - round(n)) <= 1e-9 * max(n, 1.0) and round(n) >= 1


def sampling_key(result: Any) -> str:
    """The key path of ``result``'s sampling period (module docstring): the key its run's command was sampled by
    (``simulation.settings['sampling_period_source']``, when it is a key of the spec), else a key of
    :data:`SAMPLING_KEYS` the spec gives a positive period, else :data:`SAMPLING_KEYS`'s first."""
    from designkit.runner.variants import spec_value

    spec = result.loaded.spec
    settings = getattr(result.simulation, "settings", {}) or {}
    source = str(settings.get("sampling_period_source") or "")
    if source and "." in source and " " not in source and spec_value(spec, source) is not None:
        return source
    for key in SAMPLING_KEYS:
        value = spec_value(spec, key)
        if isinstance(value, int | float) and value > 0:
            return key
    return SAMPLING_KEYS[0]


def own_rate(result: Any) -> tuple[float, str]:
    """``(rate, words)``: how often the spec's own run computes its command (1/s): its sampling rate when it is
    sampled, else once per integration step ``1/dt`` (a switching law held over each step)."""
    settings = getattr(result.simulation, "settings", {}) or {}
    period = float(settings.get("sampling_period") or 0.0)
    if period > 0:
        return 1.0 / period, f"sampled every {amount(period, 's', 4)}"
    dt = float(settings.get("dt") or (result.simulation.time[1] - result.simulation.time[0]))
    return 1.0 / dt, f"held over each integration step of {amount(dt, 's', 4)}"


def rung_changes(result: Any, key: str, rate: float) -> Rung:
    """The spec change that runs ``result``'s spec with its command sampled at ``rate`` (Hz) through ``key``
    (module docstring: the integration step kept, left to the default, or replaced where it does not divide)."""
    period = 1.0 / float(rate)
    changes: list[tuple[str, Any]] = [(key, period)]
    dt = result.loaded.spec.simulation.dt
    note = ""
    if dt is not None and not divides(float(dt), period):
        steps = math.ceil(period / float(dt) * (1 - 1e-12))
        new = period / steps
        changes.append(("simulation.dt", new))
        note = (f"the spec's simulation.dt = {amount(float(dt), 's', 4)} does not divide the period "
                f"{amount(period, 's', 4)}: replaced by {amount(new, 's', 4)} ({steps} steps a period)")
    return Rung(float(rate), period, tuple(changes), note)


def default_rates(result: Any, key: str) -> tuple[tuple[float, ...], str]:
    """The ladder run when the spec gives no ``studies.rate.rates`` (Hz, highest first) and where it comes from, in
    words: :data:`OWN_FACTORS` times the own rate when ``key`` (:func:`sampling_key`) is a key of the controller
    section (the law declares its period), else :data:`DEFAULT_RATES`."""
    if key.startswith("controller."):
        own, _ = own_rate(result)
        factors = ", ".join(f"{f:g}" for f in OWN_FACTORS)
        return (tuple(own * f for f in OWN_FACTORS),
                f"the law declares its own sampling period ({key}): the default ladder is {factors} times its rate")
    return DEFAULT_RATES, ""
