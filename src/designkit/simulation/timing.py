"""Integrator, integration step and duration of a simulation: defaults, and checks of the user's values.

Rates (:func:`rates_of`): ``|p|`` over the requested closed-loop poles, the closed-loop poles on
the nominal and the true plant and the reference's rate (:mod:`designkit.simulation.reference`);
``|p|max`` the fastest, ``|Re p|min`` the slowest requested decay, ``|p|med`` and ``|Re p|med``
the lower medians of the requested poles' moduli and decays (one extreme pole at either end of
the spectrum does not move them).

Defaults:

* ``duration``: ``horizon + settle + delay`` with ``settle = 3 * requirements.settling_time``
  when given, else ``10 / |Re p|min``, and ``horizon`` the reference's own duration (0 for a
  step); extended to ``perturbation.time + settle + delay`` when later;
* ``dt``: ``min(DT_FACTOR / rate, duration / MIN_SAMPLES)`` rounded down to a "round" value
  ``{1, 2, 2.5, 5} x 10^k`` (so that round event times fall on the grid), then the largest step
  not above it dividing the sampling period and the delay into whole numbers of steps.  A switching
  law held over each step whose own largest step sets the rate (``Law.max_step``: the step *is* its
  sampling, and each step costs its evaluation) is not rounded: its step is the largest not above
  ``max_step`` that puts the scenario's events on the grid (:func:`_switching_dt`).  ``rate``
  is ``|p|max`` for RK4; for CVODES it leaves out the *stiff* poles (``|p| > STIFF_RATIO |p|med``),
  which CVODES' BDF integrates with steps of its own;
* integrator (``numerics.integrator`` not given): RK4 unless its grid would need more than
  :data:`MAX_STEPS` steps (or a user ``dt`` is too coarse for it) because of stiff poles; then
  CVODES, whose output step follows the other poles and the reference;
* a default duration whose grid would exceed the integrator's budget (:data:`MAX_STEPS` for RK4,
  :data:`MAX_VARIABLE_STEPS` for CVODES), e.g. because of a pole near ``-1e-9``, is cut to
  ``max(CAPPED_STEPS * dt, horizon + 10 / |Re p|med + delay)`` when that fits the budget; the
  settings then say that the run does not reach steady state.

The sampling period is ``implementation.sampling_period``, ``simulation.sampling_period`` or the one the control
law declares (:func:`sampling_of`, which refuses them in conflict), the delay ``implementation.delay`` or
``simulation.delay`` (:func:`delay_of`); an implementation's period or delay not shorter than the run is refused
naming its key.  A user ``dt`` must divide the sampling
period and the delay into whole numbers of steps and satisfy ``dt * rate <= MAX_DT_RATE``, else
:class:`SpecError` on ``simulation.dt``.  Any run longer than :data:`MAX_STEPS` steps is refused
(a resource bound) naming the field to change: ``simulation.dt`` when the user set it,
``numerics.integrator`` when an explicit ``rk4`` meets a stiff loop; when the control law's largest step
sets the step, the controller field the family declares as setting it (``step_fields`` on its spec
class, :func:`step_field`: a boundary layer, a band, a relay amplitude) with the value the run needs, or
``controller``; else ``simulation.duration``.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from designkit.errors import SpecError

DT_FACTOR = 0.02
"""Default step as a fraction of the fastest resolved time constant ``1/rate``."""
MAX_DT_RATE = 1.0
"""Largest accepted ``dt * rate`` (RK4 is unstable beyond 2.78 and inaccurate well before)."""
MIN_SAMPLES = 200
"""The default step gives at least this many steps over the duration."""
MAX_STEPS = 2_000_000
"""Resource bound: refuse simulations longer than this many steps (about 2-4 s of RK4 on one link)."""
MAX_VARIABLE_STEPS = 100_000
"""A default duration needing more CVODES output steps than this is cut (one CVODES call, about 0.1 ms, per step)."""
CAPPED_STEPS = 20_000
"""Steps of a cut default duration."""
STIFF_RATIO = 100.0
"""A pole faster than ``STIFF_RATIO * |p|med`` is stiff: left to the BDF inside each CVODES output step."""
SETTLE_FACTOR, POLE_HORIZON = 3.0, 10.0
ROUNDING = 1e-6
"""Relative slack of the step rule: a rate within this of a round value is that value.  Poles are roots of
polynomials; a double root is computed to about ``sqrt(eps)`` (1.5e-8) relative -- the PUMA's double pole at
-20 comes out as 20.0000004 -- so a slack at the last bit would halve the intended step."""


@dataclass(frozen=True)
class Timing:
    """Resolved time grid: ``t_k = k dt``, ``k = 0 .. n_samples - 1``.

    Parameters
    ----------
    dt : float
        Integration (output) step (s).
    n_samples : int
        Number of recorded instants (``n_samples - 1`` steps cover the duration).
    steps_per_sample : int
        Integration steps per sampling period (0: continuous controller).
    delay_steps : int
        Integration steps of control delay.
    settings : dict
        How the integrator, dt and the duration were chosen, JSON-serialisable.
    integrator : str
        ``"rk4"`` or ``"cvodes"``: the one chosen (the user's ``numerics.integrator`` when given).
    """

    dt: float
    n_samples: int
    steps_per_sample: int
    delay_steps: int
    settings: dict[str, Any]
    integrator: str = "rk4"


@dataclass(frozen=True)
class Rates:
    """Time scales of a simulated loop.

    Parameters
    ----------
    fast : float
        Fastest rate ``|p|max`` over every relevant pole and the reference (1/s).
    slow : float
        Slowest decay ``|Re p|min`` of the requested (or, without any, the closed-loop) poles (1/s).
    poles : tuple of float
        Distinct moduli of the poles considered, ascending (1/s); empty: only ``fast`` is known.
    median : float
        Lower median of the requested poles' moduli ``|p|med`` (1/s); 0: unknown.
    median_decay : float
        Lower median of the requested poles' decays ``|Re p|med`` (1/s); 0: unknown.
    reference : float
        Rate of the reference (1/s), always resolved by the output grid.
    """

    fast: float
    slow: float
    poles: tuple[float, ...] = ()
    median: float = 0.0
    median_decay: float = 0.0
    reference: float = 0.0

    def stiff(self) -> tuple[float, ...]:
        """Moduli of the stiff poles, ``|p| > STIFF_RATIO |p|med`` (1/s), ascending."""
        if self.median <= 0:
            return ()
        return tuple(r for r in self.poles if r > STIFF_RATIO * self.median)

    def resolved(self) -> float:
        """Fastest rate a CVODES output grid must follow: the non-stiff poles and the reference (1/s)."""
        stiff = self.stiff()
        if not stiff:
            return self.fast
        kept = [r for r in self.poles if r not in stiff]
        return max([*kept, self.reference, self.median])


def _lower_median(values: list[float]) -> float:
    values = sorted(v for v in values if v > 0)
    return values[(len(values) - 1) // 2] if values else 0.0


def rates_of(requested: Any, *pole_sets: Any, reference_rate: float = 0.0) -> Rates:
    """:class:`Rates` from the requested poles and any further sets of poles (closed and open loop).

    Parameters
    ----------
    requested : sequence of complex
        The requested closed-loop poles (1/s).
    *pole_sets : array_like of complex
        Further poles that set time scales (1/s).
    reference_rate : float
        Rate of the reference (1/s).
    """
    requested = [complex(p) for p in requested]
    others = [complex(p) for poles in pole_sets for p in np.asarray(poles).ravel()]
    fast = max([abs(p) for p in (*requested, *others)] + [float(reference_rate)])
    decays = [abs(p.real) for p in requested] or [abs(p.real) for p in others if abs(p.real) > 0]
    slow = min(decays) if decays else 1.0
    base = requested or others
    moduli: list[float] = []
    for r in sorted(abs(p) for p in (*requested, *others) if abs(p) > 0):
        if not moduli or r > moduli[-1] * (1 + 1e-6):  # one entry per distinct rate (requested = closed loop)
            moduli.append(r)
    return Rates(fast=fast if fast > 0 else 1.0, slow=slow if slow > 0 else 1.0, poles=tuple(moduli),
                 median=_lower_median([abs(p) for p in base]), median_decay=_lower_median(decays),
                 reference=float(reference_rate))


def _nice_floor(value: float) -> float:
    """Largest number ``{1, 2, 2.5, 5} x 10^k`` not above ``value`` (:data:`ROUNDING` relative slack); a value too
    small to round (0 or subnormal) is kept, at least the smallest float, for the step bound to refuse."""
    if not value >= sys.float_info.min:
        return max(value, math.ulp(0.0))
    exp = math.floor(math.log10(value * (1 + ROUNDING)))
    for mantissa in (5.0, 2.5, 2.0, 1.0):
        if mantissa * 10.0**exp <= value * (1 + ROUNDING):
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


def _event_times(spec: Any) -> list[float]:
    """Instants a held law's grid should land on (s): a user duration, the perturbation's and the plant change's
    onsets, a square wave's half period and a PRBS's bit."""
    sim = spec.simulation
    out = [float(sim.duration)] if sim.duration is not None else []
    for section in (sim.perturbation, sim.plant_change):
        if section is not None and float(section.time) > 0:
            out.append(float(section.time))
    traj = sim.trajectory
    kind = getattr(traj, "kind", None)
    if kind == "square":
        out.append(0.5 * float(traj.period))
    elif kind == "prbs":
        out.append(float(traj.bit))
    return out


def _switching_dt(limit: float, events: list[float]) -> float:
    """The largest step not above ``limit`` (s) that divides every event instant into whole steps (their rational
    greatest common divisor ``e``, then ``e / ceil(e / limit)``), or ``limit`` itself when there is no event."""
    e = _rational_gcd(events)
    if e is None:
        return limit
    ratio = e / limit - ROUNDING
    return e / math.ceil(ratio) if math.isfinite(ratio) else limit  # too many steps to count: the step bound refuses


def _default_dt(rate: float, duration: float, g: float | None) -> float:
    """Default step (s) for the fastest resolved ``rate`` (1/s): see the module docstring."""
    target = _nice_floor(min(DT_FACTOR / rate, duration / MIN_SAMPLES))
    return target if g is None else g / math.ceil(g / target - ROUNDING)


def _count(n: float) -> str:
    """A step count for a message: the integer up to 1e9, else three significant digits."""
    return f"{n:.0f}" if n < 1e9 else f"{n:.3g}"


def _duration(spec: Any, slow: float, horizon: float, delay: float | None = None) -> tuple[float, str, float]:
    """``(duration, why, start)``: ``start`` (s) is where the settling allowance begins, plus the delay (s, default
    ``simulation.delay``)."""
    sim, req = spec.simulation, spec.requirements
    delay = float(sim.delay) if delay is None else float(delay)
    start = max(horizon, sim.perturbation.time) if sim.perturbation is not None else horizon
    if sim.duration is not None:
        return float(sim.duration), "simulation.duration", start + delay
    if req is not None and req.settling_time is not None:
        settle, why = SETTLE_FACTOR * req.settling_time, f"{SETTLE_FACTOR:g} x requirements.settling_time"
    else:
        settle, why = POLE_HORIZON / slow, f"{POLE_HORIZON:g} / |Re p|min"
    return (start + settle + delay, f"default: max(reference horizon, perturbation time) + {why} + delay",
            start + delay)


def _choose_integrator(spec: Any, rates: Rates, stiff: tuple[float, ...], duration: float,
                       rk4_dt: float) -> tuple[str, str]:
    """``(integrator, why)``: the user's, else RK4 unless stiff poles make its grid too fine."""
    numerics, sim = spec.numerics, spec.simulation
    if "integrator" in numerics.model_fields_set:
        return numerics.integrator, "numerics.integrator"
    steps = duration / rk4_dt
    too_coarse = sim.dt is not None and rk4_dt * rates.fast > MAX_DT_RATE
    if not stiff or (steps <= MAX_STEPS and not too_coarse):
        return "rk4", "default (RK4 resolves every pole within the step bound)"
    if too_coarse:
        need = (f"simulation.dt = {rk4_dt:g} s is too coarse for RK4 "
                f"(dt*|p| = {rk4_dt * rates.fast:.3g} > {MAX_DT_RATE:g})")
    else:
        need = f"would need {_count(steps)} RK4 steps of {rk4_dt:.3g} s over {duration:.4g} s (more than {MAX_STEPS})"
    return "cvodes", (f"chosen: cvodes because the fastest pole |p| = {rates.fast:.4g} 1/s {need}; stiff poles "
                      f"(|p| > {STIFF_RATIO:g} |p|med = {STIFF_RATIO * rates.median:.4g} 1/s: "
                      f"{', '.join(f'{r:.4g}' for r in stiff)} 1/s) are integrated by CVODES' BDF with steps of its "
                      f"own, and the output step follows the other poles and the reference "
                      f"(|p| <= {rates.resolved():.4g} 1/s)")


def step_field(controller: Any) -> tuple[str, float, int] | None:
    """``(name, value, power)``: the first field of ``controller`` the user set among those its family declares as
    setting the law's largest step (``step_fields``, name -> ``+1`` when the step grows with the value, at most in
    proportion, ``-1`` when it shrinks as it grows, at most inversely), or None."""
    declared = getattr(type(controller), "step_fields", None) or {}
    given = getattr(controller, "model_fields_set", set())
    for name, power in declared.items():
        value = getattr(controller, name, None)
        if name in given and isinstance(value, int | float) and not isinstance(value, bool) and value > 0:
            return name, float(value), int(power)
    return None


def _law_step_error(spec: Any, duration: float, dt: float, steps: float, law_step: tuple[float, str]) -> SpecError:
    """The resource-bound refusal when the step is the control law's largest step: naming the controller field that
    sets it (:func:`step_field`) and the value the run's step count needs, else the controller."""
    max_dt, reason = law_step
    need = duration / MAX_STEPS
    what = (f"sets the integration step: the control law is simulated with steps of at most {max_dt:.3g} s, so "
            f"{duration:.4g} s needs {_count(steps)} steps, more than {MAX_STEPS} (resource bound)")
    found = step_field(spec.controller)
    if found is None:
        declared = list(getattr(type(spec.controller), "step_fields", None) or {})
        hint = (f"; set what sets the step ({', '.join('controller.' + d for d in declared)})" if declared else "")
        return SpecError("controller", f"the design {what}: {reason}{hint}; the step needs to be at least {need:.3g} "
                         "s (or shorten simulation.duration)")
    name, value, power = found
    fit = value * (need / max_dt) ** (1.0 / power)
    bound = "at least" if power > 0 else "at most"
    grows = "grows at most in proportion to it" if power > 0 else "shrinks at least inversely as it grows"
    return SpecError(f"controller.{name}", f"{value:g} {what}; the step {grows}, so a run of {duration:.4g} s (steps "
                     f"of at least {need:.3g} s) needs controller.{name} {bound} {fit:.3g}")


def _bound_error(spec: Any, duration: float, dt: float, steps: float, *, integrator: str, stiff_hint: bool,
                 held: bool, law_step: tuple[float, str] | None = None) -> SpecError:
    """The resource-bound refusal, naming the field to change: the controller's field when the control law's
    largest step ``law_step`` (s, and why) sets the step, else ``simulation.dt`` or ``simulation.duration``."""
    sim = spec.simulation
    if law_step is not None and sim.dt is None:
        return _law_step_error(spec, duration, dt, steps, law_step)
    what = f"{duration:.4g} s at dt = {dt:.3g} s needs {_count(steps)} steps, more than {MAX_STEPS} (resource bound)"
    if stiff_hint and integrator == "rk4" and "integrator" in spec.numerics.model_fields_set:
        return SpecError("numerics.integrator", f"rk4: {what}: the loop is stiff; use numerics.integrator: cvodes "
                         "(variable-step BDF, output step set by the slow poles) or leave it out, or shorten "
                         "simulation.duration")
    note = "" if not (held and stiff_hint) else (
        " (the control is held over each step -- a delay or a discontinuous element without a sampling "
        "period -- so the step must follow the fastest pole whatever the integrator; with "
        "simulation.sampling_period the plant is integrated by cvodes between samples)")
    if sim.dt is not None:
        return SpecError("simulation.dt", f"{what}{note}; enlarge simulation.dt or shorten simulation.duration")
    return SpecError("simulation.duration", f"{what}{note}; shorten simulation.duration (or set a coarser "
                                            "simulation.dt)")


def sampling_of(spec: Any, law: Any) -> tuple[float, str]:
    """``(period, key)``: the controller's sampling period (s, 0: continuous) and the key path that sets it.

    A law that declares the period it was designed for (:attr:`designkit.synthesis.law.Law.sampling_period`)
    is sampled there; ``simulation.sampling_period`` may then be left out or repeat it.

    Raises
    ------
    SpecError
        On ``simulation.sampling_period`` when it is positive and differs from the law's period.
    """
    given = float(spec.simulation.sampling_period)
    impl = getattr(getattr(spec, "implementation", None), "sampling_period", None)
    own = getattr(law, "sampling_period", None)
    if impl is not None:
        impl = float(impl)
        key = "implementation.sampling_period"
        if given > 0 and abs(given - impl) > 1e-9 * impl:
            raise SpecError(key, f"{impl:g} s conflicts with simulation.sampling_period = {given:g} s; the controller "
                            "as implemented is sampled once: leave simulation.sampling_period out or set it to "
                            f"{impl:g} s")
        if own is not None and abs(impl - own) > 1e-9 * own:
            source = getattr(law, "sampling_period_source", "") or "the control law's design"
            raise SpecError(key, f"{impl:g} s conflicts with the {own:g} s the controller was designed for "
                            f"({source}); leave {key} out or set it to {own:g} s")
        if own is None:
            return impl, key
    if own is None:
        return given, "simulation.sampling_period"
    source = getattr(law, "sampling_period_source", "") or "the control law's design"
    if given > 0 and abs(given - own) > 1e-9 * own:
        raise SpecError("simulation.sampling_period", f"{given:g} s conflicts with the {own:g} s the controller was "
                        f"designed for ({source}); leave simulation.sampling_period out or set it to {own:g} s")
    return float(own), source


def delay_of(spec: Any) -> tuple[float, str]:
    """``(delay, key)``: the control delay (s, 0: none) and the key path that sets it: ``implementation.delay`` when
    positive, else ``simulation.delay``.

    Raises
    ------
    SpecError
        On ``implementation.delay`` when both are positive and differ.
    """
    given = float(spec.simulation.delay)
    impl = float(getattr(getattr(spec, "implementation", None), "delay", 0.0) or 0.0)
    if impl <= 0:
        return given, "simulation.delay"
    if given > 0 and abs(given - impl) > 1e-9 * impl:
        raise SpecError("implementation.delay", f"{impl:g} s conflicts with simulation.delay = {given:g} s; the "
                        f"controller as implemented has one computation delay: leave simulation.delay out or set it "
                        f"to {impl:g} s")
    return impl, "implementation.delay"


MAX_DELAY_STEPS = 10_000
"""Longest delay line, in integration steps (its values are part of the simulated state)."""


def resolve(spec: Any, rates: Rates, ref_horizon: float, *, held_per_step: bool = False, max_dt: float | None = None,
            max_dt_reason: str = "", sampling: tuple[float, str] | None = None,
            delay: tuple[float, str] | None = None) -> Timing:
    """Integrator, step, number of samples, sampling and delay steps for ``spec.simulation``.

    Parameters
    ----------
    spec : Spec
        Its ``simulation``, ``numerics`` and ``requirements.settling_time`` are used.
    rates : Rates
        Time scales of the loop (1/s), see :func:`rates_of`.
    ref_horizon : float
        The reference's own duration (s; 0 for a step).
    held_per_step : bool
        The control is evaluated once per step and held (a delay or a discontinuous element with a
        continuous controller): the step is then the control's update period and must follow every
        pole, so CVODES cannot take larger steps over stiff poles.
    max_dt : float, optional
        The largest step the law can be simulated with (s; :attr:`designkit.synthesis.law.Law.max_step`), and
        ``max_dt_reason`` why: the default step is chosen at or below it, a larger ``simulation.dt`` is refused.
    sampling : (float, str), optional
        The controller's sampling period (s) and the key path that sets it (:func:`sampling_of`); default
        ``simulation.sampling_period``.
    delay : (float, str), optional
        The control delay (s) and the key path that sets it (:func:`delay_of`); default ``simulation.delay``.

    Raises
    ------
    SpecError
        ``simulation.dt`` incompatible with the sampling period, the delay, the poles or the
        duration; or a run beyond :data:`MAX_STEPS` steps (see the module docstring).
    """
    sim = spec.simulation
    fast = rates.fast
    delay_s, delay_key = (float(sim.delay), "simulation.delay") if delay is None else (float(delay[0]), delay[1])
    duration, duration_source, start = _duration(spec, rates.slow, ref_horizon, delay_s)
    sample, sample_key = (float(sim.sampling_period), "simulation.sampling_period") if sampling is None else sampling
    periods = {sample_key: sample, delay_key: delay_s}
    g = _rational_gcd(list(periods.values()))
    stiff = () if held_per_step else rates.stiff()
    default_dt = sim.dt is None
    if max_dt is not None and not default_dt and float(sim.dt) > max_dt * (1 + 1e-12):
        raise SpecError("simulation.dt", f"{float(sim.dt):g} s is coarser than the {max_dt:.3g} s this control law "
                        f"can be simulated with ({max_dt_reason or 'its own bound'}); leave dt out or set at most "
                        f"{max_dt:.3g} s")
    law_rate = DT_FACTOR / max_dt if max_dt is not None else 0.0
    law_sets_step = bool(law_rate) and law_rate > fast
    fast = max(fast, law_rate)
    rk4_dt = _default_dt(fast, duration, g) if default_dt else float(sim.dt)
    integrator, integrator_source = _choose_integrator(spec, rates, stiff, duration, rk4_dt)
    rate = rates.resolved() if integrator == "cvodes" and stiff else fast
    if default_dt:
        dt = _default_dt(rate, duration, g)
        dt_source = (f"default: min({DT_FACTOR:g}/|p|, duration/{MIN_SAMPLES}) rounded down to "
                     "{1, 2, 2.5, 5} x 10^k, then the largest step not above it that divides the "
                     "sampling period and the delay; |p| = "
                     + ("|p|max" if rate == fast else "the fastest non-stiff pole or the reference rate")
                     + f" = {rate:.4g} 1/s")
        if law_rate and rate == law_rate and law_rate > rates.fast:
            dt_source += (f", set by the control law's largest step {max_dt:.3g} s (|p| = {DT_FACTOR:g}/max step): "
                          f"{max_dt_reason}")
            if held_per_step and not any(v > 0 for v in periods.values()):
                # a switching law held over each step: the step is its sampling, so take the step it can have (its
                # largest step, down only to put the scenario's events on the grid) rather than a round value
                dt = _switching_dt(min(max_dt, duration / MIN_SAMPLES), _event_times(spec))
                dt_source = (f"default for a law held over each step: its largest step {max_dt:.3g} s "
                             f"({max_dt_reason}), reduced to the largest step not above it (and not above "
                             f"duration/{MIN_SAMPLES}) that puts the scenario's events (a set duration, the "
                             "perturbation's and plant change's onsets, a square wave's half period, a PRBS bit) "
                             "on the grid")
    else:
        dt, dt_source = float(sim.dt), "simulation.dt"
        if dt * rate > MAX_DT_RATE:
            hint = (" (the loop is stiff: numerics.integrator: cvodes takes this step)"
                    if integrator == "rk4" and rates.stiff() and not held_per_step else "")
            raise SpecError("simulation.dt", f"{dt:g} s is too coarse for the fastest pole |p| = {rate:.4g} 1/s "
                            f"(need dt*|p| <= {MAX_DT_RATE:g}, i.e. dt <= {MAX_DT_RATE / rate:.3g} s; "
                            f"the default would be {DT_FACTOR / rate:.3g} s){hint}")
        for key, period in periods.items():
            if period > 0 and _whole_steps(period, dt) is None:
                raise SpecError("simulation.dt", f"{dt:g} s must divide {key} = {period:g} s into a whole "
                                f"number of steps (got {period / dt:.6g}); try dt = "
                                f"{period / math.ceil(period / dt):.6g} s or leave dt out")
    requested = duration
    steady: str | None = None
    budget = MAX_VARIABLE_STEPS if integrator == "cvodes" else MAX_STEPS
    if default_dt and sim.duration is None and not duration / dt <= budget:
        needed = start + POLE_HORIZON / (rates.median_decay if rates.median_decay > 0 else rates.slow)
        cut = max(CAPPED_STEPS * dt, needed)
        if cut / dt <= budget:
            duration = cut
            duration_source = (f"default cut to max({CAPPED_STEPS} steps, horizon + 10/|Re p|med + delay): "
                               f"{duration_source.removeprefix('default: ')}"
                               f" = {requested:.4g} s would need {_count(requested / dt)} steps (more than {budget} "
                               f"with {integrator})")
            steady = (f"not reached: the slowest requested pole decays at {rates.slow:.3g} 1/s and the default "
                      f"duration ({requested:.4g} s) was cut to {duration:.4g} s (covers horizon + 10/|Re p|med + "
                      f"delay = {needed:.4g} s); checks that need the steady state (settling time, steady-state error) "
                      "are measured at the end of this run; set simulation.duration to simulate longer")
    steps = duration / dt
    if not steps <= MAX_STEPS and default_dt:  # an implemented period or delay too short for the run sets the step
        for key, period in periods.items():
            if key.startswith("implementation.") and period > 0 and duration / period > MAX_STEPS:
                raise SpecError(key, f"{period:g} s sets the integration step (the step divides it into whole "
                                f"steps): {duration:.4g} s needs at least {_count(duration / period)} steps, more "
                                f"than {MAX_STEPS} (resource bound); lengthen {key} or shorten simulation.duration")
    if not steps <= MAX_STEPS:
        raise _bound_error(spec, duration, dt, steps, integrator=integrator, stiff_hint=bool(rates.stiff()),
                           held=held_per_step, law_step=(max_dt, max_dt_reason) if law_sets_step and max_dt else None)
    for key, period in periods.items():  # the controller as implemented: a period or delay beyond the run
        if key.startswith("implementation.") and period >= duration:
            raise SpecError(key, f"{period:g} s is not shorter than the run ({duration:.6g} s, {duration_source}): "
                            "the run would not see one sample of the controller as implemented; shorten it or "
                            "set a longer simulation.duration")
    if dt >= duration:
        raise SpecError("simulation.dt", f"{dt:g} s must be smaller than the duration {duration:g} s")
    n_samples = round(steps) + 1
    steps_per_sample = _whole_steps(sample, dt) or 0
    delay_steps = _whole_steps(delay_s, dt) or 0
    if delay_steps > MAX_DELAY_STEPS:
        raise SpecError(delay_key, f"{delay_s:g} s is {delay_steps} steps of dt = {dt:g} s, more than the "
                        f"{MAX_DELAY_STEPS} a delay line may hold (resource bound: the line is part of the simulated "
                        f"state); shorten {delay_key} or set a coarser simulation.dt")
    settings: dict[str, Any] = {
        "integrator_choice": integrator_source,
        "dt": dt, "dt_source": dt_source, "duration": (n_samples - 1) * dt,
        "duration_requested": requested if math.isfinite(requested) else str(requested),
        "duration_source": duration_source, "n_steps": n_samples - 1, "fastest_rate": rates.fast,
        "slowest_rate": rates.slow, "steps_per_sample": steps_per_sample, "delay_steps": delay_steps,
    }
    if integrator == "cvodes" and stiff:
        settings["stiff_rates"] = list(stiff)
    if steady is not None:
        settings["steady_state"] = steady
    return Timing(dt, n_samples, steps_per_sample, delay_steps, settings, integrator)


def grid(timing: Timing) -> np.ndarray:
    """Recorded instants ``k dt`` (s)."""
    return timing.dt * np.arange(timing.n_samples)
