"""How a commanded input switches, measured on the simulated record as physics.

Every law's command ``u`` (``SimulationResult.u_command``, one column per input) is split into

* the **averaged control** ``u_avg``: the centred moving average of ``u`` over a window ``w`` (s) set by the
  loop's time scale (:func:`loop_window`), never by the integration step; for a switching law it is the
  equivalent control the plant responds to;
* the **switching component** ``s = u - u_avg``.

Measured per input:

* the amplitudes, the RMS of ``s`` and of ``u_avg`` over the run (the command's unit), and the peak ``|s|``;
  the switching part **dominates** when ``rms(s) > rms(u_avg)``;
* the **reversals**: turning points of ``u`` counted with a hysteresis ``h`` (a move against the current
  direction by more than ``h`` since the last extremum reverses it), ``h = max(HYSTERESIS * rms(s),
  FLOOR * range(u))``; the **reversal rate** is the count per second of the run (1/s); a square wave of
  frequency ``f`` reverses ``2 f`` times a second, as does a sine;
* the **total variation** ``TV = sum |u_{k+1} - u_k|`` and its rate ``TV / duration`` (the command's unit per
  second, what ``requirements.max_command_variation`` bounds);
* the rate against the clocks that could set it: the record's step ``dt`` (the integration step) and, when the
  command is sampled, the sampling period ``Ts``.  A record at step ``dt`` reverses at most ``1/dt`` times a
  second (a reversal every step, a square wave at the step's Nyquist frequency ``1/(2 dt)``); the rate is
  **set by the step** when it exceeds ``STEP_SHARE / dt``: the verdict then depends on a numerical choice.
  It is **set by the sampling** when it exceeds ``STEP_SHARE / Ts``.

A record that stops being finite is measured up to that instant (the divergence is ``finite_run``'s to report).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["FLOOR", "HYSTERESIS", "STEP_SHARE", "Switching", "loop_window", "measure", "moving_average",
           "input_unit", "judge", "judge_run", "of_run", "reversals", "warning"]

HYSTERESIS = 0.5
"""Share of the switching component's RMS a move must exceed to reverse the direction."""

FLOOR = 1e-3
"""Share of the command's range below which a move never counts (round-off of a smooth command)."""

STEP_SHARE = 0.1
"""A reversal rate above this many per step (``STEP_SHARE / dt``) is set by the step."""

WINDOW_SHARE = 0.01
"""Without a loop time scale, the averaging window is this share of the run's duration."""


@dataclass(frozen=True)
class Switching:
    """How one input's command switches (module docstring).

    Parameters
    ----------
    name : str
        The input.
    window : float
        Averaging window ``w`` (s).
    switching_rms, switching_peak : float
        RMS and peak ``|s|`` of the switching component (the command's unit).
    averaged_rms : float
        RMS of the averaged control ``u_avg`` (the command's unit).
    reversals : int
        Reversals of the command over the run.
    rate : float
        Reversals per second of the run (1/s).
    variation : float
        Total variation ``TV`` (the command's unit).
    variation_rate : float
        ``TV`` per second of the run (the command's unit per second).
    step : float
        The record's step ``dt`` (s).
    sampling_period : float
        ``Ts`` (s); 0 for a continuous-time command.
    duration : float
        The measured (finite) part of the run (s).
    """

    name: str
    window: float
    switching_rms: float
    switching_peak: float
    averaged_rms: float
    reversals: int
    rate: float
    variation: float
    variation_rate: float
    step: float
    sampling_period: float
    duration: float

    @property
    def dominates(self) -> bool:
        """The switching component's RMS exceeds the averaged control's."""
        return self.switching_rms > self.averaged_rms and self.reversals > 0

    @property
    def ratio(self) -> float:
        """``rms(s) / rms(u_avg)`` (inf for a zero averaged control with a switching part)."""
        if self.averaged_rms > 0:
            return self.switching_rms / self.averaged_rms
        return float("inf") if self.switching_rms > 0 else 0.0

    @property
    def step_set(self) -> bool:
        """The reversal rate exceeds ``STEP_SHARE / dt``: the integration step sets it."""
        return self.step > 0 and self.rate > STEP_SHARE / self.step

    @property
    def sampling_set(self) -> bool:
        """The command is sampled and its reversal rate exceeds ``STEP_SHARE / Ts``."""
        return self.sampling_period > 0 and self.rate > STEP_SHARE / self.sampling_period

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable form (units: s, 1/s, the command's unit)."""
        return {"input": self.name, "window_s": self.window, "switching_rms": self.switching_rms,
                "switching_peak": self.switching_peak, "averaged_rms": self.averaged_rms,
                "switching_to_averaged": self.ratio if np.isfinite(self.ratio) else None,
                "reversals": self.reversals, "reversal_rate_per_s": self.rate,
                "total_variation": self.variation, "variation_per_s": self.variation_rate,
                "step_s": self.step, "step_max_rate_per_s": 1 / self.step if self.step > 0 else None,
                "sampling_period_s": self.sampling_period, "dominates": self.dominates,
                "set_by_step": self.step_set, "set_by_sampling": self.sampling_set}


def moving_average(t: np.ndarray, u: np.ndarray, window: float) -> np.ndarray:
    """Centred moving average of ``u`` (sampled at ``t``, s) over ``window`` (s), by the trapezoidal running
    integral; near the ends the window is cut to the record (the mean over what there is)."""
    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float)
    if u.size < 2 or window <= 0:
        return u.copy()
    integral = np.concatenate(([0.0], np.cumsum(0.5 * (u[1:] + u[:-1]) * np.diff(t))))
    lo = np.clip(t - window / 2, t[0], t[-1])
    hi = np.clip(t + window / 2, t[0], t[-1])
    width = hi - lo
    area = np.interp(hi, t, integral) - np.interp(lo, t, integral)
    return np.where(width > 0, area / np.where(width > 0, width, 1.0), u)


