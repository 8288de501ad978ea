"""Computed torque (notes section 2.2): the ``computed_torque`` family.

With the controller's model ``M^, h^`` of the arm (``h^ = C^ qd + g^ + F^(qd)``) and the errors
``e = qD - q``, ``e' = qD' - qd``::

    u = M^(q) (qD'' + K1 e + K2 e') + h^(q, qd)          (the model's inverse dynamics at a*)

On an exact model the arm's acceleration is ``a* = qD'' + K1 e + K2 e'``: the error of each joint obeys
``e'' + K2 e' + K1 e = 0``, decoupled from the others and the same at every configuration, with the
poles of ``s^2 + K2 s + K1``.  For poles ``p1, p2`` (a real pair or a conjugate pair):
``K1 = p1 p2`` (1/s^2), ``K2 = -(p1 + p2)`` (1/s); for a damping ratio and natural frequency:
``K1 = wn^2``, ``K2 = 2 zeta wn``.  The law is the model's Newton--Euler inverse dynamics evaluated at
``a*`` (one call, the Luh-Walker-Paul approach the notes cite), so ``M^`` is never inverted.

The model is the true plant unless the spec gives ``controller.model`` (mass errors, an assumed
payload, friction left out; :mod:`designkit.synthesis.model`): then the design's ``plant`` is that
model, the simulation runs on the true plant, and the checks measure what the mismatch costs.
"""

from __future__ import annotations

from typing import Any, Literal

import casadi as ca
import numpy as np
from pydantic import Field, field_validator, model_validator

from designkit.errors import SpecError
from designkit.families.computed_torque.friction_layer import (
    DEFAULT_LAYER,
    coulomb_levels,
    layer_formulas,
    layer_words,
    smoothed,
)
from designkit.spec.controllers import ControllerModel
from designkit.spec.fields import NonNegativeFinite, Section, check_conjugates, parse_pole, per_joint
from designkit.spec.ranges import Ranged, RangedPerJoint, check_poles
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import gain_knobs
from designkit.synthesis.law import Law, stateless_law
from designkit.synthesis.model import controller_model

KIND = "computed_torque"


def model_error_diagnosis(result: Any, check: Any) -> tuple[str, str] | None:
    """Why a tracking requirement (``tracking_bounds``, ``tracking_error``) failed on a model-based design: the
    model-error torque (:func:`designkit.families.computed_torque.model_error.explain`)."""
    if check.name not in ("tracking_bounds", "tracking_error"):
        return None
    from designkit.families.computed_torque.model_error import explain

    return explain(result, check)


