"""Lab experiment 3 (notes, appendix A): sliding-mode control of ROBEL's elastic joint, against PID and the linear
state regulator.

The contributed section (:data:`designkit.comparison.answers.CONTRIBUTIONS`) of a comparison that includes the
sliding-mode state regulator (``vsc``) and the linear state regulator (``state_regulator``), with the classical PID
(``pid_servo``) and the PID/sliding mode (``pid_sliding_mode``) when present.  Every answer is a number measured on
the runs or on re-simulations of them:

* **robustness**: each controller's designed law re-simulated on the true plant at every corner of
  ``plant.uncertainty`` (each corner starting at rest, as :mod:`designkit.studies.arm.mass` does);
* **chattering**: the total variation ``TV(u) = sum |u[k+1] - u[k]|`` of the command and its reversals per second
  (sign changes of ``u[k+1] - u[k]``, steps below ``1e-9 max|u|`` ignored);
* **perturbation sensitivity**: the run without ``simulation.perturbation`` against the run with it: the largest
  and the final (mean over the last tenth of the run) ``|x - x0|``, against the closed-form static offset
  (:func:`predicted_offset`);
* **parameter importance**: a one-at-a-time study, each controller re-designed and re-simulated with one of its
  parameters changed (:data:`VARIANTS`);
* **response time and control level**: 90 % rise time and settling time, peak and RMS command (the table's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.comparison.studies import rise_times
from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table
from designkit.families.pid_servo import KIND as PID
from designkit.families.pid_sliding_mode.elastic import BAND as PID_SM_BAND
from designkit.families.pid_sliding_mode.elastic import EXTRA as PID_SM_EXTRA
from designkit.families.pid_sliding_mode.elastic import RELAY as PID_SM_RELAY
from designkit.families.pid_sliding_mode.spec import KIND as PID_SM
from designkit.families.state_regulator.spec import KIND as STATE_REGULATOR
from designkit.families.vsc.spec import KIND as VSC

__all__ = ["BOX_RUNS_MAX", "VARIANTS", "Chatter", "CornerRun", "OatRun", "PerturbationEffect", "applies", "chattering",
           "corner_runs", "oat_runs", "perturbation_effect", "predicted_offset", "printed_c4", "section"]

BOX_RUNS_MAX = 16
"""Corners of the parameter box re-simulated per controller (a larger box is not re-simulated)."""
REVERSAL_TOL = 1e-9
"""A command step below this fraction of ``max |u|`` is not a reversal."""


def _scaled(values: Any, factor: float) -> list[complex]:
    return [complex(v) * factor for v in values]


VARIANTS: dict[str, tuple[tuple[str, Any], ...]] = {
    PID: (("poles and zero 1.5 times faster", lambda c, d: {"poles": _scaled(c.poles, 1.5), "zero": 1.5 * c.zero}),
          ("poles and zero 0.75 times as fast", lambda c, d: {"poles": _scaled(c.poles, 0.75),
                                                              "zero": 0.75 * c.zero})),
    PID_SM: (("sliding-motion poles p1, p2 twice as fast", lambda c, d: {"poles": [*_scaled(c.poles[:2], 2.0),
                                                                                   complex(c.poles[2])]}),
             ("pole p3 twice as fast", lambda c, d: {"poles": [*map(complex, c.poles[:2]), 2.0 * complex(c.poles[2])]}),
             ("relay margin 1 (M twice the bound)", lambda c, d: {"margin": 1.0}),
             ("boundary layer ε = 0.01 rad·s (saturation)", lambda c, d: {"epsilon": 0.01})),
    STATE_REGULATOR: (("poles 1.5 times faster", lambda c, d: {"poles": _scaled(c.poles, 1.5)}),
                      ("poles 0.75 times as fast", lambda c, d: {"poles": _scaled(c.poles, 0.75)})),
    VSC: (("sliding poles 1.5 times faster", lambda c, d: {"sliding_poles": _scaled(c.sliding_poles, 1.5)}),
          ("gain margin 0.05 (α, β close to the equivalent-control gains lᵢ)", lambda c, d: {"margin": 0.05}),
          ("gain margin 1 (α, β far from the lᵢ)", lambda c, d: {"margin": 1.0}),
          ("chattering band 3 times wider", lambda c, d: {"chattering_band": 3.0 * d.extra[VSC]["band"]}),
          ("relay δ 5 times larger", lambda c, d: {"relay_amplitude": 5.0 * d.extra[VSC]["delta"]})),
}
"""Kind -> (what is changed, in words; ``(controller section, design) -> fields to change``) of the one-at-a-time
study."""


def applies(kinds: tuple[str, ...]) -> bool:
    """The comparison includes the sliding-mode state regulator and the linear state regulator."""
    return VSC in kinds and STATE_REGULATOR in kinds


@dataclass(frozen=True)
class Chatter:
    """Chattering of a run's command: ``total_variation`` (input units), ``reversals`` and their ``rate`` (1/s)."""

    total_variation: float
    reversals: int
    rate: float


