"""A switching law's chatter predicted from its loop (:mod:`~designkit.verification.limit_cycle`) and measured on
its run, in words with units; and the boundary layer that removes it.

A switching family gives the linear loop its relay sees (:class:`~designkit.verification.limit_cycle.Loop`, from
the relay's output ``v`` to the switching variable ``s``) and the relay's amplitude ``M``; the run gives how the
command was held (:func:`timing_of`).  The **prediction** (:func:`predict`):

* a sampled command (period ``Ts``, delay ``L``): the exact symmetric orbit of the smallest consistent half period
  ``k`` (:func:`~designkit.verification.limit_cycle.sampled_orbit`): frequency ``1/(2 k Ts)`` (Hz), amplitude of
  ``s``, the command a square wave of amplitude ``M`` (behind an actuator lag, the lag's output amplitude);
* a continuous command with an actuator lag or a delay: the exact continuous orbit when there is one, else the
  describing function's; a lag alone on a loop of relative degree one (relative degree two in all) has neither:
  no finite limit cycle, the swing decaying while the frequency grows until the integration step stops it;
* neither: no finite limit cycle (the run's chatter is set by its integration step).

The orbit is symmetric: it is the chatter where the equivalent control is 0.  Where the averaged (equivalent)
control ``u_eq`` takes a share ``r = |u_eq|/M`` of the relay, the relay spends ``(1 - r)/2`` of the time on the
minority side; when the loop is an integrator at the chatter's frequency (relative degree one: ``s' ~ b v``) the
minority side keeps its ``k`` samples and the other side lengthens to ``k (1 + r)/(1 - r)``: the frequency
falls to ``f (1 - r)`` and the swing of ``s`` grows to ``A (1 + r)`` (a first-order estimate, stated as such, for
the sampled orbit only: behind a lag or a delay the words say that the orbit is not the symmetric one).

The **measurement** (:func:`measure`) is read on a settled window of the run (the family chooses it): the half
swing of ``s`` (the mean over its half cycles of the largest ``|s|`` in each), the half peak-to-peak of the
command, the sign changes of ``s`` per second over two (Hz), and the averaged
command ``u_eq``.

The **chatter amplitude** ``requirements.max_chatter_amplitude`` bounds is the half peak-to-peak of the command
on that window (the input's unit): ``M`` for a relay whatever the equivalent control, 0 for a command that has
settled.  :func:`layer_fix` sizes the boundary layer that removes it: inside ``|s| < eps`` the relay is the linear
gain ``M/eps``, and the oscillation vanishes when that gain is below the loop's critical gain; the layer is
chosen with the gain at ``LAYER_SHARE`` of the critical one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.verification.limit_cycle import (
    Loop,
    continuous_orbit,
    critical_gain,
    describing_function,
    layer_for_gain,
    no_cycle_words,
    relative_degree,
    sampled_orbit,
)

__all__ = ["LAYER_SHARE", "ChatterMeasured", "ChatterPredicted", "Timing", "layer_fix", "layer_words", "limit_of",
           "measure", "predict", "timing_of", "verdict", "words"]

LAYER_SHARE = 0.5
"""The boundary layer's linear gain ``M/eps`` is this share of the loop's critical gain (a gain margin of 2)."""


@dataclass(frozen=True)
class Timing:
    """How the run held the command.

    Parameters
    ----------
    period : float
        The sampling period ``Ts`` (s); 0 when the command is computed at every integration step.
    delay : float
        The delay ``L`` (s) from the sample to the command reaching the plant.
    bandwidth : float or None
        The actuator lag's bandwidth (rad/s) the spec states, None without one.
    lag_in_run : bool
        The run contains that lag (its settings record an actuator bandwidth).
    step : float
        The integration step ``dt`` (s).
    """

    period: float
    delay: float
    bandwidth: float | None
    lag_in_run: bool
    step: float


def _first(value: Any) -> float | None:
    if value is None:
        return None
    return float(value[0]) if isinstance(value, list | tuple) else float(value)


def timing_of(spec: Any, sim: Any) -> Timing:
    """The run's sampling period and delay (``sim.settings``), the actuator lag the spec's ``implementation``
    states, and whether the run was built with it (its settings say what the verdict is on as implemented,
    ``settings["implementation"]``)."""
    st = sim.settings
    actuator = getattr(getattr(spec, "implementation", None), "actuator", None)
    bandwidth = _first(getattr(actuator, "bandwidth", None))
    in_run = hasattr(st, "get") and st.get("implementation") is not None
    return Timing(float(st.get("sampling_period") or 0.0), float(st.get("delay") or 0.0), bandwidth,
                  bool(in_run and bandwidth is not None), float(st["dt"]))


@dataclass(frozen=True)
class ChatterPredicted:
    """The predicted chatter.

    Parameters
    ----------
    kind : str
        ``"sampled"`` (exact sampled orbit), ``"continuous"`` (exact continuous orbit), ``"describing"``
        (describing function) or ``"none"`` (no finite limit cycle).
    frequency : float or None
        The cycle's frequency (Hz).
    s_amplitude : float or None
        Amplitude of ``s`` on the cycle (the unit of ``s``).
    command : float or None
        Amplitude of the command's switching component (the input's unit): ``M`` (the relay's square wave), or
        the lag's output amplitude when the run contains the lag.
    output : float or None
        Amplitude of the loop's output named ``"output"`` (its unit), when the loop has one.
    half_period : int or None
        ``k`` (samples) of a sampled orbit.
    sentence : str
        The prediction in words.
    """

    kind: str
    frequency: float | None
    s_amplitude: float | None
    command: float | None
    output: float | None
    half_period: int | None
    sentence: str

    def to_dict(self) -> dict[str, Any]:
        """JSON form (Hz, the units of ``s``, of the input and of the output)."""
        return {"kind": self.kind, "frequency_hz": self.frequency, "s_amplitude": self.s_amplitude,
                "command_amplitude": self.command, "output_amplitude": self.output,
                "half_period_samples": self.half_period, "words": self.sentence}


def predict(loop: Loop, amplitude: float, timing: Timing, s_unit: str, u_unit: str,
            name: str = "s") -> ChatterPredicted:
    """The chatter the relay of ``amplitude`` (the input's unit) sustains on ``loop`` as the run holds it
    (module docstring); the lag enters the loop when the spec states one; ``name`` is the switching variable's."""
    m = float(amplitude)
    lagged = loop.with_lag(timing.bandwidth) if timing.bandwidth else loop
    lag_words = f" behind the actuator lag of {timing.bandwidth:.4g} rad/s" if timing.bandwidth else ""

    def peak(orbit: Any, name: str) -> float | None:
        return dict(orbit.peaks).get(name)

    if timing.period > 0:
        orbit = sampled_orbit(lagged, m, timing.period, timing.delay)
        if orbit is None:
            return ChatterPredicted("sampled", None, None, None, None, None,
                                    f"the sampled relay loop{lag_words} has no symmetric orbit of up to "
                                    f"{2 * 200} samples")
        cmd = peak(orbit, "actuator") if timing.bandwidth else m
        delay = f" and a delay of {timing.delay:.3g} s" if timing.delay > 0 else ""
        return ChatterPredicted(
            "sampled", orbit.frequency, orbit.amplitude, cmd, peak(orbit, "output"), orbit.half_period,
            f"sampled every {timing.period:.3g} s{delay}{lag_words}, the relay's exact orbit (the smallest "
            f"consistent one, {orbit.tried} shorter ones inconsistent) holds {orbit.half_period} sample"
            f"{'s' if orbit.half_period > 1 else ''} at each sign: {orbit.frequency:.4g} Hz, |{name}| up to "
            f"{orbit.amplitude:.3g} {s_unit}, the command switching by ±{cmd:.3g} {u_unit}")
    if timing.bandwidth or timing.delay > 0:
        exact = continuous_orbit(lagged, m, delay=timing.delay)
        if exact is not None:
            cmd = peak(exact, "actuator") if timing.bandwidth else m
            return ChatterPredicted("continuous", exact.frequency, exact.amplitude, cmd, peak(exact, "output"), None,
                                    f"the continuous relay loop{lag_words} has the exact orbit of "
                                    f"{exact.frequency:.4g} Hz, |{name}| up to {exact.amplitude:.3g} {s_unit}, the "
                                    f"command switching by ±{cmd:.3g} {u_unit}")
        cycle = describing_function(lagged, m, delay=timing.delay)
        if cycle is not None:
            return ChatterPredicted("describing", cycle.hertz, cycle.amplitude, cycle.command, None, None,
                                    f"the describing function of the relay{lag_words} balances at "
                                    f"{cycle.hertz:.4g} Hz with {name} of amplitude {cycle.amplitude:.3g} {s_unit} "
                                    f"(the command's fundamental 4M/π = {cycle.command:.3g} {u_unit})")
    return ChatterPredicted("none", None, None, None, None, None,
                            no_cycle_words(timing.step, relative_degree(lagged) if timing.bandwidth else 1))


@dataclass(frozen=True)
class ChatterMeasured:
    """The chatter measured on a settled window of the run.

    Parameters
    ----------
    start, stop : float
        The window (s).
    s_amplitude : float
        The half swing of ``s``: the mean over its complete half cycles (runs of one sign) of the largest
        ``|s|`` in each (the unit of ``s``); a slow drift of ``s`` across the window does not enter it.
    command : float
        Half the peak-to-peak of the command: the chatter amplitude (the input's unit).
    frequency : float
        Sign changes of ``s`` per second over two (Hz).
    equivalent : float
        The mean command over the window, the equivalent control (the input's unit).
    """

    start: float
    stop: float
    s_amplitude: float
    command: float
    frequency: float
    equivalent: float

    def to_dict(self) -> dict[str, Any]:
        """JSON form (s, Hz, the units of ``s`` and of the input)."""
        return {"window_s": [self.start, self.stop], "s_amplitude": self.s_amplitude,
                "chatter_amplitude": self.command, "frequency_hz": self.frequency,
                "equivalent_control": self.equivalent}

    @classmethod
    def from_dict(cls, d: dict[str, Any] | None) -> ChatterMeasured | None:
        """The measurement from its JSON form (:meth:`to_dict`); None from None."""
        if d is None:
            return None
        return cls(float(d["window_s"][0]), float(d["window_s"][1]), float(d["s_amplitude"]),
                   float(d["chatter_amplitude"]), float(d["frequency_hz"]), float(d["equivalent_control"]))


def _half_swing(s: np.ndarray) -> float:
    """The mean over the complete half cycles (runs of one sign, the first and last cut by the window left out)
    of the largest ``|s|`` in each; half the peak-to-peak when there are fewer than three runs."""
    nz = s[s != 0]
    cuts = np.flatnonzero(np.sign(nz[1:]) != np.sign(nz[:-1])) + 1
    runs = np.split(nz, cuts)[1:-1]
    if len(runs) < 1:
        return float(np.ptp(s)) / 2 if s.size else 0.0
    return float(np.mean([np.max(np.abs(r)) for r in runs]))


def measure(t: np.ndarray, s: np.ndarray, u: np.ndarray) -> ChatterMeasured | None:
    """The chatter on the window the arrays cover (``t`` in s); None on fewer than two samples."""
    t, s, u = (np.asarray(x, float) for x in (t, s, u))
    if t.size < 2 or t[-1] <= t[0]:
        return None
    nz = s[s != 0]
    flips = int(np.count_nonzero(np.sign(nz[1:]) != np.sign(nz[:-1]))) if nz.size > 1 else 0
    span = float(t[-1] - t[0])
    return ChatterMeasured(float(t[0]), float(t[-1]), _half_swing(s), float(np.ptp(u)) / 2, flips / 2 / span,
                           float(np.mean(u)))


def words(pred: ChatterPredicted, meas: ChatterMeasured | None, amplitude: float, s_unit: str, u_unit: str,
          compared: bool = True, name: str = "s") -> str:
    """Predicted against measured in words (the relay ``amplitude`` in the input's unit, for the bias share;
    ``name`` the switching variable's)."""
    if meas is None:
        return f"predicted: {pred.sentence}; no settled window to measure"
    seen = (f"measured over {meas.start:.3g}–{meas.stop:.3g} s: {meas.frequency:.4g} Hz (sign changes of {name} "
            f"over two), {name} swinging by ±{meas.s_amplitude:.3g} {s_unit}, the command by ±{meas.command:.3g} "
            f"{u_unit} about the equivalent control {meas.equivalent:.3g} {u_unit}")
    if not compared:
        return f"predicted: {pred.sentence}; {seen} (the run does not contain the actuator lag: not compared)"
    if pred.kind == "none" or pred.frequency is None:
        return f"predicted: {pred.sentence}; {seen}"
    r = min(abs(meas.equivalent) / amplitude, 1.0) if amplitude > 0 else 0.0
    bias = ""
    if 1e-3 < r < 1 and pred.s_amplitude is not None and pred.kind != "sampled":
        bias = (f"; the equivalent control takes r = {r:.3g} of M, so the orbit is not the symmetric one predicted "
                "(the first-order estimate holds for a held relay on an integrator, not behind a lag or a delay)")
    elif 1e-3 < r < 1 and pred.s_amplitude is not None:
        bias = (f"; with the equivalent control taking r = {r:.3g} of M the first-order estimate is "
                f"{pred.frequency * (1 - r):.4g} Hz and ±{pred.s_amplitude * (1 + r):.3g} {s_unit}")
    ratio = meas.frequency / pred.frequency
    return (f"predicted: {pred.sentence}{bias}; {seen} ({ratio:.3g} times the symmetric orbit's frequency)")


def layer_fix(loops: list[Loop], amplitude: float, timing: Timing) -> tuple[float, float] | None:
    """``(eps, K_c)``: the boundary layer (the unit of ``s``) whose gain ``M/eps`` is :data:`LAYER_SHARE` of the
    smallest critical gain ``K_c`` (the input's unit per unit of ``s``) over ``loops`` (the loop at the corners
    of a parameter box, say), held as the run holds it (its sampling period, or its integration step, and its
    delay); None when no gain destabilises any of them, or one of them is not stable at a small gain."""
    hold = timing.period if timing.period > 0 else timing.step
    gains = [critical_gain(loop.with_lag(timing.bandwidth) if timing.bandwidth else loop, hold, timing.delay)
             for loop in loops]
    k = min(gains)
    if not math.isfinite(k) or k <= 0:
        return None
    return layer_for_gain(amplitude, k, LAYER_SHARE), k


def limit_of(spec: Any) -> float | None:
    """``requirements.max_chatter_amplitude`` (the input's unit), None when the spec does not bound it."""
    req = getattr(spec, "requirements", None)
    limit = getattr(req, "max_chatter_amplitude", None) if req is not None else None
    return None if limit is None else float(limit)


def verdict(meas: ChatterMeasured | None, limit: float, unit: str) -> tuple[bool, float | None, str]:
    """``(passed, achieved, words)``: the measured chatter amplitude (half the peak-to-peak command on the
    settled window, the input's ``unit``) against ``limit``; without a settled window it fails, unmeasured."""
    if meas is None:
        return False, None, "no settled window to measure the chatter amplitude on"
    ok = meas.command <= limit
    return ok, meas.command, (f"chatter amplitude (half the peak-to-peak command over the settled window) "
                              f"{meas.command:.4g} {unit} {'within' if ok else 'over'} the limit {limit:.4g} {unit}")


def layer_words(amplitude: float, eps: float, k_c: float, timing: Timing, s_unit: str, u_unit: str,
                where: str) -> str:
    """Why the layer ``eps`` (the unit of ``s``) removes the relay's (``amplitude``, the input's unit) chatter: its
    gain against the critical gain ``k_c`` of the loop held as the run holds it (``where``: which loops)."""
    hold = (f"sampled every {timing.period:.3g} s" if timing.period > 0 else
            f"held over the integration step {timing.step:.3g} s")
    extra = "".join((f", a delay of {timing.delay:.3g} s" if timing.delay > 0 else "",
                     f", the actuator lag of {timing.bandwidth:.4g} rad/s" if timing.bandwidth else ""))
    return (f"inside the layer the relay is the linear gain {amplitude:.4g}/ε = {amplitude / eps:.4g} {u_unit}/"
            f"({s_unit}), {LAYER_SHARE:g} of the critical gain {k_c:.4g} {u_unit}/({s_unit}) of {where} "
            f"({hold}{extra}), so the predicted oscillation vanishes and the command settles to the equivalent "
            "control")
