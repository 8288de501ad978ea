"""Question 1: how well does the controller perform, and how to characterize its performance."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, fmt_percent, quantity
from designkit.studies.arm.run import commanded_moves, error_floors, motion_scales, relative_to_moves

__all__ = ["CoordinateError", "TorquePeak", "Tracking", "measure_tracking", "step_metrics", "tracking_sentences"]

STATIC_FRACTION = 0.5
"""A final error above this fraction of the peak error is a static error the loop does not remove."""

@dataclass(frozen=True)
class CoordinateError:
    """Tracking error of one tracked coordinate.

    Parameters
    ----------
    name, unit : str
        Coordinate (``q1``, ``x``) and unit (``rad``, ``m``).
    move : float
        Commanded step, or the largest excursion of the reference from its start (unit).
    peak, peak_at : float
        Largest ``|e|`` (unit) and when (s).
    rms, final : float
        RMS of ``e`` over the run and ``|e|`` at its last instant (unit).
    """

    name: str
    unit: str
    move: float
    peak: float
    peak_at: float
    rms: float
    final: float


@dataclass(frozen=True)
class TorquePeak:
    """Peak ``|u|`` commanded to one joint (N*m or N) and when (s)."""

    name: str
    unit: str
    peak: float
    at: float


@dataclass(frozen=True)
class Tracking:
    """How well the controller tracks (question 1).

    Parameters
    ----------
    kind : str
        ``"step"`` or ``"trajectory"``.
    coordinates : tuple of CoordinateError
    torques : tuple of TorquePeak
    overshoot : float or None
        Worst overshoot over the moving coordinates (%), step runs only.
    settling_time : float or None
        Worst 2 % settling time (s), step runs only.
    finite : bool
        Whether the run stayed finite.
    sentences : tuple of str
    """

    kind: str
    coordinates: tuple[CoordinateError, ...]
    torques: tuple[TorquePeak, ...]
    overshoot: float | None
    settling_time: float | None
    finite: bool
    sentences: tuple[str, ...]


def step_metrics(sim: Any) -> tuple[float | None, float | None, int | None]:
    from designkit.verification.time_domain import response_metrics

    if sim.kind != "step":
        return None, None, None
    with np.errstate(all="ignore"):
        m = response_metrics(sim)
    return m.overshoot, m.settling_time, m.worst_joint.get("overshoot")


def measure_tracking(sim: Any, plant: Any) -> Tracking:
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.tracking_errors, dtype=float)
    u = np.asarray(sim.u_command, dtype=float).reshape(t.size, -1)
    names, units = tuple(sim.coordinate_names), tuple(sim.coordinate_units)
    input_units = tuple(s.unit for s in plant.inputs)
    finite = bool(np.all(np.isfinite(e)) and np.all(np.isfinite(u)))
    moves = commanded_moves(sim)
    if not finite:
        return Tracking(sim.kind, (), (), None, None, False, (
            "The simulated run is not finite (the loop diverged): tracking cannot be characterized.",))
    a = np.abs(e)
    k = np.argmax(a, axis=0)
    coords = tuple(CoordinateError(names[c], units[c], float(moves[c]), float(a[k[c], c]), float(t[k[c]]),
                                   float(np.sqrt(np.mean(e[:, c] ** 2))), float(a[-1, c])) for c in range(e.shape[1]))
    ku = np.argmax(np.abs(u), axis=0)
    torques = tuple(TorquePeak(sim.input_names[j], input_units[j], float(abs(u[ku[j], j])), float(t[ku[j]]))
                    for j in range(u.shape[1]))
    overshoot, settling, worst = step_metrics(sim)
    sentences = tracking_sentences(sim.kind, coords, torques, overshoot, settling, worst)
    return Tracking(sim.kind, coords, torques, overshoot, settling, True, sentences)


def tracking_sentences(kind: str, coords: Sequence[CoordinateError], torques: Sequence[TorquePeak],
                       overshoot: float | None = None, settling: float | None = None,
                       overshoot_coordinate: int | None = None) -> tuple[str, ...]:
    """Sentences on how well a run tracks, chosen from its numbers.

    Parameters
    ----------
    kind : str
        ``"step"`` or ``"trajectory"``.
    coords : sequence of CoordinateError
    torques : sequence of TorquePeak
    overshoot, settling : float or None
        Worst overshoot (%) and 2 % settling time (s) of a step run.
    overshoot_coordinate : int or None
        0-based coordinate of the worst overshoot.
    """
    out: list[str] = []
    units = [c.unit for c in coords]
    moves = np.array([c.move for c in coords])
    peaks = np.array([c.peak for c in coords])
    floors = error_floors(moves, units)
    if kind == "trajectory":
        rel = relative_to_moves(peaks, moves, units)
        c = coords[int(np.argmax(rel))]
        if np.all(peaks <= floors):
            share = f", {fmt_number(c.peak / c.move, 2)} of its move" if c.move > 0 else ""
            out.append(f"Every coordinate follows the reference to the integrator's precision: the largest |e| is "
                       f"{quantity(c.peak, c.unit, 3)} ({c.name}){share}.")
        else:
            share = (f", {fmt_percent(c.peak / c.move)} of its move of {quantity(c.move, c.unit, 3)}"
                     if c.move > 0 else "")
            out.append(f"The largest departure from the commanded motion is {quantity(c.peak, c.unit, 3)} on "
                       f"{c.name} at t = {fmt_number(c.peak_at, 3)} s{share}; its RMS over the run is "
                       f"{quantity(c.rms, c.unit, 3)}.")
            if c.final >= STATIC_FRACTION * c.peak:
                out.append(f"At the end of the run the error on {c.name} is still {quantity(c.final, c.unit, 3)} "
                           f"({fmt_percent(c.final / c.peak)} of its peak): a static error remains that the loop "
                           "does not remove.")
            elif c.final <= 0.01 * c.peak:
                out.append(f"The error on {c.name} decays to {quantity(c.final, c.unit, 3)} by the end of the run.")
            else:
                out.append(f"At the end of the run the error on {c.name} is {quantity(c.final, c.unit, 3)} "
                           f"({fmt_percent(c.final / c.peak)} of its peak).")
    else:
        parts = []
        if overshoot is not None:
            where = f" ({coords[overshoot_coordinate].name})" if overshoot_coordinate is not None and len(coords) > 1 \
                else ""
            parts.append(f"overshoots by {fmt_number(overshoot, 3)} "
                         f"%{where}" if overshoot > 0 else "does not overshoot")
        parts.append(f"settles within the 2 % band in {fmt_number(settling, 3)} s" if settling is not None
                     else "does not settle within the 2 % band by the end of the run")
        out.append("The step response " + " and ".join(parts) + ".")
        finals = np.array([c.final for c in coords])
        k = int(np.argmax(relative_to_moves(finals, moves, units)))
        c = coords[k]
        if c.final <= 1e-3 * motion_scales(moves, units)[k]:
            out.append("At the end of the run every coordinate is at its command (largest |e| "
                       f"{quantity(c.final, c.unit, 3)}, "
                       f"{c.name}).")
        else:
            out.append(f"At the end of the run {c.name} is still {quantity(c.final, c.unit, 3)} from its command.")
        resting = [c for c in coords if c.move == 0 and c.peak > 0]
        for c in resting:
            out.append(f"{c.name}, commanded to stay where it is, is pushed {quantity(c.peak, c.unit, 3)} away (t = "
                       f"{fmt_number(c.peak_at, 3)} s) by the other joints' motion.")
    for unit in dict.fromkeys(tq.unit for tq in torques):  # torques (N*m) and forces (N) apart
        j = max((tq for tq in torques if tq.unit == unit), key=lambda tq: tq.peak)
        what = "force" if unit == "N" else "torque"
        out.append(f"The largest {what} is {quantity(j.peak, j.unit, 3)} on {j.name} at t = {fmt_number(j.at, 3)} s.")
    return tuple(out)
