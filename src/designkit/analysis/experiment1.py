"""The lab questions of the notes' simulation experiment 1 (appendix A), answered from one run.

The notes ask, for a controller on a manipulator: how well does it perform and how to
characterize performance; what does each gain do and how do gain variations influence
performance; what is the influence of the configuration and of the mass parameters; how
effective is it in neutralizing the intercouplings, centripetal and Coriolis forces.
:func:`lab_answers` answers them for a :class:`~designkit.pipeline.PipelineResult` of a robot
plant, with numbers measured on that run and sentences generated from those numbers (which
gain matters most, whether a coupling is negligible or dominant, whether an error is static...
are decided by the numbers, never written in advance).

What is computed (SI units: s, rad or m, N*m or N, kg*m^2 or kg):

1. **Tracking**: per tracked coordinate (joints, or end-effector coordinates of a task-space
   design) the peak, RMS and final ``|e|``, ``e = x - xD``; per joint the peak ``|u|`` commanded;
   for a step run the overshoot and settling time of
   :func:`~designkit.verification.time_domain.response_metrics`.
2. **Gains**: every gain of ``design.gains`` scaled by 0.5 and 2 (all joints at once), everything
   else equal, re-simulated on the true plant (``build(spec, replace(design, gains=...))``; the
   family's law reads the gains from the design).  The error measure is the peak ``|e|`` for a
   trajectory (the departure from the commanded motion) and the RMS ``|e|`` for a step (the peak
   of a step run is the step itself); with several coordinates each is taken relative to its move.
   Each scaled loop is also linearized on the true plant at the design's operating point (its
   slowest pole).  A run whose state is not finite, whose linearized loop has a pole with
   ``Re > 0``, or whose error over its last :data:`TAIL_FRACTION` exceeds :data:`DIVERGENCE_FACTOR`
   times the nominal peak error or the move, is reported as destabilizing the loop.  Bounded:
   skipped (and said so) above :data:`MAX_JOINTS` joints or when the re-simulations are estimated
   above :data:`STUDY_BUDGET_S` s of interpreted evaluation (the simulator's own estimate,
   :mod:`designkit.simulation.run`; each scaled law is a new step function run once, so it is
   evaluated interpreted when ``numerics.compile`` is ``auto``).
3. **Configuration**: along the simulated joint path the diagonal ``D_ii(q)`` of the true plant's
   inertia matrix, per joint its range and ratio.  For a design with per-joint loops (designed on
   the simplified link at one configuration ``q*``) the poles of each joint loop at the ends of
   that range (``tau_i = D_ii/f_i`` scales with ``D_ii``); for a model-based design (no loops, an
   ``error_poles`` check) that check's evidence.
4. **Intercoupling**: along the path, with ``qdd`` from finite differences of the simulated
   velocities (``numpy.gradient``), per joint the off-diagonal inertia torque
   ``sum_{j != i} D_ij qdd_j`` plus the Coriolis and centrifugal torque
   ``ID(q, qd, 0) - g(q) - F(qd)`` (the true plant's), against the joint's own inertial torque
   ``D_ii qdd_i``; for a model-based design the **model error torque** ``ID_true(q, qd, qdd) -
   ID_model(q, qd, qdd)`` it does not cancel (zero for an exact model).
5. **Mass parameters**: the evidence of the checks that vary them (``tracking_bounds``,
   ``robust_grid``) and the parameters on which the controller's model differs from the plant.

Everything here is a pure function of the result: the re-simulations are deterministic, so the
same run gives the same answers.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "Configuration",
    "CoordinateError",
    "Coupling",
    "GainEffect",
    "GainRun",
    "GainStudy",
    "JointCoupling",
    "JointInertia",
    "LabAnswers",
    "TorquePeak",
    "Tracking",
    "configuration_sentences",
    "coupling_level",
    "coupling_sentences",
    "coupling_torques",
    "gain_sentence",
    "lab_answers",
    "model_error_torque",
    "nature_of",
    "study_sentences",
    "tracking_sentences",
]

SCALES = (0.5, 2.0)
"""Factors applied to each gain (all joints at once) in the gain study."""
MAX_JOINTS = 6
"""No gain study above this many joints."""
STUDY_BUDGET_S = 6.0
"""No gain study when its re-simulations are estimated above this (s of interpreted CasADi evaluation)."""
DIVERGENCE_FACTOR = 10.0
"""A run diverges when its error over the last :data:`TAIL_FRACTION` exceeds this times max(nominal peak, move)."""
TAIL_FRACTION = 0.1
"""Final fraction of a run inspected for divergence."""
NEGLIGIBLE_ERROR = 1e-6
"""An error below this fraction of the coordinate's move is at integrator precision."""
NEGLIGIBLE_COUPLING = 0.05
"""Coupling below this fraction of the joint's own inertial torque is negligible."""
MODERATE_COUPLING = 0.3
"""Coupling up to this fraction of the joint's own inertial torque is moderate (significant beyond)."""
DOMINANT_COUPLING = 1.0
"""Coupling above this fraction of the joint's own inertial torque dominates it."""
STATIC_FRACTION = 0.5
"""A final error above this fraction of the peak error is a static error the loop does not remove."""
SMALL_CHANGE = 0.02
"""Relative changes below this are "unchanged" in the gain sentences."""
MAX_PATH_SAMPLES = 20000
"""At most this many instants of the path are evaluated (every k-th sample beyond)."""

_VERBS = {0.5: "halving", 2.0: "doubling"}


# ----------------------------------------------------------------------------- values


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


@dataclass(frozen=True)
class GainRun:
    """One run of the gain study.

    Parameters
    ----------
    scale : float
        Factor applied to the gain (1: the pipeline's own run).
    status : str
        ``"ok"``, ``"non-finite"`` (the simulated state overflowed), ``"unstable"`` (the loop linearized at
        the design's operating point has a pole with ``Re > 0``), ``"diverging"`` (the error at the end of
        the run is :data:`DIVERGENCE_FACTOR` times the nominal peak or the move) or ``"failed"`` (not
        simulated); ``detail`` says why.
    detail : str
        Why the run is not ``"ok"``.
    peak_error, rms_error, final_error : tuple of float
        Per tracked coordinate (its unit): peak, RMS and last ``|e|``; empty when not simulated to the end.
    peak_torque : float or None
        Peak ``|u|`` (N*m or N) of input ``torque_input`` (0-based; the input with the largest peak in the
        nominal run, so that the runs compare the same joint), named ``peak_torque_input``, unit
        ``peak_torque_unit``.
    peak_torque_input, peak_torque_unit : str
    overshoot, settling_time : float or None
        Step runs: worst overshoot (%) and settling time (s).
    torque_input : int
    abscissa : float or None
        Largest real part of the poles of the loop (true plant and this run's law) linearized at the
        design's operating point (1/s; None when there is none or no equilibrium).
    """

    scale: float
    status: str
    detail: str = ""
    peak_error: tuple[float, ...] = ()
    rms_error: tuple[float, ...] = ()
    final_error: tuple[float, ...] = ()
    peak_torque: float | None = None
    peak_torque_input: str = ""
    peak_torque_unit: str = ""
    overshoot: float | None = None
    settling_time: float | None = None
    torque_input: int = 0
    abscissa: float | None = None

    @property
    def ok(self) -> bool:
        """Whether the loop stayed stable in this run."""
        return self.status == "ok"


