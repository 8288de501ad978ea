"""Iterative learning control on computed torque (notes section 6): the ``ilc`` family.

A robot repeats one trajectory.  Each trial runs computed torque with the trial's learned acceleration
``d_k`` (rad/s^2 per joint and instant) inside the model's inverse dynamics::

    u = M^(q) (qD'' + K1 e + K2 e' + d_k) + h^(q, qd),     e = qD - q

and between trials the learning module updates ``d_{k+1} = d_k + Q e_k`` (notes 6.2).  With ``M^ = M`` the error
of each joint obeys ``e'' + K2 e' + K1 e = d - d_k`` with ``d = M^-1 f`` the input-equivalent perturbation
(``f`` what the model misses), so ``e_k = H (d - d_k)``, ``H(s) = 1/(s^2 + K2 s + K1)``, and the update
contracts ``d - d_k`` by ``I - Q H``.  The lifted (sampled, finite-horizon) ``H`` and its structure are in
:mod:`~designkit.families.ilc.lifted`, the operators ``Q`` and the certificate ``||I - Q H||_2 < 1`` in
:mod:`~designkit.families.ilc.operators`, the trial-to-trial update in :mod:`~designkit.families.ilc.learning`.

When ``M^ != M`` the notes' algebra does not hold: the arm's acceleration is ``Delta (a* + d_k) + M^-1 (h^ - h
+ f)`` with ``Delta = M^-1 M^``, so the learned signal reaches the error through ``H Delta(q)`` -- coupled
between joints by the off-diagonal entries of ``Delta`` and varying along the path -- the feedback gains become
``Delta K1``, ``Delta K2``, and the part the model misses depends on the trial's own motion.  The certificate
is then that of the model's error system; the ``ilc_lifted_model`` check measures, trial by trial, how much of
the change of the error the lifted model does not explain.

The feedback part is computed torque (exact linearization: the generic ``pole_placement``, ``lyapunov``,
``error_poles`` and ``designed_loop`` checks judge it with ``d = 0``); the iteration is the learning part,
certified by ``rho`` (``ilc_convergence``) and measured over the trials (``ilc_error_decrease``).

On a ``transfer_function`` or ``state_space`` plant, continuous or discrete-time (``plant.dt``), there is no
feedback: the learned signal is the plant's input, the lifted map comes from the plant's own Markov parameters, and
the family runs its own trials on the sampled plant (:mod:`~designkit.families.ilc.linear`).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Literal

import casadi as ca
import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from designkit.families.ilc.checks import CERTIFICATE_RULE, TRIALS_RULE
from designkit.families.ilc.diagnoses import diagnose
from designkit.families.ilc.figures import error_norm_figure, learned_figure, tracking_error_figure
from designkit.families.ilc.knobs import KNOBS, METRICS
from designkit.families.ilc.learning import IlcData, check_size, lifted_of, operator_of, trial_grid, update_rule
from designkit.families.ilc.lifted import lifted_model
from designkit.families.ilc.linear import LINEAR_PLANTS, synthesize_linear, validate_linear
from designkit.families.ilc.operators import contraction, learning_operator
from designkit.simulation.trials import MAX_TRIALS, Learning
from designkit.spec.computed_torque import PER_JOINT_FIELDS, ComputedTorqueSpec, error_poles
from designkit.spec.fields import Finite, Section, joint_values
from designkit.spec.ranges import Ranged, RangedInt
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import TRAJECTORY_REFERENCES, Display, Family
from designkit.synthesis.law import Law, dynamic_law
from designkit.synthesis.model import controller_model
from designkit.synthesis.pole_placement import error_gains

KIND = "ilc"


class LearningSpec(Section):
    """The learning operator ``Q`` of ``d_{k+1} = d_k + Q e_k``.

    ``kind: adjoint`` (default): ``Q = alpha H^T``, ``alpha`` (1/s^4 on a robot, ``(input/output)^2`` on a linear
    plant; 1e-12 to 1e30; left out: ``1 / sigma_max(H)^2``).  ``kind: p_type``: ``d_{k+1}(t_i) = d_k(t_i) + gain
    e_k(t_{i+r})`` (``r`` the relative degree in samples), ``gain`` (1/s^2 on a robot, input per output unit on a
    linear plant; 1e-12 to 1e30) required.  ``kind: filter``: ``d_{k+1} = d_k + F(z) e_k(. + r)``, ``F`` a causal
    filter ``num``/``den`` (coefficients of ``z^0, z^-1, ...``, each within 1e12, at most 20 of each; ``num[0]``
    and ``den[0]`` nonzero), required.
    """

    kind: Literal["adjoint", "p_type", "filter"] = "adjoint"
    alpha: Ranged(1e-12, 1e30, "1/s^4", base=Finite) | None = None
    gain: Ranged(1e-12, 1e30, "1/s^2", base=Finite) | None = Field(default=None, validate_default=True)
    num: list[Ranged(-1e12, 1e12, "", base=Finite)] | None = Field(default=None, min_length=1, max_length=20)
    den: list[Ranged(-1e12, 1e12, "", base=Finite)] = Field(default_factory=lambda: [1.0], min_length=1,
                                                           max_length=20)

    @model_validator(mode="after")
    def _filter(self) -> LearningSpec:
        if self.kind == "filter":
            if self.num is None:
                raise ValueError("num: the filter update needs the filter's numerator (coefficients of z^0, z^-1, ...)")
            if self.num[0] == 0:
                raise ValueError("num: num[0] must be nonzero (F's first coefficient sets the spectral radius "
                                 "|1 - F_0 h_0|; with 0 the learning never converges)")
            if self.den[0] == 0:
                raise ValueError("den: den[0] must be nonzero (a causal filter)")
        elif self.num is not None or self.den != [1.0]:
            raise ValueError("num: num and den belong to the filter update (kind: filter)")
        return self

    @field_validator("alpha")
    @classmethod
    def _alpha_is_adjoint(cls, v: float | None, info: ValidationInfo) -> float | None:
        if v is not None and info.data.get("kind") in ("p_type", "filter"):
            raise ValueError("belongs to the adjoint update (kind: adjoint)")
        return v

    @field_validator("gain")
    @classmethod
    def _gain_is_p_type(cls, v: float | None, info: ValidationInfo) -> float | None:
        kind = info.data.get("kind")
        if v is not None and kind in ("adjoint", "filter"):
            raise ValueError(f"belongs to the p_type update (kind: p_type); the {kind} update does not take it")
        if v is None and kind == "p_type":
            raise ValueError("the p_type update needs a gain (1/s^2)")
        return v


class ILCSpec(ComputedTorqueSpec):
    """Computed torque with a learned acceleration ``d_k``, updated between trials by ``d_{k+1} = d_k + Q e_k``.

    The error poles and the controller's ``model`` as for ``computed_torque``; ``trials`` (1 to 200, default
    10); ``learning`` (:class:`LearningSpec`; default the adjoint update with ``alpha`` computed).
    """

    kind: Literal[KIND]
    trials: RangedInt(1, MAX_TRIALS) = 10
    learning: LearningSpec = Field(default_factory=LearningSpec)

    @model_validator(mode="after")
    def _one_way(self) -> ILCSpec:
        # on a linear plant there is no feedback: no poles at all is allowed here, and a robot refuses it later
        if self.poles is None and self.damping is None and self.natural_frequency is None:
            return self
        return self.check_one_way()


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = ID^(q, qd, qD'' + K1 e + K2 e')`` plus the trial's feedforward ``M^(q) v`` (N*m per joint)."""
    plant = design.plant  # the controller's model
    K1, K2 = (ca.DM(np.asarray(design.gains[k], dtype=float)) for k in ("K1", "K2"))
    functions = plant.robot.functions
    p = plant.model_parameters()

    def call(name: str, *args: Any) -> ca.SX:
        return functions[name](*args, ca.DM(p)) if p is not None else functions[name](*args)

    def command(s: Any) -> ca.SX:
        return call("inverse_dynamics", s.q, s.qd, s.qDdd + K1 * (s.qD - s.q) + K2 * (s.qDd - s.qd))

    return dynamic_law(KIND, plant, command=command, feedforward=lambda s, v: ca.mtimes(call("mass_matrix", s.q), v),
                       settings={"gains": design.gains.to_json()})


