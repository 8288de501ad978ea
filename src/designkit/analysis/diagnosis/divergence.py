"""Divergence and oscillation of a simulated loop, measured on the run (no model needed).

:func:`divergence_of` decides whether the nonlinear loop diverged (non-finite samples, an integrator
failure, or an error envelope that keeps growing) and gives the evidence; :func:`measure_oscillation`
finds a sustained, regular oscillation at the end of a run; :func:`describe` says how a run diverged.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import at_time, fmt_number, quantity

__all__ = [
    "CYCLE_WINDOW",
    "GROWTH_FACTOR",
    "NOISE_FLOOR",
    "TAIL_FRACTION",
    "Divergence",
    "Oscillation",
    "describe",
    "divergence_of",
    "measure_oscillation",
]

TAIL_FRACTION = 0.25
"""Final fraction of a run whose error envelope is compared with the error scale (divergence)."""
GROWTH_FACTOR = 2.0
"""A run diverges when its error over the last :data:`TAIL_FRACTION` exceeds this times the error scale
(the commanded step or move) and still grows: a stable loop ends well inside its initial error."""
CYCLE_WINDOW = 0.4
"""Final fraction of a run searched for a sustained oscillation."""
MIN_CYCLES = 3
"""A limit cycle needs at least this many full periods in the window."""
REGULARITY = 0.2
"""Largest relative spread (std/mean) of the measured periods of a limit cycle (noise is irregular)."""
SUSTAINED = 0.8
"""Smallest ratio of the oscillation amplitude in the second half of the window to the first (not decaying)."""
NOISE_FLOOR = 1e-6
"""Oscillations below this fraction of the error scale (rad) are numerical, not limit cycles."""

@dataclass(frozen=True)
class Divergence:
    """Evidence of a diverging run (all times in s from ``time[0]``).

    Parameters
    ----------
    diverged : bool
    reason : str
        ``"non-finite"``, ``"integrator"``, ``"growing"`` or ``""``.
    scale : float
        The error scale (rad): the largest commanded step or move, or the initial error.
    onset : float or None
        When ``|x - xD|`` first exceeds ``scale`` (or the first non-finite sample).
    peaks : tuple of (float, float)
        ``(time, |e|)`` of the largest ``|e|`` of every half-cycle (between sign changes of ``e``).
    growth_rate : float or None
        Slope of ``ln |e|`` over the growing peaks (1/s).
    tail_error, previous_error : float
        Largest ``|e|`` over the last quarter of the run and over the quarter before (rad).
    joint : int
        0-based tracked coordinate with the largest final error.
    """

    diverged: bool
    reason: str
    scale: float
    onset: float | None
    peaks: tuple[tuple[float, float], ...]
    growth_rate: float | None
    tail_error: float
    previous_error: float
    joint: int


@dataclass(frozen=True)
class Oscillation:
    """A sustained oscillation measured on a signal.

    Parameters
    ----------
    amplitude : float
        Half peak-to-peak over the window (signal unit).
    frequency : float
        ``2 pi / period`` (rad/s), the period the mean spacing of the upward mean-crossings.
    mean : float
        Mean of the signal over the window.
    mean_abs_deviation : float
        Mean ``|signal - mean|`` over the window.
    cycles : int
        Full periods in the window.
    start : float
        Start of the window (s).
    """

    amplitude: float
    frequency: float
    mean: float
    mean_abs_deviation: float
    cycles: int
    start: float


def measure_oscillation(t: np.ndarray, y: np.ndarray, *, window: float = CYCLE_WINDOW,
                        scale: float = 1.0) -> Oscillation | None:
    """A sustained, regular oscillation of ``y`` over the last ``window`` of the run, or None.

    The signal minus its window mean must cross zero upward at least :data:`MIN_CYCLES` + 1 times,
    with periods regular to :data:`REGULARITY`, an amplitude above :data:`NOISE_FLOOR` ``* scale``,
    and an amplitude in the window's second half at least :data:`SUSTAINED` times that of the first.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    if t.size < 8 or not np.all(np.isfinite(y)):
        return None
    start = t[-1] - window * (t[-1] - t[0])
    sel = t >= start
    tw, yw = t[sel], y[sel]
    mean = float(np.mean(yw))
    d = yw - mean
    amp = 0.5 * float(np.max(d) - np.min(d))
    if amp <= NOISE_FLOOR * max(scale, 1e-300):
        return None
    k = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
    if k.size < MIN_CYCLES + 1:
        return None
    crossings = tw[k] + (tw[k + 1] - tw[k]) * (-d[k]) / (d[k + 1] - d[k])
    periods = np.diff(crossings)
    if np.std(periods) > REGULARITY * np.mean(periods):
        return None
    half = tw >= 0.5 * (tw[0] + tw[-1])
    a1 = 0.5 * float(np.ptp(d[~half])) if np.any(~half) else amp
    a2 = 0.5 * float(np.ptp(d[half]))
    if a1 <= 0 or a2 < SUSTAINED * a1 or a2 > a1 / SUSTAINED:
        return None
    # whole periods only for the mean |deviation|
    whole = (tw >= crossings[0]) & (tw <= crossings[-1])
    mad = float(np.mean(np.abs(d[whole])))
    return Oscillation(amplitude=amp, frequency=float(2 * np.pi / np.mean(periods)), mean=mean,
                       mean_abs_deviation=mad, cycles=int(periods.size), start=float(tw[0]))


def _errors(sim: Any) -> np.ndarray:
    tracked = sim.tracked if getattr(sim, "tracked", None) is not None else \
        np.asarray(sim.state, float)[:, list(sim.positions)]
    return np.asarray(tracked, float) - np.asarray(sim.reference, float)[:, :, 0]


