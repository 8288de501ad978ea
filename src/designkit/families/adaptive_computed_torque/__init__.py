"""Adaptive computed torque (notes section 4.4, Craig's multivariable adaptive computed torque).

Law (:mod:`designkit.families.adaptive_computed_torque.laws`)::

    Gamma = D^(q) (qD'' + K1 e + K2 e') + h^(q, qd) = W(q, qd, qD'' + K1 e + K2 e') P^,   e = qD - q
    P^_a' = K W_a(q, qd, qdd)' D^(q)^-1 (e + psi e')

``D^`` and ``h^`` are linear in the estimated parameters through the model layer's regressor
(:mod:`designkit.models.regressor`).  **Adapted**: the entries of the regressor's parameter vector the
spec names in ``controller.adapt`` (``m2``, ``Izz3``, ``fv1``, ...), starting at ``controller.initial``
(a mapping name -> value, wrong on purpose); **known**: every other entry, at the arm's true value.
The acceleration the update needs comes from ``controller.acceleration`` (``ideal``: an ideal
accelerometer; ``filtered``: a filtered velocity derivative of bandwidth ``controller.bandwidth``).

Gains: ``poles`` (a pair per joint, or one pair for all: ``K1 = p1 p2``, ``K2 = -(p1 + p2)``) or ``K1``,
``K2`` directly, per joint; ``psi`` (s) per joint, default ``2/K2`` (the SPR condition is ``psi K2 > 1``,
:mod:`~designkit.families.adaptive_computed_torque.spr`).  ``gain``: the adaptation gains ``K`` (one, or
one per adapted parameter); ``gain_matrix`` a full symmetric positive-definite ``K``, or ``combination`` ``T`` with
``gain`` diagonal on ``a = T p`` (:mod:`.gains`).  ``bounds`` (name -> ``[l, h]``) with ``delta``: the notes'
projection.  ``convergence``: the window, tolerance and floor of the tracking judgement.  Starting estimates no
arm has are warned (:mod:`.consistency`).

**Contract.**  ``Linearization("frozen")``: ``freeze(values)`` is the fixed computed torque with the
estimates held; the generic ``lyapunov`` check judges the loop frozen at the initial estimates and
``frozen_final`` at the final ones.  The family's own checks (:mod:`.checks`): the SPR certificate,
the tracking error's windowed maxima decreasing, the Lyapunov function of the adaptive loop non-increasing along the
run, and parameter convergence judged against the excitation indicator (:mod:`.excitation`).
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from designkit.errors import SpecError
from designkit.families.adaptive_computed_torque import laws as act
from designkit.families.adaptive_computed_torque.box import check_box
from designkit.families.adaptive_computed_torque.consistency import start_warnings
from designkit.families.adaptive_computed_torque.gains import ConvergenceSpec, Matrix, gain_parts
from designkit.families.adaptive_computed_torque.laws import (
    KIND,
    Adaptation,
    AdaptiveData,
    Convergence,
    Freezer,
    parameter_units,
    state_name,
)
from designkit.families.adaptive_computed_torque.spr import default_psi
from designkit.families.adaptive_computed_torque.words import unit_text
from designkit.spec.fields import Finite, NonNegativeFinite, Section, check_conjugates, parse_pole, per_joint
from designkit.spec.ranges import Ranged, RangedPerJoint, check_poles
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import Knob
from designkit.synthesis.linearization import Linearization

GAIN_RANGE = (1e-12, 1e12)
PARAMETER_RANGE = 1e6


class AdaptiveComputedTorqueSpec(Section):
    """Adaptive computed torque (notes section 4.4).

    ``poles``: two error poles (1/s) for every joint, or a pair per joint; or ``K1`` (1/s^2) and ``K2`` (1/s),
    one value or one per joint, 1e-12 to 1e12.  ``psi`` (s, 1e-12 to 1e12, one or one per joint; default
    ``2/K2``).  ``adapt``: the regressor parameters to adapt (``m1``, ``mcx2``, ``Izz3``, ``fv1``, ...);
    ``initial``: the estimate of each at ``t = 0``; ``gain``: adaptation gains (1e-12 to 1e12, one or one per
    adapted parameter); ``bounds``: ``[l, h]`` per adapted parameter (optional projection) with ``delta`` (its
    hysteresis, in each parameter's unit); ``acceleration``: ``ideal`` or ``filtered`` (with ``bandwidth``,
    rad/s, 1e-3 to 1e6).  ``gain_matrix``: instead of ``gain``, the full adaptation gain (rows, symmetric positive
    definite); ``combination``: ``T`` (rows, invertible) with ``gain`` then diagonal on ``a = T p``
    (:mod:`~designkit.families.adaptive_computed_torque.gains`).  ``convergence``: ``window``, ``tolerance`` and
    ``floor`` of the tracking-convergence judgement (:class:`~.gains.ConvergenceSpec`).
    """

    step_fields: ClassVar[dict[str, int]] = {"bandwidth": -1}
    """Fields that set the law's largest step (name -> +1: the step grows with it, -1: shrinks), first given
    first: the step-bound refusal names it (:func:`designkit.simulation.timing.step_field`)."""

    kind: Literal[KIND]
    poles: list[Any] | None = Field(default=None, description="Two error poles (1/s) for every joint, or a pair "
                                    "per joint.")
    K1: RangedPerJoint(1e-12, 1e12, "1/s^2") | None = None
    K2: RangedPerJoint(1e-12, 1e12, "1/s") | None = None
    psi: RangedPerJoint(1e-12, 1e12, "s") | None = None
    adapt: list[str] = Field(min_length=1, description="Regressor parameters to adapt (m1, mcx2, Izz3, fv1, ...).")
    initial: dict[str, Finite] = Field(description="Initial estimate of every adapted parameter.")
    gain: Finite | list[Finite] = Field(default=1.0, description="Adaptation gains K (> 0).")
    bounds: dict[str, list[Finite]] | None = None
    delta: Ranged(1e-12, 1e6, "", zero=True, base=NonNegativeFinite) = 0.0
    acceleration: Literal["ideal", "filtered"] = "ideal"
    bandwidth: Ranged(1e-3, 1e6, "rad/s") = 200.0
    scheme: Literal["craig", "slotine_li"] = "craig"
    Lambda: RangedPerJoint(1e-12, 1e12, "1/s") | None = None
    KD: RangedPerJoint(1e-12, 1e12, "N*m*s/rad") | None = None
    gain_matrix: Matrix | None = Field(default=None, description="Full adaptation gain K (symmetric positive "
                                       "definite), rows in the order of adapt.")
    combination: Matrix | None = Field(default=None, description="T: gain is diagonal on a = T p (rows in the "
                                       "order of adapt; invertible).")
    convergence: ConvergenceSpec = Field(default_factory=ConvergenceSpec)

    @field_validator("poles")
    @classmethod
    def _pole_pairs(cls, v: list[Any] | None) -> list[Any] | None:
        if v is None:
            return v
        nested = [isinstance(p, list | tuple) for p in v]
        if any(nested) and not all(nested):
            raise ValueError("give two poles, or a list of two poles per joint, not a mix")
        rows = v if all(nested) else [v]
        pairs = []
        for i, row in enumerate(rows):
            where = f"[{i}]" if all(nested) else ""
            if len(row) != 2:
                raise ValueError(f"{where}{': ' if where else ''}must list exactly 2 poles per joint, got {len(row)}")
            poles = []
            for k, p in enumerate(row):
                try:
                    poles.append(parse_pole(p))
                except ValueError as exc:
                    raise ValueError(f"{where}[{k}]: {exc}") from None
            check_poles(poles, where)
            check_conjugates(poles)
            pairs.append(poles)
        return pairs if all(nested) else pairs[0]

    @field_validator("adapt")
    @classmethod
    def _unique(cls, v: list[str]) -> list[str]:
        seen = set()
        for k, name in enumerate(v):
            if name in seen:
                raise ValueError(f"[{k}]: {name!r} is listed twice")
            seen.add(name)
        return v

    @field_validator("gain")
    @classmethod
    def _gain(cls, v: Any) -> Any:
        values = list(v) if isinstance(v, list | tuple) else [v]
        for k, x in enumerate(values):
            where = f"[{k}]: " if isinstance(v, list | tuple) else ""
            if not x > 0:
                raise ValueError(f"{where}must be positive (an adaptation gain), got {x:g}")
            if not GAIN_RANGE[0] <= x <= GAIN_RANGE[1]:
                raise ValueError(f"{where}must be between 1e-12 and 1e12, got {x:g}")
        return v

    @model_validator(mode="after")
    def _consistent(self) -> AdaptiveComputedTorqueSpec:
        direct = self.K1 is not None or self.K2 is not None
        if self.scheme == "slotine_li":
            for name in ("poles", "K1", "K2", "psi"):
                if getattr(self, name) is not None:
                    raise ValueError(f"{name}: not a gain of the Slotine-Li scheme (it takes Lambda and KD)")
            for name in ("Lambda", "KD"):
                if getattr(self, name) is None:
                    raise ValueError(f"{name}: required by the Slotine-Li scheme")
            if "acceleration" in self.model_fields_set:
                raise ValueError("acceleration: the Slotine-Li scheme needs no acceleration")
        elif self.Lambda is not None or self.KD is not None:
            raise ValueError(f"{'Lambda' if self.Lambda is not None else 'KD'}: a gain of scheme: slotine_li only")
        if self.scheme != "slotine_li" and direct == (self.poles is not None):
            raise ValueError("give either poles, or K1 and K2")
        if direct and (self.K1 is None or self.K2 is None):
            raise ValueError(f"{'K2' if self.K2 is None else 'K1'}: K1 and K2 go together")
        for name in self.adapt:
            if name not in self.initial:
                raise ValueError(f"initial: no initial estimate of the adapted parameter {name!r}")
        for name in self.initial:
            if name not in self.adapt:
                raise ValueError(f"initial.{name}: not an adapted parameter (controller.adapt lists {self.adapt})")
            if abs(self.initial[name]) > PARAMETER_RANGE:
                raise ValueError(f"initial.{name}: must be within 1e6 in magnitude, got {self.initial[name]:g}")
        for name in ("gain_matrix", "combination"):
            for i, row in enumerate(getattr(self, name) or ()):
                for j, x in enumerate(row):
                    if abs(x) > GAIN_RANGE[1]:
                        raise ValueError(f"{name}[{i}][{j}]: must be within 1e12 in magnitude, got {x:g}")
        gain_parts(self.gain, self.gain_matrix, self.combination, len(self.adapt), "gain" in self.model_fields_set)
        for name, pair in (self.bounds or {}).items():
            if name not in self.adapt:
                raise ValueError(f"bounds.{name}: not an adapted parameter (controller.adapt lists {self.adapt})")
            if len(pair) != 2:
                raise ValueError(f"bounds.{name}: must be [l, h], got {len(pair)} numbers")
            lo, hi = pair
            if lo > hi:
                raise ValueError(f"bounds.{name}: l = {lo:g} > h = {hi:g}")
            if not lo <= self.initial[name] <= hi:
                raise ValueError(f"initial.{name}: the initial estimate {self.initial[name]:g} is outside its bounds "
                                 f"[{lo:g}, {hi:g}]")
        return self


def _joint_list(value: Any, n: int, path: str) -> tuple[float, ...]:
    try:
        return per_joint(value, n, path)
    except ValueError as exc:
        key, msg = str(exc).split(": ", 1)
        raise SpecError(key, msg) from None


def gains_of(spec: Any, n: int) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...], str]:
    """``(K1, K2, psi, how)`` per joint from the spec (``how`` says where ``psi`` came from)."""
    c = spec.controller
    if c.poles is not None:
        pairs = c.poles if isinstance(c.poles[0], list) else [c.poles] * n
        if len(pairs) != n:
            raise SpecError("controller.poles", f"needs one pair of poles per joint ({n}), got {len(pairs)}")
        K1 = tuple(float((p1 * p2).real) for p1, p2 in pairs)
        K2 = tuple(float((-(p1 + p2)).real) for p1, p2 in pairs)
    else:
        K1 = _joint_list(c.K1, n, "controller.K1")
        K2 = _joint_list(c.K2, n, "controller.K2")
    if c.psi is not None:
        return K1, K2, _joint_list(c.psi, n, "controller.psi"), "given by the spec"
    return K1, K2, tuple(default_psi(k) for k in K2), "chosen as 2/K2 (SPR margin ψ K2 − 1 = 1)"


def adaptation(spec: Any, plant: Any) -> Adaptation:
    """The :class:`~.laws.Adaptation` a spec asks for on ``plant`` (names checked against the robot)."""
    c = spec.controller
    n = plant.n_joints
    known = list(plant.robot.parameter_names)
    for k, name in enumerate(c.adapt):
        if name not in known:
            raise SpecError(f"controller.adapt[{k}]", f"the robot has no parameter {name!r}; its parameters are "
                            f"{', '.join(known)}")
    if c.scheme == "slotine_li":
        K1 = K2 = psi = ()
        Lambda = _joint_list(c.Lambda, n, "controller.Lambda")
        KD = _joint_list(c.KD, n, "controller.KD")
    else:
        K1, K2, psi, _ = gains_of(spec, n)
        Lambda = KD = ()
    try:
        gains, K, T, G = gain_parts(c.gain, c.gain_matrix, c.combination, len(c.adapt), "gain" in c.model_fields_set)
    except ValueError as exc:
        key, msg = str(exc).split(": ", 1)
        raise SpecError(f"controller.{key}", msg) from None
    bounds = None
    if c.bounds:
        bounds = tuple(tuple(float(x) for x in c.bounds[name]) if name in c.bounds else (-np.inf, np.inf)
                       for name in c.adapt)
    acceleration = "none" if c.scheme == "slotine_li" else c.acceleration
    return Adaptation(names=tuple(c.adapt), initial=tuple(float(c.initial[x]) for x in c.adapt),
                      gain=tuple(float(g) for g in gains), K1=K1, K2=K2, psi=psi, acceleration=acceleration,
                      bandwidth=float(c.bandwidth), bounds=bounds, delta=float(c.delta), scheme=c.scheme, Lambda=Lambda,
                      KD=KD, gain_matrix=K, combination=T, combination_gain=G)


def _gain_unit(unit: str) -> str:
    """The unit of an adaptation gain for a parameter in ``unit``: ``unit^2 s/rad^2`` (``P^' = K W' D^-1 e1``)."""
    if not unit:
        return "s/rad^2"
    return (f"({unit})^2" if "*" in unit or "/" in unit else f"{unit}^2") + "*s/rad^2"


def _scheme_parts(spec: Any, a: Adaptation) -> tuple[list[Gain], list[str], tuple[str, ...], tuple[complex, ...]]:
    """The gains, the scheme's notes, formulas and requested poles."""
    if a.scheme == "slotine_li":
        gains = [Gain("Lambda", list(a.Lambda), "1/s", "s = ė + Λ e: the sliding variable's error pole"),
                 Gain("KD", list(a.KD), "N*m*s/rad", "damping on s")]
        notes = ["Slotine-Li scheme: no acceleration and no inverse of the estimated inertia are needed; there is no "
                 "SPR filter to certify (the passivity of the arm takes its place)."]
        formulas = ("q̇r = q̇D + Λ e,  q̈r = q̈D + Λ ė,  s = ė + Λ e,  e = qD − q",
                    "Γ = Y(q, q̇, q̇r, q̈r) P̂ + KD s = D̂ q̈r + Ĉ q̇r + ĝ + F̂ + KD s",
                    "P̂ₐ' = K Yₐᵀ s",
                    "D ṡ + (C + KD) s = Y (P − P̂);  V = ½ sᵀ D s + ½ (P − P̂)ᵀ K⁻¹ (P − P̂),  V' = −sᵀ KD s")
        return gains, notes, formulas, tuple(-float(x) for x in a.Lambda)
    _, _, _, how = gains_of(spec, len(a.K1))
    gains = [Gain("K1", list(a.K1), "1/s^2", "position error gain"),
             Gain("K2", list(a.K2), "1/s", "velocity error gain"),
             Gain("psi", list(a.psi), "s", "velocity weight of e1 = e + ψ ė (the SPR filter)")]
    notes = [f"ψ {how}; SPR needs ψ > 1/K2: " + ", ".join(f"{1 / k:.4g} s" for k in a.K2) + " per joint.",
             {"ideal": "Acceleration for the update: an ideal accelerometer (the arm's own acceleration at the "
                       "command).",
              "filtered": f"Acceleration for the update: the measured velocity differentiated through a first-order "
                          f"filter of bandwidth {a.bandwidth:g} rad/s."}[a.acceleration]]
    formulas = ("v = q̈D + K1 e + K2 ė,  e = qD − q",
                "Γ = D̂(q) v + ĥ(q, q̇) = W(q, q̇, v) P̂",
                "P̂ₐ' = K Wₐ(q, q̇, q̈)ᵀ D̂(q)⁻¹ (e + ψ ė)",
                "ë + K2 ė + K1 e = D̂⁻¹ W(q, q̇, q̈) (P − P̂);  H(s) = (1 + ψ s)/(s² + K2 s + K1) SPR ⇔ ψ K2 > 1")
    poles = tuple(p for k1, k2 in zip(a.K1, a.K2, strict=True) for p in np.roots([1.0, k2, k1]))
    return gains, notes, formulas, poles