@dataclass(frozen=True)
class GainEffect:
    """What one gain does (question 2).

    Parameters
    ----------
    name, unit, meaning : str
        The gain as the design names it.
    runs : tuple of GainRun
        Scales 0.5, 1 and 2, in that order.
    ratios : tuple of (float, float or None)
        Per scale other than 1: the factor the error measure is multiplied by (None: destabilized).
    sensitivity : float
        Largest ``|ln ratio|`` over the scales (``inf`` when a scale destabilizes the loop).
    sentence : str
    """

    name: str
    unit: str
    meaning: str
    runs: tuple[GainRun, ...]
    ratios: tuple[tuple[float, float | None], ...]
    sensitivity: float
    sentence: str


@dataclass(frozen=True)
class GainStudy:
    """Every gain scaled by 0.5 and 2 (question 2).

    Parameters
    ----------
    measure : str
        The error measure compared (``"peak |e|"`` or ``"RMS |e|"``).
    coordinates, units : tuple of str
        The tracked coordinates of the error columns and their units.
    effects : tuple of GainEffect
    most_sensitive : str or None
        The gain the error measure is most sensitive to.
    sentences : tuple of str
        Summary (or why the study was skipped).
    skipped : str
        Why the study was not run ("" when it was).
    """

    measure: str
    coordinates: tuple[str, ...]
    units: tuple[str, ...]
    effects: tuple[GainEffect, ...]
    most_sensitive: str | None
    sentences: tuple[str, ...]
    skipped: str = ""


@dataclass(frozen=True)
class JointInertia:
    """The inertia ``D_ii`` a joint sees along the motion (question 3).

    Parameters
    ----------
    joint : int
        1-based.
    unit : str
        ``kg*m^2`` (revolute) or ``kg`` (prismatic).
    low, high : float
        Smallest and largest ``D_ii`` along the path, ``low_at``, ``high_at`` when (s).
    ratio : float
        ``high / low``.
    design_value : float or None
        ``D_ii(q*)`` the joint loop was designed for (per-joint loop designs).
    design_poles, poles_at_low, poles_at_high : tuple of complex
        The joint loop's poles at ``D_ii(q*)`` and at the ends of the range (1/s; empty when not applicable).
    """

    joint: int
    unit: str
    low: float
    low_at: float
    high: float
    high_at: float
    ratio: float
    design_value: float | None = None
    design_poles: tuple[complex, ...] = ()
    poles_at_low: tuple[complex, ...] = ()
    poles_at_high: tuple[complex, ...] = ()


@dataclass(frozen=True)
class Configuration:
    """Influence of the configuration (question 3): ``joints`` and the generated ``sentences``."""

    joints: tuple[JointInertia, ...]
    sentences: tuple[str, ...]


@dataclass(frozen=True)
class JointCoupling:
    """Torques left to the controller at one joint along the path (question 4), peaks of ``|.|`` (N*m or N).

    Parameters
    ----------
    joint : int
        1-based.
    unit : str
    off_diagonal, coriolis : float
        ``sum_{j != i} D_ij qdd_j`` and the Coriolis and centrifugal torque.
    coupling, coupling_at : float
        Their sum, and when it peaks (s).
    own_inertial : float
        ``D_ii qdd_i``.
    ratio : float
        ``coupling / own_inertial`` (``inf`` when the joint has no inertial torque of its own).
    model_error : float or None
        ``ID_true - ID_model`` (model-based designs only).
    """

    joint: int
    unit: str
    off_diagonal: float
    coriolis: float
    coupling: float
    coupling_at: float
    own_inertial: float
    ratio: float
    model_error: float | None = None


@dataclass(frozen=True)
class Coupling:
    """Intercoupling, centripetal and Coriolis torques (question 4).

    Parameters
    ----------
    joints : tuple of JointCoupling
    stride : int
        Every ``stride``-th instant of the run was evaluated.
    sentences : tuple of str
    """

    joints: tuple[JointCoupling, ...]
    stride: int
    sentences: tuple[str, ...]


@dataclass(frozen=True)
class LabAnswers:
    """The answers to the lab questions of experiment 1 for one run.

    Parameters
    ----------
    controller : str
        The family's label.
    nature : str
        ``"per-joint loops"`` (designed joint by joint on simplified links), ``"model-based"``
        (cancels the model's dynamics; its error poles are checked along the path) or ``"other"``;
        decided from the design and the checks, not from the family's kind.
    tracking : Tracking
    gains : GainStudy
    configuration : Configuration
    mass : tuple of str
        Sentences on the influence of the mass parameters.
    coupling : Coupling
    """

    controller: str
    nature: str
    tracking: Tracking
    gains: GainStudy
    configuration: Configuration
    mass: tuple[str, ...]
    coupling: Coupling


# ----------------------------------------------------------------------------- formatting


def _n(x: float | None, digits: int = 3) -> str:
    """``x`` with ``digits`` significant digits ("—" for None)."""
    if x is None:
        return "—"
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "∞" if x > 0 else "-∞"
    return "0" if x == 0 else f"{x:.{digits}g}"


def _u(unit: str) -> str:
    return unit.replace("*", "·")


def _q(x: float, unit: str, digits: int = 3) -> str:
    return f"{_n(x, digits)} {_u(unit)}".rstrip()


def _poles(poles: Sequence[complex]) -> str:
    out = []
    for p in sorted(poles, key=lambda z: (z.real, z.imag)):
        if abs(p.imag) <= 1e-9 * max(1.0, abs(p)):
            out.append(_n(p.real))
        elif p.imag > 0:
            out.append(f"{_n(p.real)} ± {_n(p.imag)}j")
    return "(" + ", ".join(out) + ")"


def _percent(ratio: float) -> str:
    return "∞" if not math.isfinite(ratio) else f"{100 * ratio:.3g} %"


# ----------------------------------------------------------------------------- 1. tracking


