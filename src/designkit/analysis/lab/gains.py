"""Question 2: what each gain does, every gain scaled by 0.5 and 2 and the run re-simulated on the true plant."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.analysis.lab.run import NEGLIGIBLE_ERROR, commanded_moves, motion_scales
from designkit.analysis.lab.tracking import step_metrics
from designkit.display.numbers import fmt_number, quantity

__all__ = ["GainEffect", "GainRun", "GainStudy", "gain_sentence", "study_gains", "study_sentences"]

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
SMALL_CHANGE = 0.02
"""Relative changes below this are "unchanged" in the gain sentences."""

_VERBS = {0.5: "halving", 2.0: "doubling"}


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



def _run_record(sim: Any, scale: float, nominal: GainRun | None, scales: np.ndarray, input_units: Sequence[str],
                abscissa: float | None = None, pole_size: float = 1.0) -> GainRun:
    """The measures of one run; ``scales`` (per coordinate, see :func:`~designkit.analysis.lab.run.motion_scales`)
    bound a diverging error, ``abscissa`` (1/s) is the largest real part of its linearized loop's poles,
    ``pole_size`` their scale."""
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.tracking_errors, dtype=float)
    u = np.asarray(sim.u_command, dtype=float).reshape(t.size, -1)
    if not (np.all(np.isfinite(e)) and np.all(np.isfinite(u)) and np.all(np.isfinite(sim.state))):
        return GainRun(scale, "non-finite", "the simulated state is not finite", abscissa=abscissa)
    a = np.abs(e)
    peak = np.max(a, axis=0)
    tail = a[t >= t[-1] - TAIL_FRACTION * (t[-1] - t[0])]
    c = int(np.argmax(np.max(tail, axis=0) / scales))
    end = (f"{sim.coordinate_names[c]}'s error is {quantity(float(np.max(tail[:, c])), sim.coordinate_units[c], 3)} "
           "at the end")
    if abscissa is not None and abscissa > 1e-9 * pole_size:
        return GainRun(scale, "unstable", f"its loop linearized at the design's operating point has a pole at "
                       f"Re = {fmt_number(abscissa, 3)} 1/s; {end}", abscissa=abscissa)
    if nominal is not None and nominal.peak_error:
        bound = DIVERGENCE_FACTOR * np.maximum(np.asarray(nominal.peak_error), scales)
        grown = np.flatnonzero(np.max(tail, axis=0) > bound)
        if grown.size:
            c = int(grown[0])
            return GainRun(scale, "diverging", f"{sim.coordinate_names[c]}'s error reaches "
                           f"{quantity(float(np.max(tail[:, c])), sim.coordinate_units[c], 3)} at the end of the run",
                           abscissa=abscissa)
    torques = np.max(np.abs(u), axis=0)
    j = nominal.torque_input if nominal is not None else int(np.argmax(torques))
    overshoot, settling, _ = step_metrics(sim)
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
            text = f"{verb} it leaves {obj} practically unchanged (×{fmt_number(ratio, 3)})"
        else:
            text = f"{verb} it multiplies {obj} by {fmt_number(ratio, 2)}"
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
        extras.append(f"overshoot {fmt_number(nominal.overshoot, 3)} % → {fmt_number(run.overshoot, 3)} %")
    if (run.settling_time is None) != (nominal.settling_time is None):
        extras.append("no longer settles within the run" if run.settling_time is None
                      else f"now settles in {fmt_number(run.settling_time, 3)} s")
    elif run.settling_time is not None and nominal.settling_time and \
            abs(run.settling_time / nominal.settling_time - 1) >= 0.05:
        extras.append(f"settling time {fmt_number(nominal.settling_time, 3)} s → {fmt_number(run.settling_time, 3)} s")
    if run.abscissa is not None and nominal.abscissa and abs(run.abscissa / nominal.abscissa - 1) >= 0.05:
        extras.append(f"slowest pole Re {fmt_number(nominal.abscissa, 3)} → {fmt_number(run.abscissa, 3)} 1/s")
    if run.peak_torque is not None and nominal.peak_torque and abs(run.peak_torque / nominal.peak_torque - 1) >= 0.05:
        extras.append(f"peak |{run.peak_torque_input}| {fmt_number(nominal.peak_torque, 3)} → "
                      f"{quantity(run.peak_torque, run.peak_torque_unit, 3)}")
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
        return ", ".join(f"×{fmt_number(r, 2)} {'halved' if s == 0.5 else 'doubled' if s == 2.0 else f'at {s:g}'}"
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


def study_gains(result: Any, plant: Any, nominal_sim: Any) -> GainStudy:
    from designkit.errors import DesignkitError
    from designkit.families import family
    from designkit.simulation.run import build

    design, spec = result.design, result.loaded.spec
    names, units = tuple(nominal_sim.coordinate_names), tuple(nominal_sim.coordinate_units)
    step = nominal_sim.kind == "step"
    measure, key = ("RMS |e|", "rms") if step else ("peak |e|", "peak")
    if len(names) > 1:
        measure += " relative to the move"
    moves = commanded_moves(nominal_sim)
    scales = motion_scales(moves, units)
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
    # Each scaled law is a new loop run once: ``numerics.compile: auto`` compiles a fixed-step loop only when its
    # interpreted run would cost more than compiling, and always compiles the Dormand-Prince pair of a smooth loop
    # (its interpreted driver is a Python loop per step: 47 s against 0.3 s to compile on the SCARA).
    study_spec = spec
    effects = []
    estimate_checked = False
    for name in gains:
        runs = {1.0: nominal}
        for scale in SCALES:
            scaled = dataclasses.replace(design, gains=gains.replace(**{name: _scaled(gains[name], scale)}))
            try:  # the design carries the law built from its own gains: the scaled gains need their own law
                scaled_law = family(design.kind).law(scaled, spec.simulation.anti_windup)
                simulator = build(study_spec, scaled, plant=plant, law=scaled_law)
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
    floor_text = "below " + ", ".join(sorted({quantity(f, u, 2) for f, u in zip(floors, units, strict=True)}))
    top = None
    if effects and (not negligible or any(math.isinf(e.sensitivity) for e in effects)):
        top = max(effects, key=lambda e: e.sensitivity).name
    return GainStudy(measure, names, units, tuple(effects), top, study_sentences(measure, effects, negligible,
                                                                                    floor_text))
