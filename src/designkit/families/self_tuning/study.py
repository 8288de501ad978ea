"""Lab experiment 2 for the self-tuning regulator, answered from re-simulations of the report's scenario.

Every number of the section comes from a run: the spec's own (the pipeline's), the same scenario with the
estimator switched off (the regulator stays designed on the initial estimates), with other forgetting factors
and initial covariances, without the ad hoc modifications, with the other design strategy, with a load torque
step, on other true links, and on a quiet reference (a step with measurement noise) with and without the
covariance bound.  At most :data:`MAX_RUNS` simulations.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table
from designkit.families.self_tuning.checks import CONVERGED_REL
from designkit.families.self_tuning.runs import designed_response, samples, sylvester_condition, true_theta

__all__ = ["MAX_RUNS", "Measure", "measure", "section"]

MAX_RUNS = 20
"""Simulations the study may spend."""
LAMBDAS = (1.0, 0.995, 0.98, 0.95)
"""Forgetting factors re-simulated (the spec's own is the main run)."""
COVARIANCES = (1e-4, 1e-2, 1e4)
"""Initial covariances re-simulated."""
LOAD = 0.5
"""Load torque step of the perturbation run (N*m), from a quarter of the run."""
QUIET_NOISE = 1e-4
"""Measurement noise (rad, rad/s) of the quiet-reference runs."""


@dataclass(frozen=True)
class Measure:
    """What one run did.

    Attributes
    ----------
    label : str
        The scenario in words.
    rms, rms_last : float
        RMS of ``x1 - xD`` over the run and over its last quarter (rad).
    follow, follow_last : float
        RMS of ``x1 - ym`` at the samples, ``ym`` the requested loop's response on the true link
        (:func:`~designkit.families.self_tuning.runs.designed_response`), over the run and its last quarter
        (rad; NaN for the PID design).
    first : float or None
        Seconds from the start until the estimates stay within 5 % of the initial true link's parameters
        (before any change; None: never).
    peak_u, rms_u : float
        Peak and RMS command (N*m).
    error : float
        Largest relative error of the final estimates against the true sampled link.
    reconverged : float or None
        Seconds after ``simulation.plant_change`` until the estimates stay within 5 % (None: never; NaN: no change).
    trace : float
        ``trace P`` at the end.
    bounded, held : int
        Samples where the covariance bound fired, where the controller was held.
    condition : float
        Largest Sylvester condition number along the run.
    finite : bool
        The run stayed finite.
    """

    label: str
    rms: float
    rms_last: float
    follow: float
    follow_last: float
    first: float | None
    peak_u: float
    rms_u: float
    error: float
    reconverged: float | None
    trace: float
    bounded: int
    held: int
    condition: float
    finite: bool


def measure(label: str, sim: Any, design: Any, spec: Any, plant: Any) -> Measure:
    """The :class:`Measure` of ``sim``, a run of ``design`` in the scenario ``spec`` on ``plant``."""
    t = np.asarray(sim.time, dtype=float)
    e = np.asarray(sim.position, dtype=float) - np.asarray(sim.desired, dtype=float)[:, 0]
    u = np.asarray(sim.u_command, dtype=float)[:, 0]
    last = t >= t[0] + 0.75 * (t[-1] - t[0])
    s = samples(sim, design)
    true = true_theta(spec, plant, design, s.t)
    with np.errstate(all="ignore"):
        rel = np.abs(s.theta / true - 1)
        finite = bool(np.all(np.isfinite(e)) and np.all(np.isfinite(s.theta)))
        err = float(np.max(rel[-1])) if finite else math.inf
        cond = sylvester_condition(s, design)
    reconverged: float | None = math.nan
    change = spec.simulation.plant_change
    end = change.time if change is not None else math.inf
    ok0 = np.all(rel <= CONVERGED_REL, axis=1) & (s.t < end)
    bad0 = np.flatnonzero(~ok0 & (s.t < end))
    pre = np.flatnonzero(s.t < end)
    first = None if not pre.size or not ok0[pre[-1]] else float(s.t[bad0[-1] + 1] if bad0.size else s.t[0])
    follow = follow_last = math.nan
    if design.data.settings.design == "pole_placement" and finite:
        ts, x1, ym = designed_response(sim, design, spec, plant)
        f = x1 - ym
        follow, follow_last = _rms(f), _rms(f[ts >= ts[0] + 0.75 * (ts[-1] - ts[0])])
    if change is not None:
        ok = np.all(rel <= CONVERGED_REL, axis=1) & (s.t >= change.time)
        bad = np.flatnonzero(~ok & (s.t >= change.time))
        if not ok[-1]:
            reconverged = None
        else:
            k = bad[-1] + 1 if bad.size else int(np.flatnonzero(s.t >= change.time)[0])
            reconverged = float(s.t[k] - change.time)
    return Measure(label=label, rms=_rms(e), rms_last=_rms(e[last]), follow=follow, follow_last=follow_last,
                   first=first, peak_u=float(np.nanmax(np.abs(u))),
                   rms_u=_rms(u), error=err, reconverged=reconverged, trace=float(s.trace[-1]),
                   bounded=int(s.bounded.sum()), held=int(s.held.sum()),
                   condition=float(np.nanmax(cond)) if np.any(np.isfinite(cond)) else math.nan, finite=finite)


def _rms(x: np.ndarray) -> float:
    x = np.asarray(x, dtype=float)
    if not (x.size and np.all(np.isfinite(x))):
        return math.inf
    peak = float(np.max(np.abs(x)))  # scaled by the peak: no overflow of x * x for a large finite record
    return peak * float(np.sqrt(np.mean((x / peak) ** 2))) if peak > 0 else 0.0


def _f(x: float | None, digits: int = 3) -> str:
    return "—" if x is None or not math.isfinite(x) else fmt_number(x, digits)


def _rec(m: Measure) -> str:
    if m.reconverged is None:
        return "never"
    return "—" if not math.isfinite(m.reconverged) else f"{fmt_number(m.reconverged, 3)} s"


class _Runner:
    """Re-simulations of the report's scenario (at most :data:`MAX_RUNS`)."""

    def __init__(self, result: Any) -> None:
        self.result, self.design, self.spec = result, result.design, result.loaded.spec
        self.plant = result.plant if result.plant is not None else result.design.plant
        self.count = 0

    def run(self, label: str, *, controller: dict[str, Any] | None = None, simulation: dict[str, Any] | None = None,
            plant: Any = None, estimate: bool = True) -> Measure | None:
        if self.count >= MAX_RUNS:
            return None
        self.count += 1
        from designkit.families.self_tuning import settings_from, synthesize
        from designkit.families.self_tuning.laws import self_tuning_law
        from designkit.simulation.run import build

        spec = self.spec
        if controller:
            spec = spec.model_copy(update={"controller": spec.controller.model_copy(update=controller)})
        if simulation:
            spec = spec.model_copy(update={"simulation": spec.simulation.model_copy(update=simulation)})
        design = synthesize(spec, self.plant)
        law = None
        if not estimate:
            law = self_tuning_law(design.plant, dataclasses.replace(settings_from(design), estimate=False))
        true = self.plant if plant is None else plant
        sim = build(spec, design, plant=true, law=law).run()
        return measure(label, sim, design, spec, true)


def _row(m: Measure) -> tuple[str, ...]:
    first = "never" if m.first is None else f"{fmt_number(m.first, 3)} s"
    return (m.label, _f(m.rms), _f(m.follow), _f(m.follow_last), _f(m.peak_u), first, _f(m.error), _rec(m),
            str(m.bounded), str(m.held))


HEADER = ("Scenario", "RMS x1 − xD (rad)", "RMS x1 − ym (rad)", "x1 − ym, last quarter (rad)", "peak |u| (N·m)",
          "converged first after", "final estimate error", "re-converged after the change", "bound fired (samples)",
          "controller held (samples)")


def _table(caption: str, rows: list[Measure | None]) -> Table:
    return Table(caption, HEADER, tuple(_row(m) for m in rows if m is not None))


def _link_words(plant: Any) -> str:
    return f"Km = {plant.parameter('Km').value:g} (rad/s)/(N·m), τ = {plant.parameter('tau').value:g} s"


def section(result: Any) -> ReportSection | None:
    """The self-tuning lab section (module docstring); the link's forms only (the notes' experiment is on the link)."""
    if result.simulation is None or result.design.data.settings.form == "arx":
        return None
    r = _Runner(result)
    d, spec = result.design, r.spec
    x = d.data
    main = measure("this spec", result.simulation, d, spec, r.plant)
    fixed = r.run("estimator off (designed on the initial estimates)", estimate=False)
    questions = [_why(main, fixed, r), _parameters(main, r), _strategies(main, r), _ad_hoc(main, r),
                 _performance(main, r)]
    form = "with the speed measured" if x.settings.form == "speed" else "without a speed measurement"
    intro = (f"Notes §4.3 and the SELFTUNE simulator ({form}): each answer below is measured on a re-simulation of "
             f"this report's scenario ({r.count + 1} runs in all, sampled every {x.settings.Ts:g} s). \"Final estimate "
             "error\" is the largest relative error of the final estimates against the parameters of the true link "
             f"at the end of the run, discretized exactly; \"re-converged\" is the time after the link's change until "
             f"every estimate stays within {CONVERGED_REL:.0%} of the new link's parameters.")
    return ReportSection(anchor="lab-self-tuning", title="Lab questions (notes, experiment 2: self-tuning)",
                         intro=intro, questions=tuple(q for q in questions if q is not None))


def _why(main: Measure, fixed: Measure | None, r: _Runner) -> Question:
    x = r.design.data
    spec = r.spec
    nominal = x.nominal
    sentences = [f"The regulator starts from the estimates of a link with Km = {nominal[0]:g} (rad/s)/(N·m) and "
                 f"τ = {nominal[1]:g} s while the true link is {_link_words(r.plant)}"
                 + (f" and changes at t = {spec.simulation.plant_change.time:g} s" if spec.simulation.plant_change
                    else "") + ". Why adapt: a controller designed once for a wrong model places the wrong poles."]
    if fixed is not None:
        sentences.append("Success is measured against ym, the response the requested poles give on the true link "
                         "(the closed loop is (Am(1)/B(1)) B(z)/Am(z) when A R + B S = Am Ao holds on the true model). "
                         f"With the estimator switched off the loop keeps the controller designed on the initial "
                         f"estimates and leaves ym by {_f(fixed.follow)} rad RMS ({_f(fixed.follow_last)} rad over the "
                         f"last quarter); with self-tuning by {_f(main.follow)} rad ({_f(main.follow_last)} rad over "
                         f"the last quarter). The error against the reference itself, {_f(main.rms)} rad RMS, is "
                         "mostly the requested loop's own response time to the square wave's jumps.")
    how = ("How: at every sample recursive least squares updates the estimates of the exactly sampled link from the "
           "last input and output, and the controller is redesigned for the estimate (certainty equivalence).")
    success = (f"With what success: the final estimates are within {_f(main.error)} (relative) of the true sampled "
               "link's parameters")
    if main.reconverged is not None and math.isfinite(main.reconverged):
        success += f", and after the change they re-converged within {_f(main.reconverged)} s"
    elif main.reconverged is None:
        success += ", but after the change they did not re-converge before the end of the run"
    sentences += [how, success + "."]
    return Question("Why, how, and with what success does the self-tuning regulator adapt?", tuple(sentences),
                    (_table("This run against the same scenario without adaptation.", [main, fixed]),))


def _parameters(main: Measure, r: _Runner) -> Question:
    c = r.spec.controller
    lam_runs = [r.run(f"λ = {lam:g}", controller={"forgetting": lam}) for lam in LAMBDAS
                if abs(lam - c.forgetting) > 1e-12]
    p_runs = [r.run(f"P(0) = {p:g} I", controller={"initial_covariance": p, "max_trace": None}) for p in COVARIANCES
              if abs(p - c.initial_covariance) > 1e-12]
    main_label = dataclasses.replace(main, label=f"this spec: λ = {c.forgetting:g}, P(0) = {c.initial_covariance:g} I")
    sentences = ["The forgetting factor λ sets the estimator's memory, about 1/(1 − λ) samples "
                 f"({'the whole run' if c.forgetting == 1 else f'{1 / (1 - c.forgetting):.4g} samples'} here): "
                 "λ = 1 weighs all the past equally, so after a change of the link the estimates settle between "
                 "the old and the new link; a smaller λ follows changes faster but amplifies noise and winds the "
                 "covariance up when the excitation fades."]
    lam_done = [m for m in lam_runs if m is not None]
    if lam_done:
        best = min([main_label, *lam_done], key=lambda m: (m.error, m.rms_last))
        sentences.append(f"Of the forgetting factors simulated, {best.label} ends with the smallest estimate error "
                         f"({_f(best.error)}).")
    p_done = [m for m in p_runs if m is not None]
    firsts = ", ".join(f"{m.label.split(':')[-1].strip()}: {'never' if m.first is None else _f(m.first) + ' s'}"
                       for m in [main_label, *p_done])
    sentences.append("The initial covariance P(0) says how little the initial estimates are trusted: a small one "
                     "makes the first updates timid (the estimates move slowly away from the wrong nominal link), a "
                     f"large one lets the first samples move them at once. Time until the estimates first settle "
                     f"within {CONVERGED_REL:.0%} of the true link: {firsts}.")
    return Question("What is the influence of the estimator's parameters (λ and the initial covariance)?",
                    tuple(sentences), (_table("Forgetting factor λ.", [main_label, *lam_runs]),
                                       _table("Initial covariance (the covariance bound follows it: n P(0)).",
                                              [main_label, *p_runs])))


def _strategies(main: Measure, r: _Runner) -> Question:
    c = r.spec.controller
    x = r.design.data
    poles = list(x.settings.poles)
    if c.design == "pole_placement":
        other = r.run("PID on the estimated Km, τ (poles: the two requested and the observer's)",
                      controller={"design": "pid", "poles": [*poles, complex(x.settings.observer)], "observer": None})
        words = ("This spec places the poles of the estimated sampled model by the Diophantine equation "
                 "A R + B S = Am Ao (a Sylvester system solved at every sample; its condition number reached "
                 f"{_f(main.condition)}). The alternative re-computes the one-link PID from the estimated Km and τ.")
    else:
        other = r.run("pole placement (the first two poles, the third as observer)",
                      controller={"design": "pole_placement", "poles": poles[:2], "observer": poles[2].real})
        words = ("This spec re-computes the one-link PID from the estimated Km and τ at every sample; the alternative "
                 "places the poles of the estimated sampled model by the Diophantine equation A R + B S = Am Ao.")
    return Question("What are the control strategies?", (words, "Both are certainty-equivalence designs: the "
                    "estimate is used as if it were the truth."),
                    (_table("The two designs in the same scenario.", [dataclasses.replace(main, label="this spec"),
                                                                       other]),))


def _ad_hoc(main: Measure, r: _Runner) -> Question:
    c, sim = r.spec.controller, r.spec.simulation
    x = r.design.data
    flipped = r.run("without the modifications" if c.safeguards else "with the modifications",
                    controller={"safeguards": not c.safeguards})
    quiet = {"trajectory": None, "step": 0.5, "noise": _noise(), "plant_change": None}
    q_on = r.run("quiet reference with noise, with the modifications", controller={"safeguards": True},
                 simulation=quiet)
    q_off = r.run("quiet reference with noise, without the modifications", controller={"safeguards": False},
                  simulation=quiet)
    sentences = [f"designkit applies two modifications of the textbook estimator (on in this spec: "
                 f"{'yes' if c.safeguards else 'no'}): a covariance bound -- when the trace of P exceeds "
                 f"{_f(x.settings.max_trace)} after an update P is scaled back to that trace; it fires when forgetting "
                 "inflates P along directions the data no longer excite -- and a controller hold: an estimate with "
                 "the pole outside (0, 1), a non-positive static gain or a near-singular Sylvester matrix keeps the "
                 "previous controller.",
                 f"In this run the bound fired on {main.bounded} samples and the controller was held on {main.held}."]
    if q_on is not None and q_off is not None:
        sentences.append(f"On a quiet reference (a step of 0.5 rad, then nothing to learn from, with measurement "
                         f"noise of {QUIET_NOISE:g} rad and rad/s) the trace of P ends at {_f(q_on.trace)} with the "
                         f"bound and at {_f(q_off.trace)} without it: without the bound the estimator is ready to be "
                         "thrown by "
                         f"the next noise burst (final estimate error {_f(q_on.error)} with, {_f(q_off.error)} "
                         f"without; the loop leaves ym by {_f(q_on.follow_last)} rad RMS over the last quarter with "
                         f"the bound, {_f(q_off.follow_last)} rad without).")
    if flipped is not None and main.bounded == 0 and main.held == 0:
        sentences.append("In this scenario neither modification ever acted, so the run without them is the same run; "
                         "the quiet-reference runs show what the bound is for.")
    elif flipped is not None:
        first = "never" if flipped.first is None else f"{_f(flipped.first)} s"
        mine = "never" if main.first is None else f"{_f(main.first)} s"
        sentences.append(f"Run {flipped.label} in this scenario: the estimates first converge after {first} (against "
                         f"{mine}) and the loop leaves ym by {_f(flipped.follow)} rad RMS (against {_f(main.follow)} "
                         "rad). Where the bound slows the estimator, it is tighter than the data need: the regressor "
                         "of small position differences needs a large covariance along its direction "
                         "(controller.max_trace raises it).")
    if sim.plant_change is None:
        sentences.append("This scenario has no change of the link.")
    rows = [dataclasses.replace(main, label="this spec"), flipped, q_on, q_off]
    trace_rows = tuple((m.label, _f(m.trace), str(m.bounded), str(m.held)) for m in rows if m is not None)
    return Question("What ad hoc modifications of the off-the-shelf algorithm are required?", tuple(sentences),
                    (_table("With and without the modifications.", rows),
                     Table("Covariance at the end of each run.", ("Scenario", "trace P at the end",
                                                                 "bound fired (samples)", "controller held (samples)"),
                           trace_rows)))


def _noise() -> Any:
    from designkit.spec.sections import Noise

    return Noise(std=QUIET_NOISE, seed=1)


def _perturbation(duration: float) -> Any:
    from designkit.spec.sections import Perturbation

    return Perturbation(value=LOAD, time=round(duration / 4, 6))


def _performance(main: Measure, r: _Runner) -> Question:
    sim = r.result.simulation
    duration = float(sim.time[-1])
    load = r.run(f"load torque step of {LOAD:g} N·m at t = {duration / 4:.4g} s",
                 simulation={"perturbation": _perturbation(duration)})
    robust = [r.run(f"true link {words}", plant=r.plant.with_params(**values), simulation={"plant_change": None})
              for words, values in (("with half the gain", {"Km": r.plant.parameter("Km").value / 2}),
                                    ("with twice the gain", {"Km": r.plant.parameter("Km").value * 2}),
                                    ("with twice the time constant", {"tau": r.plant.parameter("tau").value * 2}))]
    t, x1, xD = np.asarray(sim.time), np.asarray(sim.position), np.asarray(sim.desired)[:, 0]
    settle = _settling(t, x1, xD)
    sentences = []
    if load is not None:
        sentences.append(f"External perturbation: with a load torque of {LOAD:g} N·m the loop leaves the designed "
                         f"response by {_f(load.follow_last)} rad RMS over the last quarter (against "
                         f"{_f(main.follow_last)} rad without it): the controller has no integral action, and the "
                         f"estimator, whose model has no load term, ends {_f(load.error)} (relative) from the true "
                         "link's parameters -- the load is absorbed into biased estimates.")
    if settle is not None:
        sentences.append(f"Response time: after the last reference step before the end the position settles within "
                         f"2 % of the step in {_f(settle)} s.")
    sentences.append(f"Control level: peak |u| = {_f(main.peak_u)} N·m, RMS {_f(main.rms_u)} N·m.")

    done = [m for m in robust if m is not None]
    if done:
        worst = max(done, key=lambda m: m.error)
        sentences.append(f"Robustness: on other true links, from the same initial estimates, the largest final "
                         f"estimate error is {_f(worst.error)} ({worst.label}); the loop stays bounded in "
                         f"{sum(m.finite for m in done)} of {len(done)} cases.")
    return Question("What are the sensitivity to external perturbations, the response time, the control level "
                    "and the robustness?", tuple(sentences),
                    (_table("Perturbation and other true links (no change of the link in the robustness runs).",
                            [dataclasses.replace(main, label="this spec"), load, *robust]),))


def _settling(t: np.ndarray, x: np.ndarray, r: np.ndarray) -> float | None:
    """2 % settling time after the last jump of the reference that leaves at least a tenth of the run after it."""
    jumps = np.flatnonzero(np.abs(np.diff(r)) > 1e-9)
    jumps = [k for k in jumps if t[-1] - t[k + 1] >= 0.1 * (t[-1] - t[0])]
    if not jumps:
        return None
    k = jumps[-1] + 1
    step = abs(r[k] - r[k - 1])
    end = np.flatnonzero(np.abs(np.diff(r[k:])) > 1e-9)
    stop = k + (end[0] + 1 if end.size else len(r) - k)
    outside = np.flatnonzero(np.abs(x[k:stop] - r[k]) > 0.02 * step)
    if outside.size and outside[-1] == stop - k - 1:
        return None
    return float(t[k + outside[-1] + 1] - t[k]) if outside.size else 0.0