def _moves(sim: Any) -> np.ndarray:
    xd = np.asarray(sim.desired, dtype=float)
    if sim.kind == "step":
        return np.abs(xd[-1] - np.asarray(sim.tracked_positions, dtype=float)[0])
    return np.max(np.abs(xd - xd[0]), axis=0)


def _scales(moves: np.ndarray, units: Sequence[str]) -> np.ndarray:
    """The size of each coordinate's motion (its unit): its move, or for a coordinate that does not move itself
    the largest move in the same unit (1 when none moves)."""
    out = np.empty(len(moves))
    for c, m in enumerate(moves):
        same = [moves[k] for k in range(len(moves)) if units[k] == units[c] and np.isfinite(moves[k])]
        scale = m if np.isfinite(m) and m > 0 else max(same, default=0.0)
        out[c] = scale if scale > 0 else 1.0
    return out


def _floors(moves: np.ndarray, units: Sequence[str]) -> np.ndarray:
    """Errors below these (per coordinate) are at the integrator's precision: :data:`NEGLIGIBLE_ERROR` of
    :func:`_scales`."""
    return NEGLIGIBLE_ERROR * _scales(moves, units)


def _step_metrics(sim: Any) -> tuple[float | None, float | None, int | None]:
    from designkit.verification.time_domain import response_metrics

    if sim.kind != "step":
        return None, None, None
    with np.errstate(all="ignore"):
        m = response_metrics(sim)
    return m.overshoot, m.settling_time, m.worst_joint.get("overshoot")


def _relative(peaks: np.ndarray, moves: np.ndarray, units: Sequence[str]) -> np.ndarray:
    return peaks / _scales(moves, units)


def _tracking(sim: Any, plant: Any) -> Tracking:
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.tracking_errors, dtype=float)
    u = np.asarray(sim.u_command, dtype=float).reshape(t.size, -1)
    names, units = tuple(sim.coordinate_names), tuple(sim.coordinate_units)
    input_units = tuple(s.unit for s in plant.inputs)
    finite = bool(np.all(np.isfinite(e)) and np.all(np.isfinite(u)))
    moves = _moves(sim)
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
    overshoot, settling, worst = _step_metrics(sim)
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
    floors = _floors(moves, units)
    if kind == "trajectory":
        rel = _relative(peaks, moves, units)
        c = coords[int(np.argmax(rel))]
        if np.all(peaks <= floors):
            share = f", {_n(c.peak / c.move, 2)} of its move" if c.move > 0 else ""
            out.append(f"Every coordinate follows the reference to the integrator's precision: the largest |e| is "
                       f"{_q(c.peak, c.unit)} ({c.name}){share}.")
        else:
            share = f", {_percent(c.peak / c.move)} of its move of {_q(c.move, c.unit)}" if c.move > 0 else ""
            out.append(f"The largest departure from the commanded motion is {_q(c.peak, c.unit)} on {c.name} at "
                       f"t = {_n(c.peak_at)} s{share}; its RMS over the run is {_q(c.rms, c.unit)}.")
            if c.final >= STATIC_FRACTION * c.peak:
                out.append(f"At the end of the run the error on {c.name} is still {_q(c.final, c.unit)} "
                           f"({_percent(c.final / c.peak)} of its peak): a static error remains that the loop "
                           "does not remove.")
            elif c.final <= 0.01 * c.peak:
                out.append(f"The error on {c.name} decays to {_q(c.final, c.unit)} by the end of the run.")
            else:
                out.append(f"At the end of the run the error on {c.name} is {_q(c.final, c.unit)} "
                           f"({_percent(c.final / c.peak)} of its peak).")
    else:
        parts = []
        if overshoot is not None:
            where = f" ({coords[overshoot_coordinate].name})" if overshoot_coordinate is not None and len(coords) > 1 \
                else ""
            parts.append(f"overshoots by {_n(overshoot)} %{where}" if overshoot > 0 else "does not overshoot")
        parts.append(f"settles within the 2 % band in {_n(settling)} s" if settling is not None
                     else "does not settle within the 2 % band by the end of the run")
        out.append("The step response " + " and ".join(parts) + ".")
        finals = np.array([c.final for c in coords])
        k = int(np.argmax(_relative(finals, moves, units)))
        c = coords[k]
        if c.final <= 1e-3 * _scales(moves, units)[k]:
            out.append(f"At the end of the run every coordinate is at its command (largest |e| {_q(c.final, c.unit)}, "
                       f"{c.name}).")
        else:
            out.append(f"At the end of the run {c.name} is still {_q(c.final, c.unit)} from its command.")
        resting = [c for c in coords if c.move == 0 and c.peak > 0]
        for c in resting:
            out.append(f"{c.name}, commanded to stay where it is, is pushed {_q(c.peak, c.unit)} away (t = "
                       f"{_n(c.peak_at)} s) by the other joints' motion.")
    for unit in dict.fromkeys(tq.unit for tq in torques):  # torques (N*m) and forces (N) apart
        j = max((tq for tq in torques if tq.unit == unit), key=lambda tq: tq.peak)
        what = "force" if unit == "N" else "torque"
        out.append(f"The largest {what} is {_q(j.peak, j.unit)} on {j.name} at t = {_n(j.at)} s.")
    return tuple(out)


# ----------------------------------------------------------------------------- 2. gains


def _run_record(sim: Any, scale: float, nominal: GainRun | None, scales: np.ndarray, input_units: Sequence[str],
                abscissa: float | None = None, pole_size: float = 1.0) -> GainRun:
    """The measures of one run; ``scales`` (per coordinate, see :func:`_scales`) bound a diverging error,
    ``abscissa`` (1/s) is the largest real part of its linearized loop's poles, ``pole_size`` their scale."""
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.tracking_errors, dtype=float)
    u = np.asarray(sim.u_command, dtype=float).reshape(t.size, -1)
    if not (np.all(np.isfinite(e)) and np.all(np.isfinite(u)) and np.all(np.isfinite(sim.state))):
        return GainRun(scale, "non-finite", "the simulated state is not finite", abscissa=abscissa)
    a = np.abs(e)
    peak = np.max(a, axis=0)
    tail = a[t >= t[-1] - TAIL_FRACTION * (t[-1] - t[0])]
    c = int(np.argmax(np.max(tail, axis=0) / scales))
    end = f"{sim.coordinate_names[c]}'s error is {_q(float(np.max(tail[:, c])), sim.coordinate_units[c])} at the end"
    if abscissa is not None and abscissa > 1e-9 * pole_size:
        return GainRun(scale, "unstable", f"its loop linearized at the design's operating point has a pole at "
                       f"Re = {_n(abscissa)} 1/s; {end}", abscissa=abscissa)
    if nominal is not None and nominal.peak_error:
        bound = DIVERGENCE_FACTOR * np.maximum(np.asarray(nominal.peak_error), scales)
        grown = np.flatnonzero(np.max(tail, axis=0) > bound)
        if grown.size:
            c = int(grown[0])
            return GainRun(scale, "diverging", f"{sim.coordinate_names[c]}'s error reaches "
                           f"{_q(float(np.max(tail[:, c])), sim.coordinate_units[c])} at the end of the run",
                           abscissa=abscissa)
    torques = np.max(np.abs(u), axis=0)
    j = nominal.torque_input if nominal is not None else int(np.argmax(torques))
    overshoot, settling, _ = _step_metrics(sim)
    return GainRun(scale, "ok", "", tuple(float(v) for v in peak), tuple(float(v) for v in np.sqrt(np.mean(e**2, 0))),
                   tuple(float(v) for v in a[-1]), float(torques[j]), sim.input_names[j], input_units[j], overshoot,
                   settling, j, abscissa)