def _pole(value: Any, where: str) -> complex:
    try:
        return parse_pole(value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _pair(poles: list[complex], where: str) -> list[complex]:
    if len(poles) != 2:
        raise ValueError(f"{where}must list exactly 2 poles per joint, got {len(poles)}")
    check_poles(poles, where.removesuffix(": "))
    try:
        check_conjugates(poles)
    except ValueError as exc:
        raise ValueError(f"{where}{exc}") from None
    return poles


class ComputedTorqueSpec(Section):
    """Computed torque ``u = M^(q)(qD'' + K1 e + K2 e') + h^(q, qd)``.

    Give the error poles -- ``poles``: two poles (1/s) for every joint, or one pair per joint -- or
    ``damping`` (1e-6 to 1e3) and ``natural_frequency`` (rad/s, 1e-12 to 1e12), one value or one per
    joint; either way every ``|p|`` lies between 1e-12 and 1e12 1/s and ``max |p| / min |Re p|`` is at
    most 1e12 (:func:`~designkit.spec.ranges.check_poles`).  ``model``: the model the controller
    believes (default: the true plant).
    """

    kind: Literal["computed_torque"]
    poles: list[Any] | None = Field(default=None, description="Two error poles (1/s) for every joint, or a pair "
                                    "per joint.")
    damping: RangedPerJoint(1e-6, 1e3, "") | None = None
    natural_frequency: RangedPerJoint(1e-12, 1e12, "rad/s") | None = None
    model: ControllerModel | None = None

    @field_validator("poles")
    @classmethod
    def _pole_pairs(cls, v: list[Any] | None) -> list[Any] | None:
        if v is None:
            return v
        nested = [isinstance(p, list | tuple) for p in v]
        if any(nested) and not all(nested):
            raise ValueError("give two poles, or a list of two poles per joint, not a mix")
        if not all(nested):
            return _pair([_pole(p, f"[{k}]") for k, p in enumerate(v)], "")
        if not v:
            raise ValueError("needs at least one pair of poles")
        pairs = [_pair([_pole(p, f"[{i}][{k}]") for k, p in enumerate(row)], f"[{i}]: ") for i, row in enumerate(v)]
        check_poles([p for pair in pairs for p in pair])  # one closed loop: the spread over every joint
        return pairs

    @model_validator(mode="after")
    def _one_way(self) -> ComputedTorqueSpec:
        by_poles = self.poles is not None
        by_zeta = self.damping is not None or self.natural_frequency is not None
        if by_poles == by_zeta:
            raise ValueError("give either poles, or damping and natural_frequency")
        if by_zeta and (self.damping is None or self.natural_frequency is None):
            raise ValueError("damping and natural_frequency go together")
        for name in ("damping", "natural_frequency"):
            value = getattr(self, name)
            for x in (value if isinstance(value, list) else [] if value is None else [value]):
                if x <= 0:
                    raise ValueError(f"{name}: must be positive, got {x:g}")
        if by_zeta:
            zetas, wns = (v if isinstance(v, list) else [v] for v in (self.damping, self.natural_frequency))
            if len(zetas) == len(wns) or 1 in (len(zetas), len(wns)):  # else refused per joint at synthesis
                n = max(len(zetas), len(wns))
                poles = [p for k in range(n) for p in _damped_pair(zetas[k % len(zetas)], wns[k % len(wns)])]
                try:
                    check_poles(poles)
                except ValueError as exc:
                    what = str(exc).split("]: ", 1)[-1] if str(exc).startswith("[") else str(exc)
                    raise ValueError(f"natural_frequency: the error poles of damping and natural_frequency: {what}"
                                     ) from None
        return self


FRICTION_LAYER = Ranged(1e-6, 1e3, "rad/s or m/s", zero=True, base=NonNegativeFinite)
"""``controller.friction_layer``: the boundary layer of the Coulomb compensation (0 = the exact ``sign``)."""


class ComputedTorqueLawSpec(ComputedTorqueSpec):
    """Computed torque as the ``computed_torque`` family reads it: :class:`ComputedTorqueSpec` and
    ``friction_layer`` (rad/s or m/s; 0, or 1e-6 to 1e3; default 0): the model's Coulomb compensation
    ``Fc sign(q')`` is written ``Fc s(q'/friction_layer)`` (:mod:`~designkit.families.computed_torque.friction_layer`),
    0 keeps the exact ``sign``."""

    friction_layer: FRICTION_LAYER = DEFAULT_LAYER


def _damped_pair(zeta: float, wn: float) -> tuple[complex, complex]:
    """The error poles ``wn (-zeta +- sqrt(zeta^2 - 1))`` (1/s) of a damping ratio and natural frequency (rad/s),
    as :func:`error_poles` computes them (for the spec's check of their range)."""
    disc = complex(zeta * zeta - 1.0) ** 0.5
    return wn * (-zeta + disc), wn * (-zeta - disc)


def joint_values(value: Any, n: int, path: str) -> tuple[float, ...]:
    try:
        return per_joint(value, n, path)
    except ValueError as exc:
        key, msg = str(exc).split(": ", 1)
        raise SpecError(key, msg) from None


def error_poles(spec: Any, n: int, what: str = "joint") -> list[tuple[complex, complex]]:
    """The pair of error poles of each of ``n`` joints (or task coordinates: ``what``), from ``poles`` or from
    ``damping`` and ``natural_frequency``."""
    ctrl = spec.controller
    if ctrl.poles is not None:
        if isinstance(ctrl.poles[0], list):
            if len(ctrl.poles) != n:
                raise SpecError("controller.poles", f"needs one pair of poles per {what} ({n}), got {len(ctrl.poles)}")
            return [tuple(p) for p in ctrl.poles]
        return [tuple(ctrl.poles)] * n
    zetas = joint_values(ctrl.damping, n, "controller.damping")
    wns = joint_values(ctrl.natural_frequency, n, "controller.natural_frequency")
    out = []
    for zeta, wn in zip(zetas, wns, strict=True):
        disc = complex(zeta * zeta - 1.0) ** 0.5
        out.append((wn * (-zeta + disc), wn * (-zeta - disc)))
    return out


def friction_layer_of(design: Design) -> float:
    """The design's boundary layer of the Coulomb compensation (rad/s or m/s; 0: the exact ``sign``)."""
    return float(design.extra.get("friction_layer", 0.0))


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = ID^(q, qd, qD'' + K1 (qD - q) + K2 (qD' - qd))``: the model's inverse dynamics (N*m per joint), its
    Coulomb term ``Fc sign(qd)`` smoothed in the design's boundary layer (:func:`friction_layer_of`)."""
    plant = design.plant  # the controller's model
    K1, K2 = (np.asarray(design.gains[k], dtype=float) for k in ("K1", "K2"))
    n = plant.n_joints
    pos, vel = list(plant.positions), list(plant.velocities)
    inverse_dynamics = plant.robot.functions["inverse_dynamics"]
    p = plant.model_parameters()
    layer = friction_layer_of(design)
    fc = coulomb_levels(plant.robot, p)

    def output(y: ca.SX, r: ca.SX) -> ca.SX:
        q, qd = ca.vertcat(*[y[i] for i in pos]), ca.vertcat(*[y[i] for i in vel])
        a = r[2 * n:3 * n] + K1 * (r[0:n] - q) + K2 * (r[n:2 * n] - qd)
        tau = inverse_dynamics(q, qd, a, ca.DM(p)) if p is not None else inverse_dynamics(q, qd, a)
        return smoothed(tau, qd, fc, layer)

    return stateless_law(KIND, plant, output, {"gains": design.gains.to_json(), "friction_layer": layer,
                                               "coulomb": fc.tolist()})


def synthesize(spec: Any, plant: Any) -> Design:
    """The computed-torque gains for the requested error poles, on the controller's model of ``plant``."""
    model = controller_model(plant, spec.controller.model)
    n = model.n_joints
    pairs = error_poles(spec, n)
    K1 = [float((p1 * p2).real) for p1, p2 in pairs]
    K2 = [float((-(p1 + p2)).real) for p1, p2 in pairs]
    gains = Gains.of([Gain("K1", K1, "1/s^2", "position error gain (wn^2)"),
                      Gain("K2", K2, "1/s", "velocity error gain (2 zeta wn)")])
    notes = []
    if spec.controller.model is not None:
        changed = {q.name: q.value for q in model.parameters if q.value != plant.parameter(q.name).value}
        notes.append("The controller's model differs from the true plant: "
                     + (", ".join(f"{k} = {v:.6g}" for k, v in changed.items()) or "same parameters")
                     + (f"; friction {'included' if model.robot.friction else 'left out'}"
                        if model.robot.friction != plant.robot.friction else "")
                     + ". The simulation and the robustness checks run on the true plant.")
    layer = float(spec.controller.friction_layer)
    fc = coulomb_levels(model.robot, model.model_parameters())
    friction_note = layer_words(fc, layer)
    if friction_note:
        notes.append(friction_note)
    q0 = np.zeros(n)
    if spec.simulation.initial_position is not None:
        q0 = np.array(joint_values(spec.simulation.initial_position, n, "simulation.initial_position"))
    design = Design(
        kind=KIND, plant=model, gains=gains, poles=tuple(p for pair in pairs for p in pair), reference="trajectory",
        formulas=("a* = q̈D + K1 (qD − q) + K2 (q̇D − q̇)",
                  "u = M̂(q) a* + ĥ(q, q̇)  (the model's Newton–Euler at a*)",
                  "ë + K2 ė + K1 e = 0 per joint on an exact model:  K1 = p1 p2,  K2 = −(p1 + p2)",
                  *layer_formulas(fc, layer)),
        notes=tuple(notes),
        extra={"model_differs": spec.controller.model is not None, "codegen_terms": ["D_hat", "h_hat"],
               "friction_layer": layer},
    )
    return with_closed_loop(design, law(design), np.concatenate([q0, np.zeros(2 * n)]),
                            field="simulation.initial_position")


FAMILY = Family(
    kind=KIND,
    spec=ComputedTorqueLawSpec,
    plants=("robot",),
    reference="trajectory",
    synthesize=synthesize,
    law=law,
    checks=("pole_placement", "lyapunov", "error_poles", "robustness", "tracking_bounds", "designed_loop",
            "time_domain", "torque_limits"),
    diagnoses=(model_error_diagnosis,),
    display=Display(
        label="Computed torque",
        law=("u = M̂(q) (q̈D + K1 (qD − q) + K2 (q̇D − q̇)) + ĥ(q, q̇)",),
        summary="Notes §2.2: the model's inverse dynamics at the desired acceleration plus a PD correction; on an "
                "exact model every joint's error obeys ë + K2 ė + K1 e = 0, decoupled, at every configuration.",
    ),
    knobs=gain_knobs({"K1": ("1/s^2", "position error gain (wn^2)"), "K2": ("1/s", "velocity error gain (2 zeta wn)")},
                     ("K1", "K2")),
    traits=("model_based",),
)