def _error_scale(sim: Any, e: np.ndarray) -> float:
    ref = np.asarray(sim.reference, float)[:, :, 0]
    with np.errstate(invalid="ignore"):
        moves = np.max(np.abs(ref - ref[0]), axis=0)
        first = np.abs(e[0])
    vals = [float(v) for v in (*moves, *first) if np.isfinite(v)]
    return max(vals) if vals else 0.0


def _rising(peaks: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """The final run of half-cycle peaks each 1 % above the one before (a last, smaller one cut short by the end
    of the run is left out)."""
    peaks = list(peaks)
    if len(peaks) >= 2 and peaks[-1][1] < peaks[-2][1]:
        peaks = peaks[:-1]
    k0 = len(peaks) - 1
    while k0 > 0 and 1.01 * peaks[k0 - 1][1] < peaks[k0][1]:
        k0 -= 1
    return peaks[k0:]


def divergence_of(sim: Any) -> Divergence:
    """Whether the simulated loop diverged (see the module docstring) and the evidence."""
    t = np.asarray(sim.time, float)
    e = _errors(sim)
    scale = _error_scale(sim, e)
    u = np.asarray(sim.u_command, float).reshape(t.size, -1)
    finite = np.all(np.isfinite(e), axis=1) & np.all(np.isfinite(u), axis=1) & \
        np.all(np.isfinite(np.asarray(sim.state, float)), axis=1)
    failure = dict(sim.settings).get("integrator_failure") if getattr(sim, "settings", None) else None
    n = t.size
    with np.errstate(invalid="ignore"):
        mag = np.abs(e)
    last_ok = int(np.flatnonzero(finite)[-1]) if finite.any() else 0
    joint = int(np.nanargmax(mag[last_ok])) if mag.shape[1] and np.any(np.isfinite(mag[last_ok])) else 0
    ej = e[:, joint]
    tail0, prev0 = int(n * (1 - TAIL_FRACTION)), int(n * (1 - 2 * TAIL_FRACTION))
    with np.errstate(invalid="ignore"):
        tail = float(np.nanmax(mag[tail0:])) if np.any(np.isfinite(mag[tail0:])) else math.inf
        prev = float(np.nanmax(mag[prev0:tail0])) if np.any(np.isfinite(mag[prev0:tail0])) else math.inf
    # half-cycle peaks of the finite part
    peaks: list[tuple[float, float]] = []
    good = np.flatnonzero(np.isfinite(ej))
    if good.size:
        seg_e, seg_t = ej[good], t[good]
        sign = np.sign(seg_e)
        cuts = np.flatnonzero(sign[1:] * sign[:-1] < 0) + 1
        for chunk in np.split(np.arange(seg_e.size), cuts):
            if chunk.size:
                k = chunk[int(np.argmax(np.abs(seg_e[chunk])))]
                peaks.append((float(seg_t[k] - t[0]), float(abs(seg_e[k]))))
    reason = ""
    onset = None
    if not np.all(finite):
        reason, onset = "non-finite", float(t[int(np.flatnonzero(~finite)[0])] - t[0])
    elif failure:
        reason = "integrator"
    elif scale > 0 and tail > GROWTH_FACTOR * scale and tail > prev:
        reason = "growing"
    if reason and onset is None:
        with np.errstate(invalid="ignore"):
            over = np.flatnonzero(np.nanmax(mag, axis=1) > scale) if scale > 0 else np.array([], int)
        onset = float(t[int(over[0])] - t[0]) if over.size else None
    growth = None
    if reason == "growing" and len(peaks) >= 2:
        rising = _rising(peaks)
        rising = rising[1:] if len(rising) >= 3 else rising  # the first is where growth starts, off the envelope
        if len(rising) >= 2 and rising[-1][0] > rising[0][0]:
            tt = np.array([p[0] for p in rising])
            yy = np.log([p[1] for p in rising])
            growth = float(np.polyfit(tt, yy, 1)[0])
    return Divergence(diverged=bool(reason), reason=reason, scale=scale, onset=onset, peaks=tuple(peaks),
                      growth_rate=growth, tail_error=tail, previous_error=prev, joint=joint)



def describe(result: Any, div: Divergence) -> str:
    """How the run of ``result`` diverged, in words (``div`` from :func:`divergence_of`)."""
    sim = result.simulation
    name = sim.coordinate_names[div.joint] if len(sim.coordinate_names) > div.joint else "x1"
    unit = sim.coordinate_units[div.joint] if len(sim.coordinate_units) > div.joint else "rad"
    if div.reason == "non-finite":
        how = f"the simulated state stops being finite at {at_time(div.onset or 0.0)}"
    elif div.reason == "integrator":
        how = str(dict(sim.settings).get("integrator_failure"))
    else:
        seq = _rising([p for p in div.peaks if p[1] > 0])[-4:]
        peaks = ", ".join(f"{quantity(v, unit)} ({at_time(tt)})" for tt, v in seq)
        err = f"|{name} − xD|" if len(sim.coordinate_names) == 1 else f"|{name} − {name}D|"
        what = "step" if sim.kind == "step" else "move"
        how = (f"the error {err} first exceeds the {quantity(div.scale, unit)} {what} at {at_time(div.onset or 0.0)} "
               f"and its half-cycle peaks grow ({peaks}")
        if div.growth_rate is not None and div.growth_rate > 0:
            how += f"; growth rate {quantity(div.growth_rate, '1/s', 3)}"
        how += (f"), reaching {fmt_number(div.tail_error / div.scale, 3)} times the {what} over the last "
                f"{fmt_number(100 * TAIL_FRACTION, 2)} % of the run")
    return how