def _scaled(value: Any, scale: float) -> Any:
    return value * scale if isinstance(value, float) else np.asarray(value, dtype=float) * scale


def _values(run: GainRun, measure: str) -> np.ndarray:
    return np.asarray(run.peak_error if measure == "peak" else run.rms_error, dtype=float)


def _aggregate(run: GainRun, measure: str, scales: np.ndarray) -> float:
    """The error measure of a run over all coordinates, each relative to its move (dimensionless): the largest
    relative peak, or the root mean square of the relative RMS errors."""
    rel = _values(run, measure) / scales
    return float(np.max(rel)) if measure == "peak" else float(np.sqrt(np.mean(rel**2)))


def _ratio(run: GainRun, nominal: GainRun, measure: str, scales: np.ndarray) -> float | None:
    """Factor on the error measure against the nominal run (None: the run is not stable)."""
    if not run.ok or not nominal.ok:
        return None
    return max(_aggregate(run, measure, scales), NEGLIGIBLE_ERROR) / max(_aggregate(nominal, measure, scales),
                                                                         NEGLIGIBLE_ERROR)


def gain_sentence(name: str, meaning: str, measure: str, runs: Sequence[GainRun],
                  ratios: Sequence[tuple[float, float | None]]) -> str:
    """One sentence on what scaling gain ``name`` did, chosen from the numbers.

    Parameters
    ----------
    name, meaning : str
        The gain and its role.
    measure : str
        The error measure in words (``"peak |e|"``).
    runs : sequence of GainRun
        Scales 0.5, 1, 2 (the nominal run has scale 1).
    ratios : sequence of (scale, ratio or None)
        The factor on the error measure for each scale other than 1 (None: the loop was not stable).

    Examples
    --------
    >>> runs = (GainRun(0.5, "ok"), GainRun(1.0, "ok"), GainRun(2.0, "ok"))
    >>> gain_sentence("K1", "proportional", "peak |e|", runs, [(0.5, 3.1), (2.0, 0.4)])
    'K1, proportional: halving it multiplies the peak |e| by 3.1; doubling it multiplies it by 0.4; so raising K1 lowers the peak |e|.'
    """  # noqa: E501
    nominal = next(r for r in runs if r.scale == 1.0)
    by_scale = {r.scale: r for r in runs}
    parts = []
    named = False  # the measure is named once, then "it"
    for scale, ratio in ratios:
        run = by_scale[scale]
        verb = _VERBS.get(scale, f"scaling it by {scale:g}")
        if ratio is None:
            word = "could not be simulated" if run.status == "failed" else "destabilizes the loop"
            parts.append(f"{verb} it {word} ({run.detail or run.status})")
            continue
        obj = "it" if named else f"the {measure}"
        named = True
        if abs(ratio - 1.0) < SMALL_CHANGE:
            text = f"{verb} it leaves {obj} practically unchanged (×{_n(ratio, 3)})"
        else:
            text = f"{verb} it multiplies {obj} by {_n(ratio, 2)}"
        parts.append(text + _side_effects(run, nominal))
    sentence = f"{name}, {meaning}: " + "; ".join(parts)
    finite = dict(ratios)
    lo, hi = finite.get(0.5), finite.get(2.0)
    if lo is not None and hi is not None and max(abs(lo - 1), abs(hi - 1)) >= SMALL_CHANGE:
        if lo > 1 > hi:
            sentence += f"; so raising {name} lowers the {measure}"
        elif lo < 1 < hi:
            sentence += f"; so lowering {name} lowers the {measure}"
        elif lo >= 1 and hi >= 1:
            sentence += f"; the designed value gives the smallest {measure} of the three"
        else:
            sentence += f"; both changes lower the {measure}"
    return sentence + "."


def _side_effects(run: GainRun, nominal: GainRun) -> str:
    """What else changed noticeably: overshoot (0.5 point), settling time and peak torque (5 %)."""
    extras = []
    if run.overshoot is not None and nominal.overshoot is not None and abs(run.overshoot - nominal.overshoot) >= 0.5:
        extras.append(f"overshoot {_n(nominal.overshoot)} % → {_n(run.overshoot)} %")
    if (run.settling_time is None) != (nominal.settling_time is None):
        extras.append("no longer settles within the run" if run.settling_time is None
                      else f"now settles in {_n(run.settling_time)} s")
    elif run.settling_time is not None and nominal.settling_time and \
            abs(run.settling_time / nominal.settling_time - 1) >= 0.05:
        extras.append(f"settling time {_n(nominal.settling_time)} s → {_n(run.settling_time)} s")
    if run.abscissa is not None and nominal.abscissa and abs(run.abscissa / nominal.abscissa - 1) >= 0.05:
        extras.append(f"slowest pole Re {_n(nominal.abscissa)} → {_n(run.abscissa)} 1/s")
    if run.peak_torque is not None and nominal.peak_torque and abs(run.peak_torque / nominal.peak_torque - 1) >= 0.05:
        extras.append(f"peak |{run.peak_torque_input}| {_n(nominal.peak_torque)} → "
                      f"{_q(run.peak_torque, run.peak_torque_unit)}")
    return f" ({'; '.join(extras)})" if extras else ""