def validate(spec: Any) -> None:
    """The lifted model is the smooth, continuous, undelayed loop's: refuse what changes its structure."""
    if spec.plant.kind in LINEAR_PLANTS:
        validate_linear(spec)
        return
    ctrl = spec.controller
    if ctrl.poles is None and ctrl.damping is None and ctrl.natural_frequency is None:
        raise ValueError("controller.poles: computed torque on a robot needs its error poles: give either poles, or "
                         "damping and natural_frequency")
    if ctrl.learning.kind == "filter":
        raise ValueError("controller.learning.kind: the filter update runs on a transfer_function or state_space "
                         "plant; on a robot use adjoint or p_type")
    sim = spec.simulation
    if sim.delay > 0:
        raise ValueError("simulation.delay: the learning's lifted model has no delay (a delay of m steps makes the "
                         "learned signal reach the error m steps later); leave the delay out")
    if sim.sampling_period > 0:
        raise ValueError("simulation.sampling_period: the learning's lifted model is the continuous loop "
                         "integrated by the simulator; a sampled controller changes its discretization")
    if sim.nonlinearity is not None:
        raise ValueError("simulation.nonlinearity: the learning's certificate is for the linear error system; a "
                         "nonlinear element at the plant input is not part of it")
    if getattr(spec, "implementation", None) is not None:
        raise ValueError("implementation: the learning's lifted model and certificate are of the continuous loop the "
                         "simulator integrates; sampling, a computation delay, quantisation or an actuator change that "
                         "loop, and the learning is not designed for it; leave the implementation section out")