def _convergence(spec: Any) -> Convergence:
    """``controller.convergence`` as the checks read it; a window longer than half the run is refused (the judgement
    compares at least two windows)."""
    c = spec.controller.convergence
    duration = getattr(spec.simulation, "duration", None)
    if c.window is not None and duration is not None and 2 * c.window > float(duration) * (1 + 1e-12):
        raise SpecError("controller.convergence.window", f"{c.window:g} s is longer than half the run "
                        f"({float(duration):g} s): the judgement compares at least two windows")
    return Convergence(window=None if c.window is None else float(c.window), tolerance=float(c.tolerance),
                       floor=float(c.floor))


def _gain_notes(a: Adaptation) -> list[str]:
    """The full adaptation gain in words when it is not diagonal."""
    if a.gain_matrix is None:
        return []

    def rows(M: Any) -> str:
        return "[" + "; ".join(" ".join(f"{x:.6g}" for x in r) for r in M) + "]"

    order = ", ".join(a.names)
    if a.combination is not None:
        return [f"Adaptation gain diagonal on the combinations a = T p (p = {order}): T = {rows(a.combination)}, "
                f"gains on a {', '.join(f'{g:.6g}' for g in a.combination_gain)}; on p, K = T⁻¹ G T⁻ᵀ = "
                f"{rows(a.gain_matrix)} (the K_ entries of the gain table are its diagonal)."]
    return [f"Adaptation gain K (p = {order}) = {rows(a.gain_matrix)}, symmetric positive definite (the K_ entries "
            "of the gain table are its diagonal)."]