def study_sentences(measure: str, effects: Sequence[GainEffect], negligible: bool = False,
                    floor_text: str = "") -> tuple[str, ...]:
    """Which gains destabilize the loop, and which the error measure is most and least sensitive to.

    Parameters
    ----------
    measure : str
        The error measure in words.
    effects : sequence of GainEffect
    negligible : bool
        Every run tracked to the integrator's precision (``floor_text`` says below what).
    """
    if not effects:
        return ("The design has no gains to vary.",)
    out = []
    unstable = [e for e in effects if not math.isfinite(e.sensitivity)]
    for e in unstable:
        bad = [_VERBS.get(s, f"scaling by {s:g}") for s, r in e.ratios if r is None]
        out.append(f"{' or '.join(bad).capitalize()} {e.name} destabilizes the loop.")
    stable = [e for e in effects if math.isfinite(e.sensitivity)]
    if negligible and not unstable:
        out.append(f"With every gain halved or doubled the tracking error stays at the integrator's precision "
                   f"({floor_text}): the model cancels the dynamics, and the gains act only on what it does not "
                   "cancel (initial errors, disturbances, model errors), of which this run has none.")
        return tuple(out)
    if not stable:
        return tuple(out)
    ranked = sorted(stable, key=lambda e: -e.sensitivity)
    top, low = ranked[0], ranked[-1]
    if top.sensitivity < math.log1p(SMALL_CHANGE):
        out.append(f"No gain changes the {measure} by more than {100 * SMALL_CHANGE:g} % when halved or doubled.")
        return tuple(out)

    def factors(e: GainEffect) -> str:
        return ", ".join(f"×{_n(r, 2)} {'halved' if s == 0.5 else 'doubled' if s == 2.0 else f'at {s:g}'}"
                         for s, r in e.ratios if r is not None)

    head = "Of the gains that keep the loop stable, the" if unstable else "The"
    text = f"{head} {measure} is most sensitive to {top.name} ({factors(top)})"
    if len(ranked) > 1:
        text += f" and least to {low.name} ({factors(low)})"
    out.append(text + ".")
    return tuple(out)


def _abscissa(plant: Any, law: Any, op: Any) -> float | None:
    """Largest real part (1/s) of the poles of ``plant`` with ``law`` linearized at the operating point ``op``
    (None without an operating point or an equilibrium near it)."""
    from designkit.synthesis.closed_loop import linearize

    if not op:
        return None
    try:
        poles = linearize(plant, law, op["r"], z0=[*op["x"], *op["xc"]])[0].poles
    except (ValueError, RuntimeError):
        return None
    return float(np.max(np.real(poles))) if np.size(poles) else None


def _gain_study(result: Any, plant: Any, nominal_sim: Any) -> GainStudy:
    from designkit.errors import DesignkitError
    from designkit.families import family
    from designkit.simulation.run import build

    design, spec = result.design, result.loaded.spec
    names, units = tuple(nominal_sim.coordinate_names), tuple(nominal_sim.coordinate_units)
    step = nominal_sim.kind == "step"
    measure, key = ("RMS |e|", "rms") if step else ("peak |e|", "peak")
    if len(names) > 1:
        measure += " relative to the move"
    moves = _moves(nominal_sim)
    scales = _scales(moves, units)
    floors = NEGLIGIBLE_ERROR * scales
    input_units = tuple(s.unit for s in plant.inputs)
    op = design.operating_point
    pole_size = max((abs(p) for p in design.closed_loop.poles), default=1.0) if design.closed_loop else 1.0
    law = family(design.kind).law(design, spec.simulation.anti_windup)
    nominal = _run_record(nominal_sim, 1.0, None, scales, input_units, _abscissa(plant, law, op), pole_size)

    def skipped(reason: str) -> GainStudy:
        return GainStudy(measure, names, units, (), None, (f"Gain study skipped: {reason}.",), reason)

    if plant.n_joints > MAX_JOINTS:
        return skipped(f"the arm has {plant.n_joints} joints, more than {MAX_JOINTS}")
    if not nominal.ok:
        return skipped(f"the design's own run is not stable ({nominal.detail})")
    gains = design.gains
    n_runs = len(gains) * len(SCALES)
    study_spec = spec
    if spec.numerics.compile == "auto":  # each scaled law is a new step, run once: compiling it would not pay
        study_spec = spec.model_copy(update={"numerics": spec.numerics.model_copy(update={"compile": "never"})})
    effects = []
    estimate_checked = False
    for name in gains:
        runs = {1.0: nominal}
        for scale in SCALES:
            scaled = dataclasses.replace(design, gains=gains.replace(**{name: _scaled(gains[name], scale)}))
            try:
                simulator = build(study_spec, scaled, plant=plant)
            except (DesignkitError, ValueError, RuntimeError) as exc:
                runs[scale] = GainRun(scale, "failed", str(exc).splitlines()[0])
                continue
            if not estimate_checked:
                estimate = float(simulator.compiled.get("interpreted_estimate_s", 0.0)) * n_runs
                if estimate > STUDY_BUDGET_S:
                    return skipped(f"its {n_runs} runs of {simulator.time.size - 1} steps are estimated at "
                                   f"{estimate:.3g} s, above the {STUDY_BUDGET_S:g} s budget")
                estimate_checked = True
            try:
                with np.errstate(all="ignore"):
                    sim = simulator.run()
            except (ValueError, RuntimeError) as exc:
                runs[scale] = GainRun(scale, "failed", str(exc).splitlines()[0])
                continue
            runs[scale] = _run_record(sim, scale, nominal, scales, input_units, _abscissa(plant, simulator.law, op),
                                      pole_size)
        ordered = tuple(runs[s] for s in sorted(runs))
        ratios = tuple((s, _ratio(runs[s], nominal, key, scales)) for s in SCALES)
        sensitivity = max(abs(math.log(r)) if r is not None else math.inf for _, r in ratios)
        meaning = gains.meaning(name) or "gain"
        effects.append(GainEffect(name, gains.unit(name), gains.meaning(name), ordered, ratios, sensitivity,
                                  gain_sentence(name, meaning, measure, ordered, ratios)))
    negligible = not step and all(np.all(_values(r, key) <= floors) for e in effects for r in e.runs if r.ok)
    floor_text = "below " + ", ".join(sorted({_q(f, u, 2) for f, u in zip(floors, units, strict=True)}))
    top = None
    if effects and (not negligible or any(math.isinf(e.sensitivity) for e in effects)):
        top = max(effects, key=lambda e: e.sensitivity).name
    return GainStudy(measure, names, units, tuple(effects), top, study_sentences(measure, effects, negligible,
                                                                                    floor_text))


# ----------------------------------------------------------------------------- path samples


@dataclass(frozen=True)
class _Path:
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    stride: int


def _path(sim: Any) -> _Path | None:
    t = np.asarray(sim.time, dtype=float)
    q = np.asarray(sim.state, dtype=float)[:, list(sim.positions)]
    qd = np.asarray(sim.state, dtype=float)[:, list(sim.velocities)]
    ok = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(qd), axis=1)
    end = int(np.argmin(ok)) if not np.all(ok) else t.size
    if end < 3:
        return None
    t, q, qd = t[:end], q[:end], qd[:end]
    qdd = np.gradient(qd, t, axis=0)
    stride = max(1, math.ceil(t.size / MAX_PATH_SAMPLES))
    return _Path(t[::stride], q[::stride], qd[::stride], qdd[::stride], stride)


