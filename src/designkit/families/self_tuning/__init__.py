"""Self-tuning regulator of one link (notes section 4.3, the SELFTUNE simulator, figures 4.1 and 4.2): ``self_tuning``.

Plant: the link ``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)``.  Controller: a sampled law
(period ``controller.sampling_period``) that at each sample

1. estimates the parameters of the exactly (zero-order-hold) discretized link by recursive least
   squares with forgetting factor ``lambda``, in either form of the appendix -- speed measured
   (``theta = [A22, B2]``) or not (position differences, ``theta = [A22, B1, B2 A12 - B1 A22]``)
   (:mod:`designkit.families.self_tuning.model`);
2. redesigns the controller for the estimated model (certainty equivalence): pole placement by the
   Diophantine equation ``A R + B S = Am Ao`` (``design: pole_placement``), or the one-link PID
   placing three continuous poles on the estimated ``Km``, ``tau`` (``design: pid``);
3. computes the command, held until the next sample.

It is one :func:`~designkit.synthesis.law.dynamic_law` with discrete memory
(:mod:`designkit.families.self_tuning.laws`) that declares its sampling period, so the simulation
samples it there.

**Contract.**  ``Linearization("none")``: the law is a difference equation in its memory (past inputs
and outputs, estimates, covariance); the generic linear checks linearize continuous-time laws in
``(y, xc)`` and would see a constant command.  The loop that *is* linear -- the estimated discrete
model under the controller designed for it -- is checked by the family's own rules
(:mod:`designkit.families.self_tuning.checks`) on the discrete closed loop, sample by sample.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from designkit.families.self_tuning.data import SelfTuningData
from designkit.families.self_tuning.laws import KIND, Settings, self_tuning_law
from designkit.families.self_tuning.model import PARAMETER_NAMES, PARAMETER_UNITS, theta_of
from designkit.spec.fields import Pole, PositiveFinite, Section, check_conjugates
from designkit.spec.ranges import Ranged, check_poles
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import Knob
from designkit.synthesis.linearization import Linearization

__all__ = ["FAMILY", "SelfTuningSpec", "law", "synthesize"]

REASON = ("the self-tuning regulator is a sampled difference equation in its memory (estimates, covariance, past "
          "inputs and outputs): a continuous-time linearization in (y, xc) does not describe it; its discrete "
          "closed loop is checked sample by sample by the family's own checks")
MIN_WINDOW_SAMPLES = 10
"""The excitation window spans at least this many samples."""


class NominalLink(Section):
    """The link the initial estimates are the exact ZOH parameters of: ``Km`` ((rad/s)/(N*m)) and ``tau`` (s),
    1e-6 to 1e6 each; a missing one is the spec's plant's."""

    Km: Ranged(1e-6, 1e6, "(rad/s)/(N*m)", base=PositiveFinite) | None = None
    tau: Ranged(1e-6, 1e6, "s", base=PositiveFinite) | None = None


class SelfTuningSpec(Section):
    """Self-tuning regulator (RLS with forgetting and a certainty-equivalence design, notes section 4.3).

    ``sampling_period`` (s, required): the period the regulator is designed and run at.  ``estimator``:
    ``speed`` (speed measured, fig. 4.1) or ``position`` (position differences, fig. 4.2).
    ``forgetting``: ``lambda`` in (0, 1].  ``initial_covariance``: ``P(0) = p I``, > 0.  ``max_trace``: the
    covariance bound (default ``n p``, the initial trace).  ``safeguards``: the covariance bound and the
    controller hold (default true).  ``design``: ``pole_placement`` (``poles``: two, 1/s, plus ``observer``,
    1/s, default twice the fastest pole's modulus) or ``pid`` (``poles``: three).  ``nominal``: the link the
    initial estimates come from (default the spec's plant).  ``excitation_window`` (s): the window of the
    excitation indicator.
    """

    kind: Literal[KIND]
    sampling_period: Ranged(1e-5, 10.0, "s", base=PositiveFinite) = Field(
        description="Sampling period of the regulator (s).")
    estimator: Literal["speed", "position"] = "speed"
    forgetting: Ranged(0.0, 1.0, "", low_open=True) = 0.99
    initial_covariance: Ranged(0.0, 1e12, "", low_open=True) = 1000.0
    max_trace: Ranged(0.0, 1e15, "", low_open=True) | None = None
    safeguards: bool = True
    design: Literal["pole_placement", "pid"] = "pole_placement"
    poles: list[Pole] = Field(description="Requested continuous closed-loop poles (1/s).")
    observer: Ranged(-1e6, 0.0, "1/s", high_open=True) | None = None
    nominal: NominalLink | None = None
    excitation_window: Ranged(1e-4, 1e6, "s", base=PositiveFinite) = 2.0

    @field_validator("poles")
    @classmethod
    def _poles(cls, v: list[complex]) -> list[complex]:
        check_poles(v)
        check_conjugates(v)
        return v

    @model_validator(mode="after")
    def _shape(self) -> SelfTuningSpec:
        need = 2 if self.design == "pole_placement" else 3
        if len(self.poles) != need:
            why = ("the pole-placement loop is A R + B S = Am Ao with Am of degree 2 (and the observer pole)"
                   if need == 2 else "the PID loop on the link is third order")
            raise ValueError(f"poles: must list exactly {need} poles for design {self.design}, got "
                             f"{len(self.poles)}: {why}")
        if self.design == "pid" and self.observer is not None:
            raise ValueError("observer: only the pole-placement design has an observer pole")
        if self.excitation_window < MIN_WINDOW_SAMPLES * self.sampling_period:
            raise ValueError(f"excitation_window: {self.excitation_window:g} s spans fewer than {MIN_WINDOW_SAMPLES} "
                             f"samples of {self.sampling_period:g} s")
        return self


def validate(spec: Any) -> None:
    """Cross-section rules: no anti-windup; the run must be long enough for the excitation window."""
    c, sim = spec.controller, spec.simulation
    if sim.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the self-tuning regulator has no continuous integral to limit")
    if sim.duration is not None and c.excitation_window > sim.duration:
        raise ValueError(f"controller.excitation_window: {c.excitation_window:g} s is longer than "
                         f"simulation.duration = {sim.duration:g} s: the run is too short for the excitation window")
    traj = sim.trajectory
    if sim.duration is not None and traj is not None and getattr(traj, "period", None) is not None \
            and sim.duration < 2 * float(traj.period):
        raise ValueError(f"simulation.duration: {sim.duration:g} s covers fewer than two periods of the "
                         f"{traj.kind} reference ({float(traj.period):g} s): too short to excite the estimator")
    if sim.plant_change is not None and sim.duration is not None \
            and sim.plant_change.time + c.excitation_window > sim.duration:
        raise ValueError(f"simulation.plant_change.time: {sim.plant_change.time:g} s leaves less than "
                         f"controller.excitation_window = {c.excitation_window:g} s of the run after the change")


def _nominal(spec: Any, plant: Any) -> Any:
    nominal = spec.controller.nominal
    if nominal is None:
        return plant
    values = {k: v for k, v in (("Km", nominal.Km), ("tau", nominal.tau)) if v is not None}
    return plant.with_params(**values) if values else plant


def link_values(plant: Any) -> tuple[float, float]:
    """``(Km, tau)`` of a link plant."""
    return float(plant.parameter("Km").value), float(plant.parameter("tau").value)


def settings_of(spec: Any, plant: Any) -> Settings:
    """The law's :class:`~designkit.families.self_tuning.laws.Settings` from the spec."""
    c = spec.controller
    Km, tau = link_values(_nominal(spec, plant))
    Ts = float(c.sampling_period)
    theta0 = theta_of(Km, tau, Ts, c.estimator)
    n = len(theta0)
    P0 = float(c.initial_covariance)
    observer = (float(c.observer) if c.observer is not None else
                -2.0 * max(abs(complex(p)) for p in c.poles)) if c.design == "pole_placement" else 0.0
    return Settings(form=c.estimator, Ts=Ts, forgetting=float(c.forgetting), P0=P0, theta0=theta0,
                    max_trace=float(c.max_trace) if c.max_trace is not None else n * P0, safeguards=bool(c.safeguards),
                    design=c.design, poles=tuple(complex(p) for p in c.poles), observer=observer)


def synthesize(spec: Any, plant: Any) -> Design:
    """The self-tuning regulator a spec asks for (module docstring)."""
    st = settings_of(spec, plant)
    nominal = _nominal(spec, plant)
    notes = []
    if spec.controller.nominal is None:
        notes.append("No nominal link given: the initial estimates are the exact parameters of the spec's plant.")
    return design(nominal, st, excitation_window=float(spec.controller.excitation_window), notes=tuple(notes))


def design(nominal: Any, st: Settings, *, excitation_window: float = 2.0, notes: tuple[str, ...] = ()) -> Design:
    """The self-tuning design for ``st`` on the link layout of ``nominal``.

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> from designkit.families.self_tuning.model import theta_of
    >>> st = Settings("speed", 0.01, 0.99, 100.0, theta_of(2.0, 0.5, 0.01, "speed"), 200.0, True,
    ...               "pole_placement", (-4.0, -5.0), -10.0)
    >>> d = design(LinkPlant(Km=2.0, tau=0.5), st)
    >>> d.linearization.kind, d.law.sampling_period, d.law.memory_names[:2]
    ('none', 0.01, ('th1', 'th2'))
    """
    from designkit.families.self_tuning.laws import initial_controller

    Km, tau = link_values(nominal)
    names, units = PARAMETER_NAMES[st.form], PARAMETER_UNITS[st.form]
    coefs = initial_controller(st)
    gains = [Gain("Ts", st.Ts, "s", "sampling period"), Gain("λ", st.forgetting, "", "forgetting factor"),
             Gain("P(0)", st.P0, "", "initial covariance (times the identity)"),
             Gain("tr P max", st.max_trace, "", "covariance bound (trace)" + ("" if st.safeguards else ", off"))]
    if st.design == "pole_placement":
        gains += [Gain(n_, v, u, w) for n_, v, u, w in zip(
            ("R1", "S0", "S1", "T0"), coefs, ("", "N*m/rad", "N*m/rad", "N*m/rad"),
            ("R(z) = z + R1, at the initial estimates", "S(z) = S0 z + S1", "S(z) = S0 z + S1",
             "T(z) = T0 (z − zo)"), strict=True)]
    else:
        gains += [Gain("K1", coefs[0], "N*m/rad", "proportional, at the initial estimates"),
                  Gain("K2", coefs[1], "N*m*s/rad", "rate feedback, at the initial estimates"),
                  Gain("K3", coefs[2], "N*m/(rad*s)", "integral, at the initial estimates")]
    data = SelfTuningData(settings=st, parameters=tuple(names), units=tuple(units), nominal=(Km, tau),
                          excitation_window=excitation_window,
                          desired=tuple(st.desired()) if st.design == "pole_placement" else None)
    formulas = (
        "x(k+1) = A x(k) + B u(k),  A = e^(F Ts),  B = ∫₀^Ts e^(F s) ds b  (exact zero-order hold)",
        ("x2(k) = A22 x2(k−1) + B2 u(k−1)" if st.form == "speed" else
         "Δx1(k) = A22 Δx1(k−1) + B1 u(k−1) + (B2 A12 − B1 A22) u(k−2)"),
        "θ ← θ + P φ (y − φᵀθ)/(λ + φᵀPφ),  P ← (P − P φ φᵀ P/(λ + φᵀPφ))/λ",
        ("A R + B S = Am Ao  (Sylvester system, solved each sample)" if st.design == "pole_placement" else
         "K2 = (τ̂ c1 − 1)/K̂m,  K1 = τ̂ c2/K̂m,  K3 = τ̂ c3/K̂m  (each sample)"),
    )
    poles = tuple(complex(p) for p in st.poles) + ((complex(st.observer),) if st.design == "pole_placement" else ())
    d = Design(kind=KIND, plant=nominal, gains=Gains.of(gains), poles=poles, reference="step", formulas=formulas,
               notes=notes, data=data)
    return with_law(d, self_tuning_law(nominal, st), Linearization("none", reason=REASON))


def law(design: Design, anti_windup: Any = None) -> Any:
    """The self-tuning law of ``design`` (rebuilt from its :class:`Settings`)."""
    return self_tuning_law(design.plant, settings_from(design))


def settings_from(design: Design) -> Settings:
    """The :class:`Settings` the design's law is made of (its :class:`SelfTuningData`)."""
    return design.data.settings


def _family() -> Family:
    from designkit.families.self_tuning import answers, checks, figures, report

    return Family(
        kind=KIND, spec=SelfTuningSpec, plants=("link",), reference="step", synthesize=synthesize, law=law,
        uses=("plant.uncertainty", "plant.uncertainty.samples"),
        checks=("time_domain", "box_runs", *checks.RULES),
        display=Display(
            label="Self-tuning regulator (RLS and certainty-equivalence design)",
            law=("θ̂(k) = θ̂(k−1) + K(k) (y(k) − φ(k)ᵀ θ̂(k−1))  (recursive least squares, forgetting λ)",
                 "R̂(z) u = T̂(z) xD − Ŝ(z) x1,  Â R̂ + B̂ Ŝ = Am Ao  (pole placement on the estimated model)",
                 "or u = −K̂1 (x1 − xD) − K̂2 x2 − K̂3 Σ Ts (x1 − xD)  (PID on the estimated Km, τ)"),
            summary="Notes §4.3 and the SELFTUNE simulator: a sampled regulator that estimates the link's discrete "
                    "model by recursive least squares and redesigns itself for the estimate at every sample."),
        validate=validate, references=("step", "square", "prbs"),
        figures=figures.FIGURES, sections=(report.section,), diagnoses=(checks.diagnose,), json=report.json,
        knobs=(Knob("forgetting", "", "forgetting factor λ of the least squares (1 − λ sets its memory)", 0.5, 1.0,
                    path="controller.forgetting", role="forgetting", boundary=True),
               Knob("poles", "1/s", "requested closed-loop poles of the certainty-equivalence design", 1e-3, 1e6,
                    path="controller.poles"),
               Knob("sampling_period", "s", "the regulator's sampling period", 1e-5, 10.0,
                    path="controller.sampling_period")),
        traits=("adaptive", "certainty_equivalence"),
        answers=answers.ANSWERS,
        variants=answers.VARIANTS,
    )


FAMILY = _family()