def reversals(u: np.ndarray, hysteresis: float) -> int:
    """Turning points of ``u`` with a hysteresis (the command's unit): the direction reverses when ``u`` moves
    against it by more than ``hysteresis`` from the last extremum; the first direction taken is no reversal."""
    u = np.asarray(u, dtype=float)
    if u.size < 2:
        return 0
    direction, count = 0, 0
    high = low = extremum = float(u[0])
    for value in u[1:].tolist():
        if direction == 0:
            high, low = max(high, value), min(low, value)
            if value - low > hysteresis:
                direction, extremum = 1, value
            elif high - value > hysteresis:
                direction, extremum = -1, value
        elif direction * (value - extremum) > 0:
            extremum = value
        elif direction * (extremum - value) > hysteresis:
            direction, extremum, count = -direction, value, count + 1
    return count


def loop_window(design: Any, spec: Any, duration: float) -> float:
    """The averaging window (s) from the loop's time scale: ``1 / max |Re p|`` over the poles the design requests
    (``Design.poles``, 1/s: the placed poles, a sliding law's sliding poles) or, without any, the spec's
    ``controller.poles``; else ``WINDOW_SHARE`` of the run's ``duration`` (s); never shorter than two sampling
    periods of a sampled command."""
    window = WINDOW_SHARE * duration
    fastest = 0.0
    for poles in (getattr(design, "poles", None), getattr(getattr(spec, "controller", None), "poles", None)):
        try:
            fastest = max((abs(complex(p).real) for p in np.ravel(np.asarray(poles, dtype=complex))), default=0.0) \
                if poles is not None and len(poles) else 0.0
        except (TypeError, ValueError):
            fastest = 0.0
        if fastest > 0:
            window = 1.0 / fastest
            break
    sampling = max(float(getattr(getattr(spec, section, None), "sampling_period", 0.0) or 0.0)
                   for section in ("simulation", "implementation"))
    return max(window, 2 * sampling)


def _rms(x: np.ndarray) -> float:
    """RMS of ``x``, scaled by its peak first (a diverging record near 1e150 does not overflow its square)."""
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    if not np.isfinite(peak) or peak == 0:
        return peak
    return peak * float(np.sqrt(np.mean((x / peak) ** 2)))


def measure(name: str, t: np.ndarray, u: np.ndarray, window: float, sampling_period: float = 0.0) -> Switching:
    """Measure how the command ``u`` (sampled at ``t``, s) switches (module docstring), averaging over ``window``
    (s); ``sampling_period`` (s, 0: continuous) is the controller's."""
    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float)
    bad = np.flatnonzero(~np.isfinite(u) | ~np.isfinite(t))
    if bad.size:
        t, u = t[: bad[0]], u[: bad[0]]
    duration = float(t[-1] - t[0]) if t.size > 1 else 0.0
    step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    avg = moving_average(t, u, window)
    s = u - avg
    s_rms, a_rms = _rms(s), _rms(avg)
    peak = float(np.max(np.abs(s))) if s.size else 0.0
    span = float(np.ptp(u)) if u.size else 0.0
    count = reversals(u, max(HYSTERESIS * s_rms, FLOOR * span)) if span > 0 else 0
    tv = float(np.sum(np.abs(np.diff(u)))) if u.size > 1 else 0.0
    rate = count / duration if duration > 0 else 0.0
    return Switching(name, float(window), s_rms, peak, a_rms, count, rate, tv,
                     tv / duration if duration > 0 else 0.0, step, float(sampling_period), duration)