def _inertia_unit(plant: Any, i: int) -> str:
    return "kg" if plant.inputs[i].unit == "N" else "kg*m^2"


# ----------------------------------------------------------------------------- 3. configuration


def _loop_poles(loop: Any, inertia_factor: float) -> tuple[complex, ...]:
    """Poles of a joint loop on its simplified link with ``tau`` scaled by ``inertia_factor`` (``tau = D/f``)."""
    ch = loop.characteristic
    if ch is None or "tau" not in ch.parameters:
        return ()
    theta = {p: loop.plant.parameter(p).value for p in ch.parameters}
    theta["tau"] = theta["tau"] * inertia_factor
    coeffs = [float(np.asarray(c)) for c in ch.coefficients(loop.gains, **theta)]
    return tuple(complex(r) for r in np.roots(coeffs))


def _configuration(result: Any, plant: Any, path: _Path | None, nature: str) -> Configuration:
    design = result.design
    if path is None:
        return Configuration((), ("The simulated path is not finite: the configuration's influence is not measured.",))
    M = np.asarray(plant.robot.mass_matrix(path.q, p=plant.model_parameters()), dtype=float)
    D = np.diagonal(M, axis1=1, axis2=2)
    joints = []
    star = design.extra.get("configuration") if nature == "per-joint loops" else None
    design_D = None
    if star is not None:
        links = design.extra.get("links")
        if links:
            design_D = [float(lk["inertia"]) for lk in links]
        else:
            Ms = design.plant.robot.mass_matrix(np.asarray(star, float), p=design.plant.model_parameters())
            design_D = np.diag(np.asarray(Ms, float)).tolist()
    for i in range(D.shape[1]):
        lo, hi = int(np.argmin(D[:, i])), int(np.argmax(D[:, i]))
        low, high = float(D[lo, i]), float(D[hi, i])
        extra: dict[str, Any] = {}
        if design_D is not None and i < len(design.loops):
            loop, d0 = design.loops[i], design_D[i]
            extra = {"design_value": d0, "design_poles": _loop_poles(loop, 1.0),
                     "poles_at_low": _loop_poles(loop, low / d0), "poles_at_high": _loop_poles(loop, high / d0)}
        joints.append(JointInertia(i + 1, _inertia_unit(plant, i), low, float(path.t[lo]), high, float(path.t[hi]),
                                   high / low if low > 0 else math.inf, **extra))
    sentences = list(configuration_sentences(joints))
    if nature == "per-joint loops":
        sentences += _loop_configuration_sentences(joints, star)
    elif nature == "model-based":
        sentences += _model_configuration_sentences(result, joints)
    return Configuration(tuple(joints), tuple(sentences))


def configuration_sentences(joints: Sequence[JointInertia]) -> tuple[str, ...]:
    """How much the inertia each joint sees varies along the motion (one sentence per joint)."""
    out = []
    for j in joints:
        if j.ratio - 1 <= 1e-9:
            out.append(f"The inertia joint {j.joint} sees does not depend on this motion "
                       f"(D_{j.joint}{j.joint} = {_q(j.low, j.unit, 4)} throughout).")
        elif j.ratio < 1.01:
            out.append(f"The inertia joint {j.joint} sees is practically constant along this motion "
                       f"(D_{j.joint}{j.joint} = {_q(j.low, j.unit, 4)}, within {_percent(j.ratio - 1)}).")
        else:
            out.append(f"The inertia joint {j.joint} sees varies by a factor {_n(j.ratio)} along this motion: "
                       f"D_{j.joint}{j.joint} from {_q(j.low, j.unit)} (t = {_n(j.low_at)} s) to "
                       f"{_q(j.high, j.unit)} (t = {_n(j.high_at)} s).")
    return tuple(out)


def _loop_configuration_sentences(joints: Sequence[JointInertia], star: Any) -> list[str]:
    out = []
    where = "(" + ", ".join(_n(v, 4) for v in star) + ")" if star is not None else "q*"
    for j in joints:
        if j.design_value is None:
            continue
        a, b = j.low / j.design_value, j.high / j.design_value
        text = (f"Joint {j.joint}'s loop was designed on its simplified link at q* = {where} for "
                f"D_{j.joint}{j.joint}(q*) = {_q(j.design_value, j.unit)}; ")
        if max(abs(a - 1), abs(b - 1)) < 0.01:
            out.append(text + "along the motion the inertia stays within 1 % of that value, so the loop keeps the "
                       "poles it was designed for.")
            continue
        text += (f"along the motion the inertia is {_n(a)}–{_n(b)} times that value, and so is the time constant "
                 f"tau_{j.joint} = D_{j.joint}{j.joint}/f_{j.joint} of the link the gains were computed for")
        if j.design_poles and j.poles_at_low and j.poles_at_high:
            ends = []
            if abs(a - 1) >= 0.01:
                ends.append(f"{_poles(j.poles_at_low)} 1/s at the lightest configuration")
            if abs(b - 1) >= 0.01:
                ends.append(f"{_poles(j.poles_at_high)} 1/s at the heaviest")
            stable = all(p.real < 0 for p in (*j.poles_at_low, *j.poles_at_high))
            text += (f": its poles move from the placed {_poles(j.design_poles)} 1/s to " + " and ".join(ends)
                     + (" (still stable)" if stable else ": the frozen loop is unstable there"))
        out.append(text + ".")
    return out


def _check(result: Any, name: str) -> Any:
    return next((c for c in result.checks if c.name == name), None)


