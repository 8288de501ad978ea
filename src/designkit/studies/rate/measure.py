"""What the rate study measures on one run of a switching law: the same numbers at every rate, from the run's record.

* **steady error** (``steady_error``, the reference's unit): the largest ``|x - xD|`` over the last
  :data:`STEADY_SHARE` of the reference's last plateau (:func:`plateau`: the whole run for a step, the last
  completed half period of a square wave, the whole run for a reference still moving at the end), the largest over
  the tracked coordinates -- the band the error stays in at the end, the limit cycle a held relay leaves included;
* **switching component** (``chatter_rms``, ``chatter_peak``, the command's unit) and **reversal rate**
  (``reversal_rate``, 1/s): :func:`designkit.verification.switching.measure` of each input's command, averaged over
  the loop's window (:func:`~designkit.verification.switching.loop_window`, never shorter than two sampling periods
  of the run), the largest over the inputs;
* **control effort** (``command_rms``, the command's unit): the RMS of ``u`` over the run, the largest over the
  inputs;
* the run's own clocks: the period its command was held (``sampling_period``, s, from the simulation's settings)
  and its integration step (``dt``, s).

A record that stops being finite is measured up to that instant by the switching measure; its steady error and
effort are infinite (the row's outcome says it diverged).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["KEYS", "STEADY_SHARE", "measure_run", "plateau", "units_of"]

STEADY_SHARE = 0.1
"""Share of the run, at its end, over which the steady error is taken."""

KEYS = ("steady_error", "chatter_rms", "chatter_peak", "reversal_rate", "command_rms", "sampling_period", "dt")
"""The keys of a row's metrics, in the table's order."""


def units_of(run: Any) -> tuple[str, str]:
    """``(reference unit, command unit)`` of ``run``: the tracked coordinates' and the plant inputs' (empty when
    several differ)."""
    sim = run.simulation
    coords = set(getattr(sim, "coordinate_units", ()) or ())
    plant = run.plant if getattr(run, "plant", None) is not None else run.design.plant
    inputs = {s.unit for s in getattr(plant, "inputs", ())}
    return (coords.pop() if len(coords) == 1 else ""), (inputs.pop() if len(inputs) == 1 else "")


PLATEAU_MIN = 10
"""Fewest samples a stretch of constant reference holds to be a plateau (a jump on the run's very last samples
leaves a shorter one: the plateau before it is taken)."""


def plateau(t: np.ndarray, xd: np.ndarray) -> tuple[int, int]:
    """``(first, end)`` sample indices of the reference's last plateau: the last stretch of ``xd`` (one column per
    coordinate) held constant over at least :data:`PLATEAU_MIN` samples -- the one before a jump on the run's last
    samples --, or the whole run for a reference that moves to the end (or never moves)."""
    n = t.size
    starts = np.flatnonzero(np.any(np.diff(xd, axis=0) != 0, axis=1)) + 1
    bounds = [0, *starts.tolist(), n]
    for k in (len(bounds) - 2, len(bounds) - 3):
        if k >= 0 and bounds[k + 1] - bounds[k] >= PLATEAU_MIN:
            return bounds[k], bounds[k + 1]
    return 0, n


def _steady(t: np.ndarray, e: np.ndarray, xd: np.ndarray) -> float:
    first, end = plateau(t, xd)
    tt, ee = t[first:end], e[first:end]
    tail = np.abs(ee[tt >= tt[-1] - STEADY_SHARE * (tt[-1] - tt[0])])
    return float(np.max(tail)) if np.all(np.isfinite(tail)) else math.inf


def _rms(u: np.ndarray) -> float:
    if not np.all(np.isfinite(u)):
        return math.inf
    peak = float(np.max(np.abs(u))) if u.size else 0.0
    return peak * float(np.sqrt(np.mean((u / peak) ** 2))) if peak > 0 else 0.0


def measure_run(run: Any) -> dict[str, float]:
    """The numbers of the module docstring on ``run`` (a run of the family's own, with a simulation), by key."""
    from designkit.verification.switching import loop_window, measure

    sim = run.simulation
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.tracking_errors, dtype=float).reshape(t.size, -1)
    u = np.asarray(sim.u_command, dtype=float).reshape(t.size, -1)
    xd = np.asarray(sim.desired, dtype=float).reshape(t.size, -1)
    settings = getattr(sim, "settings", {}) or {}
    period = float(settings.get("sampling_period") or 0.0)
    dt = float(settings.get("dt") or (t[1] - t[0]))
    window = max(loop_window(run.design, run.loaded.spec, float(t[-1] - t[0])), 2.0 * period)
    names = tuple(getattr(sim, "input_names", ()) or ()) or tuple(f"u{j + 1}" for j in range(u.shape[1]))
    switching = [measure(names[j], t, u[:, j], window, period) for j in range(u.shape[1])]
    return {
        "steady_error": _steady(t, e, xd),
        "chatter_rms": max(m.switching_rms for m in switching),
        "chatter_peak": max(m.switching_peak for m in switching),
        "reversal_rate": max(m.rate for m in switching),
        "command_rms": max(_rms(u[:, j]) for j in range(u.shape[1])),
        "sampling_period": period,
        "dt": dt,
    }