def chattering(sim: Any) -> Chatter:
    """:class:`Chatter` of ``sim.u_command[:, 0]`` (module docstring)."""
    t = np.asarray(sim.time, float)
    u = np.asarray(sim.u_command, float).reshape(len(t), -1)[:, 0]
    du = np.diff(u)
    tv = float(np.sum(np.abs(du)))
    big = du[np.abs(du) > REVERSAL_TOL * max(float(np.max(np.abs(u))), 1e-300)]
    reversals = int(np.count_nonzero(np.sign(big[1:]) != np.sign(big[:-1])))
    return Chatter(tv, reversals, reversals / float(t[-1] - t[0]))


@dataclass(frozen=True)
class CornerRun:
    """One corner's re-simulation: the parameter values, overshoot (%), settling time (s), steady-state error
    (the position's unit), peak command and whether the run stayed finite."""

    at: dict[str, float]
    overshoot: float | None
    settling_time: float | None
    steady_state_error: float | None
    peak_command: float
    bounded: bool


def _build(spec: Any, design: Any, plant: Any) -> Any:
    from designkit.simulation.run import build

    return build(spec, design, plant=plant).run()


def _plant(run: Any) -> Any:
    return run.plant if getattr(run, "plant", None) is not None else run.design.plant


def corner_runs(run: Any) -> tuple[CornerRun, ...]:
    """The designed law of ``run`` re-simulated on the true plant at every corner of ``plant.uncertainty``."""
    from designkit.verification.robustness import box_from_uncertainty
    from designkit.verification.time_domain import response_metrics

    spec = run.loaded.spec
    unc = spec.plant.uncertainty
    if unc is None:
        return ()
    plant = _plant(run)
    box = box_from_uncertainty(plant, unc)
    corners = np.asarray(box.vertices, float)
    if len(corners) > BOX_RUNS_MAX:
        return ()
    band = spec.requirements.settling_band if spec.requirements is not None else 0.02
    out = []
    for theta in corners:
        at = dict(zip(box.names, map(float, theta), strict=True))
        sim = _build(spec, run.design, plant.with_params(**at))
        bounded = bool(np.all(np.isfinite(np.asarray(sim.state, float))))
        with np.errstate(all="ignore"):
            m = response_metrics(sim, settling_band=band)
        peak = float(np.max(np.abs(np.asarray(sim.u_command, float)))) if bounded else math.inf
        out.append(CornerRun(at, m.overshoot, m.settling_time, m.steady_state_error, peak, bounded))
    return tuple(out)


@dataclass(frozen=True)
class PerturbationEffect:
    """The load step's effect: ``value`` (N·m) from ``onset`` (s); ``peak`` and ``final`` ``|x - x0|`` (rad)."""

    value: float
    onset: float
    peak: float
    final: float
    predicted: float | None