def _model_configuration_sentences(result: Any, joints: Sequence[JointInertia]) -> list[str]:
    check = _check(result, "error_poles")
    if check is None:
        return []
    cert = check.certificate
    widest = max(joints, key=lambda j: j.ratio) if joints else None
    varies = (f", although D_{widest.joint}{widest.joint} varies by a factor {_n(widest.ratio)}"
              if widest is not None and widest.ratio >= 1.01 else "")
    label = _label(result)
    out = []
    instants = cert.get("instants")
    at = f" at {instants} instants" if instants else ""
    dimensionless = check.unit in ("", "1") or check.unit.startswith("1 ")
    evidence = (_n(check.achieved, 2) + ("" if dimensionless else f" {check.unit}")
                if isinstance(check.achieved, float) else "")
    if "damped_least_squares" in cert:
        dls = cert["damped_least_squares"]
        out.append(f"{label} cancels the configuration-dependent dynamics through its model, but its damped "
                   f"least-squares resolution moves the task-error poles by up to "
                   f"{_n(dls.get('largest_pole_move_1_per_s'))} 1/s along the path (t = {_n(dls.get('at_s'))} s), "
                   "where J is worst conditioned.")
    elif check.passed:
        out.append(f"{label} cancels the configuration-dependent dynamics through its model: on the model the "
                   f"error dynamics linearized{at} along the reference are the requested decoupled ones (the "
                   f"error_poles check: {evidence or 'passed'}, target {check.target}){varies}, so the "
                   "configuration does not change the designed error dynamics.")
    else:
        out.append(f"On the model the error dynamics leave the requested ones along the path (the error_poles "
                   f"check: {evidence or 'failed'}, target {check.target}): {check.detail}.")
    true = cert.get("true_plant")
    if true:
        move = float(true["largest_pole_move_1_per_s"])
        size = max((abs(complex(*p)) for p in cert.get("requested_poles", ())), default=1.0)
        text = f"On the true plant the model mismatch moves them by up to {_n(move)} 1/s (t = {_n(true.get('at_s'))} s)"
        if move < 1e-3 * size:
            text += (f", {_n(move / size, 2)} of their size: the mismatch shows as a torque the model misses "
                     "(below), not as a change of the error dynamics")
        else:
            text += ": along the path the configuration acts through what the model gets wrong"
        out.append(text + ".")
    return out


def _label(result: Any) -> str:
    """The label of the result's controller family (``"Computed torque"``)."""
    from designkit.families import family

    return family(result.design.kind).display.label


# ----------------------------------------------------------------------------- 4. coupling


def coupling_torques(plant: Any, q: Any, qd: Any, qdd: Any) -> dict[str, np.ndarray]:
    """The torques of the coupled dynamics at a batch of states, on ``plant`` (N*m or N per joint).

    Parameters
    ----------
    plant : RobotPlant
    q, qd, qdd : array_like, shape (N, n)
        Joint positions (rad or m), velocities and accelerations.

    Returns
    -------
    dict of ndarray, shape (N, n)
        ``own`` ``D_ii qdd_i``; ``off_diagonal`` ``sum_{j != i} D_ij qdd_j``; ``coriolis``
        ``ID(q, qd, 0) - g(q) - F(qd)`` (Coriolis and centrifugal, ``C(q, qd) qd``); ``coupling``
        ``off_diagonal + coriolis``.
    """
    robot, p = plant.robot, plant.model_parameters()
    q, qd, qdd = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (q, qd, qdd))
    M = np.asarray(robot.mass_matrix(q, p=p), dtype=float).reshape(q.shape[0], q.shape[1], q.shape[1])
    own = np.diagonal(M, axis1=1, axis2=2) * qdd
    off = np.einsum("kij,kj->ki", M, qdd) - own
    rest = np.asarray(robot.inverse_dynamics(q, qd, np.zeros_like(qdd), p=p), dtype=float).reshape(q.shape)
    gravity = np.asarray(robot.gravity_torque(q, p=p), dtype=float).reshape(q.shape)
    friction = np.asarray(robot.friction_torque(qd, p=p), dtype=float).reshape(q.shape)
    coriolis = rest - gravity - friction
    return {"own": own, "off_diagonal": off, "coriolis": coriolis, "coupling": off + coriolis}


def model_error_torque(plant: Any, model: Any, q: Any, qd: Any, qdd: Any) -> np.ndarray:
    """``ID_plant(q, qd, qdd) - ID_model(q, qd, qdd)``, shape (N, n) (N*m or N): the torque a controller
    that cancels ``model``'s dynamics leaves uncancelled on ``plant`` (zero for an exact model)."""
    q, qd, qdd = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (q, qd, qdd))
    true = plant.robot.inverse_dynamics(q, qd, qdd, p=plant.model_parameters())
    believed = model.robot.inverse_dynamics(q, qd, qdd, p=model.model_parameters())
    return (np.asarray(true, dtype=float) - np.asarray(believed, dtype=float)).reshape(q.shape)


def coupling_level(ratio: float) -> str:
    """The coupling of a joint in words, from ``coupling / own inertial torque``.

    >>> [coupling_level(r) for r in (0.01, 0.2, 0.6, 2.0, float("inf"))]
    ['negligible', 'moderate', 'significant', 'dominant', 'dominant']
    """
    if ratio < NEGLIGIBLE_COUPLING:
        return "negligible"
    if ratio <= MODERATE_COUPLING:
        return "moderate"
    if ratio <= DOMINANT_COUPLING:
        return "significant"
    return "dominant"


def coupling_sentences(joints: Sequence[JointCoupling], nature: str, label: str = "The controller",
                       intercoupling: Sequence[Any] = ()) -> tuple[str, ...]:
    """Sentences on the coupling torques, chosen from the numbers.

    Parameters
    ----------
    joints : sequence of JointCoupling
    nature : str
        ``"per-joint loops"``, ``"model-based"`` or ``"other"``.
    label : str
        The controller in words.
    intercoupling : sequence of dict
        The ``coupling`` check's ``intercoupling_error`` rows (``joint``, ``max_abs_rad``, ``at_s``), if any.
    """
    out = []
    for j in joints:
        level = coupling_level(j.ratio)
        own = (f"{_percent(j.ratio)} of its own inertial torque D_{j.joint}{j.joint} q̈_{j.joint} "
               f"(peak {_q(j.own_inertial, j.unit)})" if math.isfinite(j.ratio)
               else "while the joint has no inertial torque of its own (it does not accelerate by itself)")
        text = (f"At joint {j.joint} the intercoupling, centripetal and Coriolis torques reach "
                f"{_q(j.coupling, j.unit)} (t = {_n(j.coupling_at)} s; off-diagonal inertia "
                f"{_q(j.off_diagonal, j.unit)}, Coriolis and centrifugal {_q(j.coriolis, j.unit)}), {own}: {level}.")
        out.append(text)
    if not joints:
        return tuple(out)
    if nature == "model-based":
        errs = [j.model_error for j in joints if j.model_error is not None]
        if errs and max(errs) == 0:
            out.append(f"{label} computes them from its model, which is the plant here: they are cancelled "
                       "exactly (model error torque 0 at every joint).")
        elif errs:
            e = max((j for j in joints if j.model_error is not None), key=lambda j: j.model_error)
            share = e.model_error / e.coupling if e.coupling > 0 else math.inf
            text = (f"{label} cancels them through its model up to the model error torque ID_plant − ID_model, "
                    f"which reaches {_q(e.model_error, e.unit)} at joint {e.joint}, {_n(share)} times the coupling "
                    f"torque there")
            if share < NEGLIGIBLE_COUPLING:
                text += ": the coupling is cancelled almost exactly"
            elif share > 1:
                text += (": the model mismatch, not the coupling, is what the feedback e'' + K2 e' + K1 e has to "
                         "absorb")
            else:
                text += ": what is left acts as a disturbance on the error dynamics e'' + K2 e' + K1 e = 0"
            out.append(text + ".")
    elif nature == "per-joint loops":
        text = (f"{label} has no model of them: each joint's loop sees them as the perturbation xi_i of its "
                "simplified link and can only reject them by feedback")
        if intercoupling:
            r = max(intercoupling, key=lambda row: row["max_abs_rad"])
            text += (f"; the coupling check measures what gets through: joint {r['joint']} departs from its "
                     f"decoupled response by up to {_n(r['max_abs_rad'])} rad (t = {_n(r['at_s'])} s)")
        out.append(text + ".")
    return tuple(out)