def warning(m: Switching, unit: str = "") -> str | None:
    """The page-1 sentence for an input whose switching part dominates or whose reversal rate the step or the
    sampling sets (None otherwise); the unit as the report writes it (``N*m`` -> ``N·m``)."""
    if not (m.dominates or m.step_set or m.sampling_set) or m.reversals == 0:
        return None
    from designkit.display.numbers import unit as written

    u = f" {written(unit)}" if unit else ""
    parts = [f"The commanded {m.name} switches {m.rate:.3g} times a second ({m.reversals} reversals in "
             f"{m.duration:.3g} s) with a switching component of RMS {m.switching_rms:.3g}{u} (peak "
             f"{m.switching_peak:.3g}{u}) on an averaged control of RMS {m.averaged_rms:.3g}{u} (averaged over "
             f"{m.window:.3g} s)"]
    if m.dominates:
        parts.append("the switching part dominates the command")
    if m.step_set:
        parts.append(f"the rate is set by the integration step (dt = {m.step:.3g} s, which allows at most "
                     f"{1 / m.step:.3g} reversals a second), so the verdict depends on a numerical choice and "
                     f"holds for a continuous-time switch simulated at that step, not for a controller as implemented")
    elif m.sampling_set:
        parts.append(f"the rate is set by the sampling period ({m.sampling_period:.3g} s)")
    return "; ".join(parts) + "."


def judge(m: Switching, unit: str = "") -> tuple[bool, str]:
    """A switching law's chattering judged as physics: it passes when its switching component does not dominate
    the equivalent (averaged) control and its reversal rate is not set by the integration step (a rate set by the
    sampling period is the controller's own clock and is allowed).  Returns ``(passed, words)``."""
    u = f" {unit}" if unit else ""
    ratio = "inf" if not np.isfinite(m.ratio) else f"{m.ratio:.3g}"
    words = (f"switching component RMS {m.switching_rms:.3g}{u} against the equivalent control's "
             f"{m.averaged_rms:.3g}{u} (ratio {ratio}, averaged over {m.window:.3g} s); {m.rate:.3g} reversals a "
             f"second against at most {1 / m.step:.3g} the step allows" if m.step > 0 else "no record")
    if m.sampling_period > 0:
        words += f" and {1 / m.sampling_period:.3g} samples a second"
    faults = []
    if m.dominates:
        faults.append("the switching part dominates the command")
    if m.step_set:
        faults.append("the rate is set by the integration step, a numerical choice")
    return not faults, words + (": " + " and ".join(faults) if faults else "")


def sampling_of(sim: Any, spec: Any) -> float:
    """The period (s, 0: continuous) at which the run ``sim`` sampled its law: its settings' ``sampling_period``
    (``simulation.sampling_period``, ``implementation.sampling_period`` or the law's own), else the spec's
    ``simulation.sampling_period``."""
    settings = getattr(sim, "settings", None)
    if hasattr(settings, "get") and settings.get("sampling_period") is not None:
        return float(settings.get("sampling_period") or 0.0)
    return float(getattr(getattr(spec, "simulation", None), "sampling_period", 0.0) or 0.0)


def of_run(design: Any, sim: Any, spec: Any, j: int = 0) -> Switching:
    """How input ``j`` of the run ``sim`` (a ``SimulationResult``) of ``design`` switches, averaged over
    :func:`loop_window`, with the period the run sampled its law at (:func:`sampling_of`)."""
    duration = float(sim.time[-1] - sim.time[0]) if len(sim.time) > 1 else 0.0
    sampling = sampling_of(sim, spec)
    return measure(sim.input_names[j], sim.time, np.asarray(sim.u_command)[:, j],
                   loop_window(design, spec, duration), sampling)


def judge_run(design: Any, sim: Any, spec: Any, unit: str = "") -> tuple[bool, str, list[dict[str, Any]]]:
    """:func:`judge` on every input of the run: ``(every input passes, words, [Switching.to_dict per input])``;
    the words name the input when there are several and its unit (the plant's, else ``unit``)."""
    measured = [of_run(design, sim, spec, j) for j in range(len(sim.input_names))]
    verdicts = [judge(m, input_unit(design, j) or unit) for j, m in enumerate(measured)]
    several = len(measured) > 1
    words = "; ".join(f"{m.name}: {w}" if several else w for m, (_, w) in zip(measured, verdicts, strict=True))
    return all(ok for ok, _ in verdicts), words, [m.to_dict() for m in measured]


def input_unit(design: Any, j: int) -> str:
    """The unit of the design's plant input ``j`` (``plant.inputs[j].unit``; empty when the plant names none)."""
    inputs = getattr(getattr(design, "plant", None), "inputs", None)
    try:
        return str(inputs[j].unit)
    except (TypeError, IndexError, AttributeError):
        return ""