def synthesize(spec: Any, plant: Any) -> Design:
    """The computed-torque gains, the trial's grid and lifted model, and the learning operator and rule (on a linear
    plant: its sampled model, :func:`~designkit.families.ilc.linear.synthesize_linear`)."""
    ctrl = spec.controller
    model = controller_model(plant, ctrl.model)
    if plant.kind in LINEAR_PLANTS:
        return synthesize_linear(spec, plant, model, KIND)
    n = model.n_joints
    pairs = error_poles(spec, n)
    K1, K2 = error_gains(pairs)
    feedback = [Gain("K1", list(K1), "1/s^2", "position error gain (wn^2)"),
                Gain("K2", list(K2), "1/s", "velocity error gain (2 zeta wn)")]
    q0 = np.zeros(n)
    if spec.simulation.initial_position is not None:
        q0 = np.array(joint_values(spec.simulation.initial_position, n, "simulation.initial_position"))
    design = Design(kind=KIND, plant=model, gains=Gains.of(feedback), poles=tuple(p for pr in pairs for p in pr),
                    reference="trajectory", extra={"codegen_terms": ["D_hat", "h_hat"]})
    design = with_closed_loop(design, law(design), np.concatenate([q0, np.zeros(2 * n)]),
                              field="simulation.initial_position")
    timing = trial_grid(spec, design, plant)
    check_size(timing.n_samples, timing.dt, n, ctrl.trials)  # before any lifted quantity is computed
    lifted = lifted_model(K1, K2, timing.dt, timing.n_samples, timing.integrator)
    learning = ctrl.learning
    if learning.kind == "adjoint":
        name, unit, meaning = "alpha", "1/s^4", "learning gain of Q = alpha H^T"
        if learning.alpha is not None:
            value, source = float(learning.alpha), "controller.learning.alpha"
        else:
            value = 1.0 / max(s.estimate for s in lifted.sigma_max) ** 2
            source = "computed: 1 / sigma_max(H)^2, which removes the largest singular direction in one trial"
    else:
        name, unit, meaning = "gamma", "1/s^2", "learning gain of the P-type update (one-step advance)"
        value, source = float(learning.gain), "controller.learning.gain"
    info = IlcData(samples=timing.n_samples, dt=timing.dt, integrator=timing.integrator, trials=ctrl.trials,
                   learning=learning.kind, value=value, value_source=source, model_differs=ctrl.model is not None)
    notes = [f"Learning: {learning.kind.replace('_', '-')} update, {name} = {value:.6g} {unit} ({source}); "
             f"{ctrl.trials} trials of {timing.n_samples} samples (dt = {timing.dt:g} s, {timing.integrator})."]
    if ctrl.model is not None:
        changed = {q.name: q.value for q in model.parameters if q.value != plant.parameter(q.name).value}
        notes.append("The controller's model differs from the true plant ("
                     + (", ".join(f"{k} = {v:.6g}" for k, v in changed.items()) or "same parameters")
                     + "): the learning certificate is that of the model's error system (M^ = M); the trials run on "
                       "the true plant and measure the difference.")
    design = dataclasses.replace(
        design, gains=Gains.of([*feedback, Gain(name, value, unit, meaning)]), notes=tuple(notes),
        data=info,
        formulas=("a* = q̈D + K1 (qD − q) + K2 (q̇D − q̇)",
                  "u = M̂(q) (a* + d_k) + ĥ(q, q̇)  (d_k the trial's learned acceleration)",
                  "e_k = H (d − d_k),  H(s) = 1/(s² + K2 s + K1) per joint when M̂ = M",
                  "d_(k+1) = d_k + Q e_k:  ‖d − d_(k+1)‖ ≤ ρ ‖d − d_k‖,  ρ = ‖I − Q H‖₂"),
        learning=Learning(ctrl.trials, update_rule(K1, K2, info), learning_operator(learning.kind, value).describe()))
    return dataclasses.replace(design, law=law(design))