def predicted_offset(run: Any, w: float) -> float | None:
    """The static offset of the controlled position a constant load ``w`` (N·m) leaves, in closed form.

    PID: 0 (integral of the load position error).  PID/sliding mode (motor side): the motor is held at ``xD``
    and the spring carries the load, ``x3 - xD = w/(KR R2)``.  State regulator: ``-C (A - B K)^-1 D w``.
    Sliding-mode regulator: on ``sigma = 0`` at rest, ``x3 - xD = c1 w/(KR R2 (c1 + c3))`` (docs/families/vsc.md).
    """
    d = run.design
    plant = d.plant
    if plant.kind != "elastic_joint":
        return None
    p = plant.params
    if d.kind == PID:
        return 0.0
    if d.kind == PID_SM and PID_SM_EXTRA in d.extra:
        return w / (p.KR * p.R2)
    if d.kind == STATE_REGULATOR:
        return w * float(d.extra[STATE_REGULATOR]["load_offset_per_unit"])
    if d.kind == VSC:
        c = d.extra[VSC]["c"]
        return c[0] * w / (p.KR * p.R2 * (c[0] + c[2]))
    return None


def _without(spec: Any, **changes: Any) -> Any:
    return spec.model_copy(update={"simulation": spec.simulation.model_copy(update=changes)})


def perturbation_effect(run: Any) -> PerturbationEffect | None:
    """The run against the same design's run without ``simulation.perturbation`` (None without one)."""
    spec = run.loaded.spec
    pert = spec.simulation.perturbation
    if pert is None:
        return None
    value = float(pert.value[0] if isinstance(pert.value, list | tuple) else pert.value)
    base = _build(_without(spec, perturbation=None), run.design, _plant(run))
    sim = run.simulation
    t = np.asarray(sim.time, float)
    n = min(len(t), len(base.time))
    x = np.asarray(sim.tracked_positions, float).reshape(len(t), -1)[:n, 0]
    x0 = np.asarray(base.tracked_positions, float).reshape(len(base.time), -1)[:n, 0]
    d = np.abs(x - x0)
    after = t[:n] >= float(pert.time)
    last = t[:n] >= t[n - 1] - 0.1 * (t[n - 1] - t[0])
    return PerturbationEffect(value, float(pert.time), float(np.max(d[after])), float(np.mean(d[last])),
                              predicted_offset(run, value))


@dataclass(frozen=True)
class OatRun:
    """One variant of the one-at-a-time study: what changed and the run's measures."""

    label: str
    change: str
    overshoot: float | None
    settling_time: float | None
    final_error: float | None
    peak_command: float
    total_variation: float
    reversal_rate: float
    bounded: bool
    error: str = ""
    slowest_pole: float | None = None


def _slowest(design: Any) -> float | None:
    """Largest real part (1/s) of the linear closed loop's poles; None for a switching law (no linearization)."""
    loop = design.closed_loop
    return None if loop is None else float(np.max(np.linalg.eigvals(np.asarray(loop.A, float)).real))


def _measure(label: str, change: str, spec: Any, sim: Any, design: Any = None) -> OatRun:
    from designkit.verification.time_domain import response_metrics

    band = spec.requirements.settling_band if spec.requirements is not None else 0.02
    bounded = bool(np.all(np.isfinite(np.asarray(sim.state, float))))
    with np.errstate(all="ignore"):
        m = response_metrics(sim, settling_band=band)
    ch = chattering(sim) if bounded else Chatter(math.inf, 0, math.inf)
    peak = float(np.max(np.abs(np.asarray(sim.u_command, float)))) if bounded else math.inf
    return OatRun(label, change, m.overshoot, m.settling_time, m.steady_state_error, peak, ch.total_variation,
                  ch.rate, bounded, slowest_pole=None if design is None else _slowest(design))


def oat_runs(label: str, run: Any) -> tuple[OatRun, ...]:
    """The spec's own run, then each variant of :data:`VARIANTS` for the run's kind (re-designed, re-simulated)."""
    from designkit.families import synthesize

    spec = run.loaded.spec
    out = [_measure(label, "as specified", spec, run.simulation, run.design)]
    for words, change in VARIANTS.get(run.design.kind, ()):
        try:
            ctl = spec.controller.model_copy(update=change(spec.controller, run.design))
            new = spec.model_copy(update={"controller": ctl})
            new = type(new).model_validate(new.model_dump())
            design = synthesize(new, _plant(run))
            out.append(_measure(label, words, new, _build(new, design, _plant(run)), design))
        except Exception as exc:  # noqa: BLE001 - a variant a family refuses is reported, not fatal
            reason = str(exc).splitlines()[0][:160]
            out.append(OatRun(label, words, None, None, None, math.nan, math.nan, math.nan, False, reason))
    return tuple(out)