def synthesize(spec: Any, plant: Any) -> Design:
    """The adaptive computed torque a spec asks for (module docstring) on the arm ``plant``."""
    a = adaptation(spec, plant)
    check_box(spec, plant, tuple(a.names))
    n = plant.n_joints
    units = parameter_units(a.names)
    true = act.true_parameters(plant)
    idx = [list(plant.robot.parameter_names).index(x) for x in a.names]
    scheme_gains, scheme_notes, formulas, poles = _scheme_parts(spec, a)
    gains = Gains.of([*scheme_gains, *(Gain(f"K_{x}", g, _gain_unit(u), f"adaptation gain of {x}")
                                       for x, g, u in zip(a.names, a.gain, units, strict=True))])
    notes = [scheme_notes[0],
             "Adapted: " + ", ".join(f"{x} (from {v:.6g} {unit_text(u)}; true {true[i]:.6g} {unit_text(u)})"
                                     for x, v, u, i in zip(a.names, a.initial, units, idx, strict=True))
             + "; every other parameter of the regressor is known (the arm's true value).", *scheme_notes[1:],
             *_gain_notes(a)]
    warned = start_warnings(plant, a.names, a.initial)
    q0 = np.zeros(n)
    if spec.simulation.initial_position is not None:
        q0 = np.array(_joint_list(spec.simulation.initial_position, n, "simulation.initial_position"))
    design = Design(
        kind=KIND, plant=plant, gains=gains, poles=poles, reference="trajectory", formulas=formulas,
        notes=tuple(notes),
        data=AdaptiveData(adaptation=a, units=tuple(units), true=tuple(float(true[i]) for i in idx),
                          convergence=_convergence(spec), start_warnings=warned),
    )
    held = (a.Lambda, a.KD) if a.scheme == "slotine_li" else (a.K1, a.K2)
    lin = Linearization("frozen", reason="the law with the estimated parameters held (no adaptation)",
                        parameters=tuple(state_name(x) for x in a.names), initial=a.initial, units=units,
                        freeze=Freezer(plant, a.names, *held, a.scheme))
    return with_closed_loop(design, act.adaptive_law(plant, a), np.concatenate([q0, np.zeros(2 * n)]),
                            field="simulation.initial_position", linearization=lin)