_LEARNING_GAIN = {"adjoint": "alpha", "p_type": "gamma", "filter": "q0"}
"""The design gain that holds each update's learning gain."""


def _json(result: Any) -> dict[str, Any]:
    """``rho`` (``||I - Q H||_2``, Lanczos estimate; its proved bracket and the spectral radius beside it) and
    ``trials.error_norm``: per trial, the Euclidean norm of the sampled tracking error over every joint and
    instant (rad); a number that is not finite is written ``null`` (strict JSON)."""
    design = result.design
    sim = result.simulation
    c = contraction(lifted_of(design, None if sim is None else sim.time), operator_of(design))
    trials = result.trials
    from designkit.verification.certificate import to_json

    with np.errstate(over="ignore", invalid="ignore"):  # a diverged trial's norm is written null
        norms = [] if trials is None else [float(v) for v in trials.error_norms]
    return to_json({
        "rho": c.rho,
        "rho_bounds": [c.lower, c.upper],
        "spectral_radius": c.spectral_radius,
        "learning": {"kind": c.kind, "value": c.value, "unit": design.gains.unit(_LEARNING_GAIN[c.kind]),
                     "range": dict(c.alpha_range)},
        "trials": {"error_norm": norms,
                   "max_tracking_error": [] if trials is None else [float(v) for v in trials.max_tracking_errors]},
    })


FAMILY = Family(
    kind=KIND,
    spec=ILCSpec,
    plants=("robot", *LINEAR_PLANTS),
    uses=("plant.uncertainty", "plant.uncertainty.grid", "plant.uncertainty.samples", "plant.dt"),
    reference="trajectory",
    synthesize=synthesize,
    law=law,
    checks=("pole_placement", "lyapunov", CERTIFICATE_RULE, "error_poles", "robustness", "designed_loop",
            TRIALS_RULE, "time_domain", "torque_limits"),
    display=Display(
        label="Iterative learning control",
        law=("u = M̂(q) (q̈D + K1 (qD − q) + K2 (q̇D − q̇) + d_k) + ĥ(q, q̇)",
             "d_(k+1) = d_k + Q e_k between trials"),
        law_of=lambda d: (("u(t_i) = u_k(t_i): the learned input, played to the plant and held over each sample",
                           "u_(k+1) = u_k + Q e_k between trials") if d.data.sampled is not None else ()),
        summary="Notes §6.2: computed torque repeats a trajectory; between trials a learned acceleration d_k is "
                "corrected by the last trial's error through Q, converging monotonically when ‖I − Q H‖₂ < 1; on a "
                "linear plant (continuous or discrete-time) the learned signal is the plant's input itself.",
    ),
    validate=validate,
    references=(*TRAJECTORY_REFERENCES, "multisine"),
    figures=(error_norm_figure, tracking_error_figure, learned_figure),
    diagnoses=(diagnose,),
    json=_json,
    knobs=KNOBS,
    metrics=METRICS,
    traits=("learning", "model_based"),
    per_joint_fields=PER_JOINT_FIELDS,
)

__all__ = ["FAMILY", "ILCSpec", "law", "synthesize"]