def _coupling(result: Any, plant: Any, path: _Path | None, nature: str) -> Coupling:
    if path is None:
        return Coupling((), 1, ("The simulated path is not finite: the coupling torques are not measured.",))
    tq = coupling_torques(plant, path.q, path.qd, path.qdd)
    model_err = None
    if nature == "model-based":
        model_err = np.abs(model_error_torque(plant, result.design.plant, path.q, path.qd, path.qdd))
    joints = []
    size = float(np.max(np.abs(tq["own"]), initial=0.0))
    for i in range(path.q.shape[1]):
        c = np.abs(tq["coupling"][:, i])
        k = int(np.argmax(c))
        own = float(np.max(np.abs(tq["own"][:, i])))
        peak = float(c[k])
        moves_itself = own > NEGLIGIBLE_ERROR * max(size, peak)  # else its own acceleration is numerical noise
        ratio = peak / own if moves_itself else (0.0 if peak == 0 else math.inf)
        joints.append(JointCoupling(
            i + 1, plant.inputs[i].unit, float(np.max(np.abs(tq["off_diagonal"][:, i]))),
            float(np.max(np.abs(tq["coriolis"][:, i]))), peak, float(path.t[k]), own, ratio,
            float(np.max(model_err[:, i])) if model_err is not None else None))
    check = _check(result, "coupling")
    rows = check.certificate.get("intercoupling_error", ()) if check is not None else ()
    return Coupling(tuple(joints), path.stride, coupling_sentences(joints, nature, _label(result), rows))


# ----------------------------------------------------------------------------- 5. mass parameters


def _mass_sentences(result: Any, plant: Any) -> tuple[str, ...]:
    design = result.design
    out = []
    differs = [(q.name, q.unit, q.value, plant.parameter(q.name).value) for q in design.plant.parameters
                if q.name in plant.parameter_names and q.value != plant.parameter(q.name).value]
    if differs:
        out.append("The controller's model differs from the true plant: " + ", ".join(
            f"{name} {_n(m, 4)} against {_q(t, unit, 4)}" for name, unit, m, t in differs)
            + " (model against plant); the torque this costs is the model error torque below.")
    bounds = _check(result, "tracking_bounds")
    sim = result.simulation
    if bounds is not None and bounds.achieved is not None:
        cert = bounds.certificate
        per_joint = cert.get("bound_per_joint_rad", [])
        j = int(np.argmax(per_joint)) if per_joint else 0
        where = ", ".join(f"{k} = {_n(v, 4)}" for k, v in dict(cert.get("worst_parameters", {})).items())
        errors = None if sim is None or sim.task_space else np.abs(np.asarray(sim.tracking_errors, dtype=float))
        nominal = float(np.max(errors[:, j])) if errors is not None and errors.shape[1] > j else None
        runs = f"{cert.get('corners')} corners" + (f" and {cert.get('random_samples')} random samples"
                                                    if cert.get("random_samples") else "")
        text = (f"Over {cert.get('runs')} runs on the true plant at the parameter box's {runs} the largest "
                f"|q − qD| is {_n(bounds.achieved)} rad at joint {j + 1} ({where})")
        if nominal is not None and np.isfinite(nominal):
            move = float(_moves(sim)[j])
            if nominal <= NEGLIGIBLE_ERROR * max(move, 1.0):
                text += f", where this run tracks to the integrator's precision ({_n(nominal, 2)} rad)"
            else:
                text += f", {_n(bounds.achieved / nominal)} times this run's {_n(nominal)} rad"
        out.append(text + ".")
    grid = _check(result, "robust_grid")
    if grid is not None:
        cert = grid.certificate
        worst = dict(cert.get("worst_abscissa", {}))
        abscissa = worst.pop("spectral_abscissa", None)
        where = ", ".join(f"{k} = {_n(v, 4)}" for k, v in worst.items())
        if cert.get("unstable") or cert.get("undecided"):
            bad = cert.get("unstable", 0) + cert.get("undecided", 0)
            out.append(f"The linearized loop is unstable or undecided for {bad} of the {cert.get('plants')} plants "
                       "of the parameter box.")
        else:
            out.append(f"The linearized loop stays stable for all {cert.get('plants')} plants of the parameter box; "
                       f"its slowest pole, Re = {_n(abscissa)} 1/s, is at {where}.")
    if not out:
        out.append("The spec gives no parameter box and the controller's model is the plant: this run does not vary "
                   "the mass parameters (give plant.uncertainty, or controller.model for a model-based design).")
    return tuple(out)


# ----------------------------------------------------------------------------- entry point


def nature_of(result: Any) -> str:
    """``"per-joint loops"``, ``"model-based"`` or ``"other"`` (see :class:`LabAnswers`), from the design and checks."""
    if result.design.loops:
        return "per-joint loops"
    if _check(result, "error_poles") is not None:
        return "model-based"
    return "other"


def lab_answers(result: Any) -> LabAnswers | None:
    """Answer the lab questions of experiment 1 for ``result`` (see the module docstring).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        Its ``simulation``, ``plant`` (the true plant; None: the design's), ``design`` and ``checks``.

    Returns
    -------
    LabAnswers or None
        None for a plant that is not a robot, or a run without simulation.
    """
    sim = result.simulation
    plant = result.plant if result.plant is not None else result.design.plant
    if sim is None or getattr(plant, "kind", None) != "robot" or getattr(result.design.plant, "kind", None) != "robot":
        return None
    nature = nature_of(result)
    path = _path(sim)
    with np.errstate(all="ignore"):
        tracking = _tracking(sim, plant)
    return LabAnswers(
        controller=_label(result),
        nature=nature,
        tracking=tracking,
        gains=_gain_study(result, plant, sim),
        configuration=_configuration(result, plant, path, nature),
        mass=_mass_sentences(result, plant),
        coupling=_coupling(result, plant, path, nature),
    )
