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

from dataclasses import dataclass
from typing import Any, Literal

import casadi as ca
import numpy as np

from designkit.spec.computed_torque import FRICTION_LAYER, PER_JOINT_FIELDS, ComputedTorqueSpec, error_poles
from designkit.spec.fields import joint_values
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, FamilyData, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.friction_layer import DEFAULT_LAYER, coulomb_levels, layer_formulas, layer_words, smoothed
from designkit.synthesis.knobs import Knob, gain_knobs
from designkit.synthesis.law import Law, stateless_law
from designkit.synthesis.model import controller_model
from designkit.synthesis.pole_placement import error_gains

KIND = "computed_torque"


def model_error_diagnosis(result: Any, check: Any) -> tuple[str, str] | None:
    """Why a tracking requirement (``tracking_bounds``, ``tracking_error``) failed on a model-based design: the
    model-error torque (:func:`designkit.families.computed_torque.model_error.explain`)."""
    if check.name not in ("tracking_bounds", "tracking_error"):
        return None
    from designkit.families.computed_torque.model_error import explain

    return explain(result, check)


class ComputedTorqueLawSpec(ComputedTorqueSpec):
    """Computed torque as the ``computed_torque`` family reads it: :class:`ComputedTorqueSpec` and
    ``friction_layer`` (rad/s or m/s; 0, or 1e-6 to 1e3; default 0): the model's Coulomb compensation
    ``Fc sign(q')`` is written ``Fc s(q'/friction_layer)`` (:mod:`~designkit.synthesis.friction_layer`),
    0 keeps the exact ``sign``."""

    kind: Literal[KIND]
    friction_layer: FRICTION_LAYER = DEFAULT_LAYER


@dataclass(frozen=True)
class ComputedTorqueData(FamilyData):
    """The computed-torque family's design data (:attr:`~designkit.synthesis.design.Design.data`).

    Attributes
    ----------
    friction_layer : float
        The boundary layer of the Coulomb compensation (rad/s or m/s; 0: the exact ``sign``).
    model_differs : bool
        Whether the controller's model differs from the true plant (``controller.model`` given).
    """

    friction_layer: float = 0.0
    model_differs: bool = False


def friction_layer_of(design: Design) -> float:
    """The design's boundary layer of the Coulomb compensation (rad/s or m/s; 0: the exact ``sign``, also for a design
    without :class:`ComputedTorqueData`, such as the learning family's whose feedback is this law)."""
    data = design.data
    return float(data.friction_layer) if isinstance(data, ComputedTorqueData) else 0.0


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
    K1, K2 = error_gains(pairs)
    gains = Gains.of([Gain("K1", list(K1), "1/s^2", "position error gain (wn^2)"),
                      Gain("K2", list(K2), "1/s", "velocity error gain (2 zeta wn)")])
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
        extra={"codegen_terms": ["D_hat", "h_hat"]},
        data=ComputedTorqueData(friction_layer=layer, model_differs=spec.controller.model is not None),
    )
    return with_closed_loop(design, law(design), np.concatenate([q0, np.zeros(2 * n)]),
                            field="simulation.initial_position")


FAMILY = Family(
    kind=KIND,
    spec=ComputedTorqueLawSpec,
    plants=("robot",),
    uses=("plant.uncertainty", "plant.uncertainty.grid", "plant.uncertainty.samples"),
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
                     ("K1", "K2")) + (
        Knob("poles", "1/s", "error poles of each joint (sets K1, K2)", 1e-3, 1e5, path="controller.poles"),),
    traits=("model_based",),
    per_joint_fields=PER_JOINT_FIELDS,
)