def _f(x: float | None, unit: str = "", digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    if math.isinf(x):
        return "never" if unit == "s" else "unbounded"
    return f"{fmt_number(x, digits)} {unit}".strip()


def _runs(result: Any) -> list[tuple[str, Any]]:
    return list(zip(result.labels, result.results, strict=True))


def _by_kind(result: Any, kind: str) -> tuple[str, Any] | None:
    return next(((label, r) for label, r in _runs(result) if r.design.kind == kind), None)


def _check(run: Any, name: str) -> Any:
    return next((c for c in run.checks if c.name == name), None)


_WORDS = {PID: "the classical PID", PID_SM: "the PID/sliding mode", STATE_REGULATOR: "the linear state regulator",
          VSC: "the sliding-mode state regulator"}


def _why(result: Any, chat: dict[str, Chatter]) -> Question:
    eu = result.table.error_unit
    sentences = []
    found = _by_kind(result, VSC)
    if found is not None:
        label, run = found
        info = run.design.extra[VSC]
        reach, poles, eq, off = (_check(run, n) for n in ("vsc_reaching_time", "vsc_sliding_poles",
                                                            "vsc_equivalent_control", "vsc_offset"))
        measured = ", ".join(_f(complex(*p).real, digits=6) for p in (poles.certificate.get("poles") or [])) \
            if poles is not None else "—"
        sentences.append(
            f"Why: {label} makes the loop's motion independent of the plant's parameters where it matters: once the "
            f"state is on the surface σ = c x̃ = 0 the motion has the poles chosen for it "
            f"({', '.join(_f(complex(*p).real) for p in info['sliding_poles'])} 1/s) whatever Km and τ1, with "
            f"gains that keep it there for every plant of the box (theorem 3, certified: "
            f"{_check(run, 'vsc_gains').status if _check(run, 'vsc_gains') else '—'}).")
        vertex = [min(-complex(*z).real for z in v["poles"]) for v in info.get("vertex_poles", ())]
        if vertex:
            sentences.append(
                f"The sliding motion does depend on the link's parameters (J2, τ2, KR, R2 enter the reduced system): "
                f"at the corners of the box its slowest decay rate is {_f(min(vertex), '1/s')} to "
                f"{_f(max(vertex), '1/s')}, against {_f(min(-complex(*z).real for z in info['sliding_poles']), '1/s')}"
                " requested at the nominal plant; theorem 3 keeps the state on σ = 0 there, not the poles.")
        sentences.append(
            f"How: it reached the surface in {_f(reach.achieved if reach else None, 's')}, then slid with the "
            f"measured poles {measured} 1/s; the equivalent control stayed between the two switching controls on "
            f"{_f(100 * eq.achieved if eq and eq.achieved is not None else None, '%', 4)} of the sliding samples "
            f"(theorem 1); the unmatched load left {_f(off.achieved if off else None, eu, 4)} against the predicted "
            f"{_f(off.certificate.get('predicted') if off else None, eu, 4)}.")
        sentences.append(
            f"With what success: overshoot {_f(result.table.row(label).values.get('overshoot'), '%')}, settling "
            f"{_f(result.table.row(label).values.get('settling_time'), 's')}, at the price of a command that "
            f"reverses {_f(chat[label].rate)} times per second (total variation "
            f"{_f(chat[label].total_variation, result.table.command_unit)}).")
    found = _by_kind(result, PID_SM)
    if found is not None:
        label, run = found
        info = run.design.extra.get(PID_SM_EXTRA)
        band = _check(run, PID_SM_BAND)
        if info is not None and band is not None:
            sentences.append(
                f"{label} slides too, on the motor (|slm| at most {_f(band.achieved, 'rad·s')} against the band "
                f"{_f(info['band'], 'rad·s')}): the motor follows its model exactly, but the link hangs on the spring "
                f"with its own mode ({_f(info['load_mode']['omega'], 'rad/s')}, damping "
                f"{_f(info['load_mode']['zeta'])}), which the motor-side surface cannot damp.")
    return Question("Why, how and with what success a sliding-mode controller?", tuple(sentences))


def _importance(result: Any, oat: dict[str, tuple[OatRun, ...]]) -> Question:
    eu, cu = result.table.error_unit, result.table.command_unit
    rows, sentences = [], []
    for label, runs in oat.items():
        base = runs[0]
        for v in runs:
            stable = (v.error or "no") if not v.bounded else ("yes" if v.slowest_pole is None or v.slowest_pole < 0
                                                              else f"no (pole at {_f(v.slowest_pole, '1/s')})")
            rows.append((label, v.change, _f(v.overshoot, "%"), _f(v.settling_time, "s"), _f(v.final_error, eu),
                         _f(v.peak_command, cu), _f(v.total_variation, cu), stable))
        parts = []
        for v in runs[1:]:
            if v.error:
                parts.append(f"{v.change}: refused ({v.error})")
                continue
            if v.slowest_pole is not None and v.slowest_pole >= 0:
                parts.append(f"{v.change}: the loop is UNSTABLE (a closed-loop pole at {_f(v.slowest_pole, '1/s')}: "
                             "the elastic mode)")
                continue
            parts.append(f"{v.change}: settling {_f(base.settling_time, 's')} → {_f(v.settling_time, 's')}, peak "
                         f"command {_f(base.peak_command, cu)} → {_f(v.peak_command, cu)}, TV(u) "
                         f"{_f(base.total_variation, cu)} → {_f(v.total_variation, cu)}")
        if parts:
            sentences.append(f"{label}: " + "; ".join(parts) + ".")
    table = Table("One parameter changed at a time (the first row of each controller: the spec's design)",
                  ("controller", "change", "overshoot", "settling", "final error", "peak |u|", "TV(u)", "stable"),
                  tuple(rows))
    return Question("What is the importance of each controller parameter?", tuple(sentences), (table,))


def _structure(result: Any) -> Question:
    from designkit.families import family

    sentences = []
    for label, run in _runs(result):
        d = run.design
        law = d.law
        states = ", ".join(s.name for s in d.plant.states) if d.kind in (STATE_REGULATOR, VSC) else (
            "x1, x2 (motor)" if d.kind == PID_SM else "x3, x4 (link)")
        integ = (f"held over steps of at most {_f(law.max_step, 's')} (a switching law)" if law.discontinuous else
                 ("continuous, integrated with a step of at most " + _f(law.max_step, "s") if law.max_step else
                  "continuous"))
        lines = family(d.kind).display.law
        if d.kind == PID_SM and PID_SM_EXTRA in d.extra:
            lines = (d.formulas[0],)
        elif d.kind == PID and d.plant.kind == "elastic_joint":
            lines = ("u = −K1 (x3 − xD) − K2 x4 − K3 ∫(x3 − xD) dt + K3 K4 xD (the link's position and speed)",)
        sentences.append(f"{label} ({_WORDS.get(d.kind, d.kind)}): " + "; ".join(lines)
                         + f". It measures {states}, has {len(law.state_names)} controller state(s), is {integ}; its "
                         f"design needs: " + {
                             PID: "the rigid approximation and the PID pole/zero matching",
                             PID_SM: "the PID matching, a1 and a2 from the sliding poles, M over the sliding motions",
                             STATE_REGULATOR: "Ackermann's formula and the reference gain",
                             VSC: "c from the sliding poles (Ackermann for surfaces), the lᵢ ranges over the box "
                                  "and the gain certificate",
                         }.get(d.kind, "its family's synthesis") + ".")
    found = _by_kind(result, VSC)
    if found is not None:
        sentences.append(_surface_sentence(*found))
    return Question("What is the basic structure, and which algorithms does each need?", tuple(sentences))


def printed_c4(c: Any, tau2: float, k2: float) -> float:
    """Figure 5.3's ``c4`` as printed: its last term ``c1 J2/(c2 KR R2^2) = c1/(c2 k2)`` where the derivation gives
    ``c1/(tau2 k2)`` (docs/families/vsc.md); ``c`` the designed surface (``c2 = 1``)."""
    return float(c[3] + c[0] / (tau2 * k2) - c[0] / (c[1] * k2))


def _surface_sentence(label: str, run: Any) -> str:
    from designkit.families.vsc.surface import reduced_poles

    info = run.design.extra[VSC]
    c = np.asarray(info["c"], float)
    A, B, _ = (np.asarray(m, float) for m in info["nominal_model"])
    p = run.design.plant.params
    k2 = p.KR * p.R2**2 / p.J2
    wrong = c.copy()
    wrong[3] = printed_c4(c, p.tau2, k2)
    poles = ", ".join(_f(z.real, digits=4) if abs(z.imag) < 1e-9 else f"{_f(z.real, digits=4)} ± "
                      f"{_f(abs(z.imag), digits=4)}j" for z in reduced_poles(A, B, wrong) if z.imag >= -1e-9)
    return (f"{label}'s surface c = (" + ", ".join(_f(v, digits=5) for v in c) + ") is computed from the sliding "
            f"poles by Ackermann's formula for surfaces, which equals figure 5.3's closed form once its c4 is read "
            f"with τ2 where c2 is printed; the printed c4 = {_f(wrong[3], digits=5)} would put the sliding motion at "
            f"{poles} 1/s instead.")


def _compare(result: Any, chat: dict[str, Chatter], effects: dict[str, PerturbationEffect | None]) -> Question:
    keys = ("rms_error_before", "rise_time_before", "overshoot", "settling_time", "max_error_load", "peak_command",
            "rms_command", "rms_error_final")
    winners = [w.sentence for w in result.table.winners() if w.metric.key in keys]
    eu = result.table.error_unit
    sm = _by_kind(result, VSC)
    sentences = []
    for kind in (PID, STATE_REGULATOR):
        other = _by_kind(result, kind)
        if sm is None or other is None:
            continue
        (a, _), (b, _) = sm, other
        va, vb = result.table.row(a).values, result.table.row(b).values
        ea, eb = effects.get(a), effects.get(b)

        def ratio(x: float | None, y: float | None) -> str:
            return _f(x / y) if x is not None and y not in (None, 0) else "—"

        sentences.append(
            f"{a} against {_WORDS[kind]} ({b}): settles in {_f(va.get('settling_time'), 's')} against "
            f"{_f(vb.get('settling_time'), 's')}, with {ratio(va.get('peak_command'), vb.get('peak_command'))} times "
            f"its peak command and {ratio(chat[a].total_variation, chat[b].total_variation)} times its command's "
            f"total variation; the load leaves {_f(ea.final if ea else None, eu, 4)} against "
            f"{_f(eb.final if eb else None, eu, 4)}.")
    return Question("How does the sliding mode compare with the PID and the linear state regulator?",
                    (*sentences, "Metric by metric on the shared task (table above):", *winners))


def _perturbation(result: Any, effects: dict[str, PerturbationEffect | None]) -> Question:
    eu = result.table.error_unit
    rows, sentences = [], []
    for label, e in effects.items():
        if e is None:
            continue
        rows.append((label, _f(e.peak, eu, 4), _f(e.final, eu, 4), _f(e.predicted, eu, 4)))
        sentences.append(f"{label}: the {_f(e.value, 'N·m')} load from {_f(e.onset, 's')} moves the link by "
                         f"{_f(e.peak, eu, 4)} at most and leaves {_f(e.final, eu, 4)} (predicted static offset "
                         f"{_f(e.predicted, eu, 4)}).")
    table = Table("The load step's effect: |x − x0| against the same design's run without it",
                  ("controller", "largest", "left at the end", "predicted offset"), tuple(rows))
    return Question("How sensitive is each to an external perturbation?", tuple(sentences), (table,))


def _response(result: Any) -> Question:
    rows, sentences = [], []
    for label, run in _runs(result):
        edges = rise_times(run.simulation)
        rise = edges[0][1] if edges else None
        settle = result.table.row(label).values.get("settling_time")
        rows.append((label, _f(rise, "s"), _f(settle, "s")))
        sentences.append(f"{label}: 90 % of the step in {_f(rise, 's')}, settled (2 %) in {_f(settle, 's')}.")
    table = Table("Response time of the step", ("controller", "90 % rise time", "settling time"), tuple(rows))
    return Question("What is each controller's response time?", tuple(sentences), (table,))


def _level(result: Any, chat: dict[str, Chatter]) -> Question:
    t = result.table
    cu = t.command_unit
    sentences = tuple(f"{r.label}: peak |u| {_f(r.values.get('peak_command'), cu)}, RMS "
                      f"{_f(r.values.get('rms_command'), cu)}; the command reverses {chat[r.label].reversals} times "
                      f"({_f(chat[r.label].rate, '1/s')}), total variation {_f(chat[r.label].total_variation, cu)}."
                      for r in t.rows)
    return Question("What control level does each need, and how much does it chatter?", sentences)


def _robustness(result: Any, corners: dict[str, tuple[CornerRun, ...]]) -> Question:
    eu = result.table.error_unit
    spec = result.loaded.spec
    unc = spec.plant.uncertainty
    if unc is None:
        return Question("How robust is each to parameter changes?", ("The spec gives no parameter box.",))
    names = ", ".join(f"{k} in [{fmt_number(lo, 4)}, {fmt_number(hi, 4)}]" for k, (lo, hi) in unc.intervals.items())
    rows, sentences = [], [f"Each controller's law, designed for the nominal joint, was re-simulated on the true "
                           f"plant at every corner of the box ({names}), each corner starting at rest."]

    def span(values: list[float | None], unit: str) -> str:
        finite = [v for v in values if v is not None and math.isfinite(v)]
        if not finite:
            return "undefined"
        return f"{_f(min(finite), unit)} to {_f(max(finite), unit)}" + (
            "" if len(finite) == len(values) else f" ({len(values) - len(finite)} undefined)")

    for label, runs in corners.items():
        if not runs:
            continue
        worst = max(runs, key=lambda c: -1.0 if c.settling_time is None else c.settling_time)
        at = ", ".join(f"{k} = {fmt_number(v, 4)}" for k, v in worst.at.items())
        bounded = sum(c.bounded for c in runs)
        rows.append((label, f"{bounded} of {len(runs)}", span([c.overshoot for c in runs], "%"),
                     span([c.settling_time for c in runs], "s"), span([c.steady_state_error for c in runs], eu),
                     span([c.peak_command for c in runs], result.table.command_unit)))
        settle = span([c.settling_time for c in runs], "s")
        sentences.append(f"{label}: bounded at {bounded} of {len(runs)} corners; overshoot "
                         f"{span([c.overshoot for c in runs], '%')}, settling {settle} (longest at {at}).")
    evidence = {"lyapunov": "a Lyapunov function of the nominal loop", "robust_vertices": "every corner's linear loop "
                "stable", "vsc_gains": "theorem 3's conditions certified on the whole box", PID_SM_RELAY:
                "the relay above the equivalent control at every corner (simulated)"}
    for label, run in _runs(result):
        found = [f"{words} ({c.status})" for name, words in evidence.items() if (c := _check(run, name)) is not None]
        if found:
            sentences.append(f"{label}'s stability rests on: " + "; ".join(found) + ".")
    table = Table("The designed laws at the corners of the parameter box",
                  ("controller", "bounded", "overshoot", "settling time", "steady-state error", "peak |u|"),
                  tuple(rows))
    return Question("How robust is each to parameter changes (and how stable)?", tuple(sentences), (table,))


def section(result: Any) -> ReportSection | None:
    """The experiment's questions answered from the runs (None when a run is missing)."""
    if any(r.simulation is None for r in result.results):
        return None
    chat = {label: chattering(r.simulation) for label, r in _runs(result)}
    effects = {label: perturbation_effect(r) for label, r in _runs(result)}
    corners = {label: corner_runs(r) for label, r in _runs(result)}
    oat = {label: oat_runs(label, r) for label, r in _runs(result)}
    return ReportSection(
        anchor="lab-3-comparison", title="Lab experiment 3: sliding-mode control of the elastic joint (ROBEL)",
        intro="The experiment's questions, answered from the controllers' runs of the shared task and from "
              "re-simulations of them with one thing changed: the load removed, a corner of the parameter box, one "
              "controller parameter (numbers measured, not quoted).",
        questions=(_why(result, chat), _importance(result, oat), _structure(result), _compare(result, chat, effects),
                   _perturbation(result, effects), _response(result), _level(result, chat),
                   _robustness(result, corners)),
    )