def law(design: Design, anti_windup: Any = None) -> Any:
    """The adaptive law of ``design`` (its settings from ``design.data``)."""
    return act.adaptive_law(design.plant, design.data.adaptation)


def validate(spec: Any) -> None:
    """Cross-section rules: no anti-windup (no integral), no controller-model section."""
    if spec.simulation.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the adaptive computed torque has no integral to limit")


def _family() -> Family:
    from designkit.families.adaptive_computed_torque import checks, diagnoses, figures, report

    return Family(
        kind=KIND, spec=AdaptiveComputedTorqueSpec, plants=("robot",), reference="trajectory",
        uses=("plant.uncertainty", "plant.uncertainty.samples"), box_design="each",
        synthesize=synthesize, law=law,
        checks=("lyapunov", "frozen_final", "time_domain", "torque_limits", "box_runs", *checks.RULES),
        display=Display(
            label="Adaptive computed torque",
            law=("Craig (the default scheme): Γ = D̂(q) (q̈D + K1 e + K2 ė) + ĥ(q, q̇) = W(q, q̇, q̈D + K1 e + K2 ė) P̂,  "
                 "e = qD − q;  P̂ₐ' = K Wₐ(q, q̇, q̈)ᵀ D̂(q)⁻¹ (e + ψ ė)",
                 "Slotine–Li (scheme slotine_li): Γ = Y(q, q̇, q̇r, q̈r) P̂ + KD s,  q̇r = q̇D + Λ e,  s = ė + Λ e;  "
                 "P̂ₐ' = K Yₐᵀ s",
                 "P̂ₐ: the adapted parameters; every other parameter of the arm is known"),
            summary="Notes §4.4 (Craig 1988): computed torque whose model parameters are estimated on line from the "
                    "filtered tracking error e + ψ ė, the filter (1 + ψ s)/(s² + K2 s + K1) strictly positive "
                    "real; or the Slotine–Li passivity-based law, which needs neither the acceleration nor D̂⁻¹."),
        validate=validate, figures=figures.FIGURES, sections=(report.section,), json=report.json,
        knobs=(Knob("gain", "", "adaptation gain K of the parameter update", 1e-9, 1e9, path="controller.gain",
                    role="adaptation", boundary=True,
                    when=lambda d: d.data.adaptation.gain_matrix is None or d.data.adaptation.combination is not None),
               Knob("psi", "s", "ψ of the error filter e + ψ ė (strictly positive real when ψ K2 > 1)", 1e-9, 1e9,
                    path="controller.psi", current=lambda d: d.gains["psi"], when=lambda d: "psi" in d.gains)),
        traits=("adaptive", "model_based"),
        diagnoses=(diagnoses.diagnose,),
    )


FAMILY = _family()
