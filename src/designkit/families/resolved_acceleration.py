"""Resolved-acceleration control (notes section 2.3): the ``resolved_acceleration`` family.

The end effector is servoed in task space (Luh, Walker and Paul, 1980).  With the task
coordinates ``x(q)`` (position, and the orientation as ``-e_o`` when it is controlled; see
:mod:`designkit.models.task`), ``J`` the selected rows of the geometric Jacobian and the errors
``e = xD - x``, ``e' = xD' - J qd``::

    a* = xD'' + K1 e + K2 e'                        desired task acceleration
    qdd* = J^-1 (a* - Jdot qd)                      resolved to the joints
    u = M^(q) qdd* + h^(q, qd)                      the model's inverse dynamics at qdd*

On an exact model ``J qdd + Jdot qd = a*``: every task coordinate's error obeys
``e'' + K2 e' + K1 e = 0`` (exactly for position; for the orientation error to first order about
the held orientation), with computed torque's gains (:func:`designkit.synthesis.pole_placement.error_gains`) per
coordinate.  ``J^-1`` exists only away from singular configurations; with
``damped_least_squares: {damping: lambda}`` the resolution is
``qdd* = (J^T J + lambda^2 I)^-1 J^T (a* - Jdot qd)`` (Wampler 1986; Nakamura and Hanafusa
1986): bounded joint accelerations, ``|qdd*| <= |a* - Jdot qd| / (2 lambda)``, at the price of a
task-space gain ``sigma^2 / (sigma^2 + lambda^2)`` along each singular direction of ``J``.

The task space is square: as many controlled coordinates as joints (position for a planar or
3-joint arm, position and orientation for a 6-joint arm, position and the rotation about ``z``
for a SCARA).  The reference is ``simulation.trajectory`` of kind ``line`` or ``circle``
(:mod:`designkit.simulation.cartesian`); the motion it asks of the joints is solved by inverse
kinematics along the path (:func:`designkit.models.task.joint_path`), which also gives the
conditioning the ``singularity`` check reports.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Literal

import casadi as ca
import numpy as np
from pydantic import Field

from designkit.errors import ModelError, SpecError
from designkit.models.task import TaskSpace, check_path, joint_path, task_functions, task_space
from designkit.spec.computed_torque import FRICTION_LAYER, PER_JOINT_FIELDS, ComputedTorqueSpec, error_poles
from designkit.spec.fields import PositiveFinite, Section, joint_values
from designkit.spec.ranges import Ranged
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, FamilyData, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.friction_layer import DEFAULT_LAYER, coulomb_levels, layer_formulas, layer_words, smoothed
from designkit.synthesis.knobs import Knob, gain_knobs
from designkit.synthesis.law import Law, stateless_law
from designkit.synthesis.model import controller_model
from designkit.synthesis.pole_placement import error_gains

KIND = "resolved_acceleration"
PATH_SAMPLES = 401
"""Instants at which the path's joint motion is solved and its conditioning evaluated."""


class DampedLeastSquares(Section):
    """Damped least-squares resolution: ``damping`` lambda (units of ``J``'s singular values: m/rad; 1e-6 to 1e3)."""

    damping: Ranged(1e-6, 1e3, "m/rad", base=PositiveFinite)


class ResolvedAccelerationSpec(ComputedTorqueSpec):
    """Resolved acceleration: task-space PD, ``qdd* = J^-1(a* - Jdot qd)``, the model's inverse dynamics.

    Error poles as for ``computed_torque``, one pair per task coordinate.  ``orientation``:
    ``none`` (position only) or ``held`` (the initial orientation is held; error
    ``e_o = sin(theta) k``).  ``damped_least_squares``: resolve with damping (default: exact
    inverse).  ``max_condition`` (above 1, at most 1e12): the condition number of ``J`` above which a
    configuration on the path counts as near-singular.
    """

    kind: Literal["resolved_acceleration"]  # type: ignore[assignment]
    orientation: Literal["none", "held"] = "none"
    damped_least_squares: DampedLeastSquares | None = None
    max_condition: Ranged(1, 1e12, "", low_open=True) = Field(default=100.0, description="Condition number of J "
                                                              "counted as near-singular.")
    friction_layer: FRICTION_LAYER = DEFAULT_LAYER


@dataclass(frozen=True)
class ResolvedAccelerationData(FamilyData):
    """The resolved-acceleration family's design data (:attr:`~designkit.synthesis.design.Design.data`), read by its
    law and its motion; the motion (:class:`designkit.simulation.motion.TaskMotion`) carries the task space, the
    resolution and the conditioning limit to the generic checks.

    Attributes
    ----------
    space : TaskSpace
        The controlled task coordinates (rows of the geometric Jacobian) and the orientation held.
    damping : float or None
        ``lambda`` of the damped least-squares resolution (units of ``J``'s singular values, m/rad for position
        rows), or None for the exact inverse ``J^-1``.
    max_condition : float
        The condition number of ``J`` (1) above which a configuration of the path counts as near-singular.
    friction_layer : float
        The boundary layer of the Coulomb compensation (rad/s or m/s; 0: the exact ``sign``).
    model_differs : bool
        Whether the controller's model differs from the true plant (``controller.model`` given).
    """

    space: TaskSpace
    damping: float | None
    max_condition: float
    friction_layer: float
    model_differs: bool


def _q0(spec: Any, n: int) -> np.ndarray:
    if spec.simulation.initial_position is None:
        return np.zeros(n)
    return np.array(joint_values(spec.simulation.initial_position, n, "simulation.initial_position"))


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = ID^(q, qd, J^-1 (xD'' + K1 e + K2 e' - Jdot qd))`` with the task errors ``e``, ``e'`` (N*m)."""
    plant = design.plant
    K1, K2 = (np.asarray(design.gains[k], dtype=float) for k in ("K1", "K2"))
    n = plant.n_joints
    pos, vel = list(plant.positions), list(plant.velocities)
    p = plant.model_parameters()
    data = design.data
    fns = task_functions(plant.robot, p, data.space)
    inverse_dynamics = plant.robot.functions["inverse_dynamics"]
    damping = data.damping
    layer = float(data.friction_layer)
    fc = coulomb_levels(plant.robot, p)

    def output(y: ca.SX, r: ca.SX) -> ca.SX:
        q, qd = ca.vertcat(*[y[i] for i in pos]), ca.vertcat(*[y[i] for i in vel])
        J = fns.jacobian(q)
        e, e_dot = r[0:n] - fns.tracked(q), r[n:2 * n] - J @ qd
        b = r[2 * n:3 * n] + K1 * e + K2 * e_dot - fns.bias(q, qd)
        qdd = ca.solve(J.T @ J + damping**2 * ca.SX.eye(n), J.T @ b) if damping else ca.solve(J, b)
        tau = inverse_dynamics(q, qd, qdd, ca.DM(p)) if p is not None else inverse_dynamics(q, qd, qdd)
        return smoothed(tau, qd, fc, layer)

    return stateless_law(KIND, plant, output, {"gains": design.gains.to_json(), "damping": damping,
                                               "friction_layer": layer, "coulomb": fc.tolist()})


def synthesize(spec: Any, plant: Any) -> Design:
    """Task-space gains for the requested error poles, on the controller's model of ``plant``."""
    model = controller_model(plant, spec.controller.model)
    ctrl = spec.controller
    n = model.n_joints
    q0 = _q0(spec, n)
    space = task_space(model.robot, model.model_parameters(), q0, ctrl.orientation == "held")
    if space.m != n:
        hint = ("control the orientation too (orientation: held)" if space.m < n else
                "leave the orientation free (orientation: none)")
        raise SpecError("controller.orientation", f"the task space must be square: {space.m} controlled "
                        f"coordinates ({', '.join(space.names)}) for {n} joints; {hint}")
    pairs = error_poles(spec, n, "task coordinate")
    K1, K2 = error_gains(pairs)
    gains = Gains.of([Gain("K1", list(K1), "1/s^2", "task position error gain (wn^2), per coordinate"),
                      Gain("K2", list(K2), "1/s", "task velocity error gain (2 zeta wn), per coordinate")])
    damping = ctrl.damped_least_squares.damping if ctrl.damped_least_squares is not None else None
    notes = [f"Task coordinates {', '.join(f'{a} ({u})' for a, u in zip(space.names, space.units, strict=True))}"
             + ("; the initial orientation is held" if space.orientation_rows else "") + "."]
    if damping is not None:
        notes.append(f"Damped least squares, lambda = {damping:g}: joint accelerations bounded by "
                     f"|a* - Jdot qd| / {2 * damping:g}; the task gain along a singular direction of J with "
                     "singular value sigma is sigma^2/(sigma^2 + lambda^2).")
    if ctrl.model is not None:
        notes.append("The controller's model differs from the true plant; the simulation and the robustness "
                     "checks run on the true plant.")
    layer = float(ctrl.friction_layer)
    fc = coulomb_levels(model.robot, model.model_parameters())
    if layer_words(fc, layer):
        notes.append(layer_words(fc, layer))
    design = Design(
        kind=KIND, plant=model, gains=gains, poles=tuple(p for pair in pairs for p in pair), reference="trajectory",
        formulas=("a* = ẍD + K1 (xD − x) + K2 (ẋD − J q̇)",
                  ("q̈* = (Jᵀ J + λ² I)⁻¹ Jᵀ (a* − J̇ q̇)  (damped least squares, λ = " + f"{damping:g})"
                   if damping else "q̈* = J⁻¹ (a* − J̇ q̇)"),
                  "u = M̂(q) q̈* + ĥ(q, q̇)  (the model's Newton–Euler at q̈*)",
                  "ë + K2 ė + K1 e = 0 per task coordinate on an exact model:  K1 = p1 p2,  K2 = −(p1 + p2)",
                  *layer_formulas(fc, layer)),
        notes=tuple(notes),
        extra={"codegen_terms": ["D_hat", "h_hat", "J", "Jdot_qd"]},
        data=ResolvedAccelerationData(space=space, damping=damping, max_condition=float(ctrl.max_condition),
                                      friction_layer=layer, model_differs=ctrl.model is not None),
    )
    fns = task_functions(model.robot, model.model_parameters(), space)
    x0 = np.asarray(fns.tracked(q0)).ravel()
    r0 = np.concatenate([x0, np.zeros(2 * n)])
    design = with_closed_loop(design, law(design), r0, z0=np.concatenate([q0, np.zeros(n)]),
                              field="simulation.initial_position",
                              hint=" (a singular task Jacobian: start away from the singularity or set "
                                   "controller.damped_least_squares)")
    return dataclasses.replace(design, motion=motion(spec, design))


def motion(spec: Any, design: Design) -> Any:
    """The task-space reference of ``simulation.trajectory`` and the joint path that tracks it exactly, with the
    design's resolution (``damping``) and conditioning limit (``max_condition``) for the checks.

    Raises
    ------
    SpecError
        ``simulation.trajectory``: not a ``line`` or ``circle``, out of reach, leaving the joint or
        velocity limits.
    """
    from designkit.simulation.cartesian import cartesian_reference
    from designkit.simulation.motion import TaskMotion

    traj = spec.simulation.trajectory
    if traj is None or traj.kind not in ("line", "circle"):
        got = "none" if traj is None else repr(traj.kind)
        raise SpecError("simulation.trajectory" if traj is None else "simulation.trajectory.kind",
                        f"a task-space controller follows an end-effector path: give kind line or circle (got {got})")
    plant = design.plant
    n = plant.n_joints
    data = design.data
    space = data.space
    p = plant.model_parameters()
    fns = task_functions(plant.robot, p, space)
    q0 = _q0(spec, n)
    p0 = np.asarray(plant.robot.functions["fkine"](ca.DM(q0), *([ca.DM(p)] if p is not None else [])))[:3, 3]
    ref = cartesian_reference(traj, p0, space, q0)
    t = np.linspace(0.0, ref.horizon, PATH_SAMPLES)
    X = ref.evaluate(t)
    path = joint_path(fns, q0, t, X[:, :, 0], X[:, :, 1])
    limits = getattr(spec.plant, "limits", None)
    try:
        end = ("to" if traj.to is not None else "displacement") if traj.kind == "line" else "center"
        check_path(path, "simulation.trajectory", plant.joint_limits,
                   getattr(limits, "velocity", None) if limits is not None else None,
                   reach_key=f"simulation.trajectory.{end}")
    except ModelError as exc:
        raise SpecError(exc.field, exc.message) from None
    return TaskMotion(ref, space, fns, path, damping=data.damping, max_condition=data.max_condition)


FAMILY = Family(
    kind=KIND,
    spec=ResolvedAccelerationSpec,
    plants=("robot",),
    uses=("plant.uncertainty", "plant.uncertainty.grid", "plant.uncertainty.samples"),
    reference="trajectory",
    synthesize=synthesize,
    law=law,
    checks=("lyapunov", "error_poles", "singularity", "robustness", "tracking_bounds",
            "designed_loop", "time_domain", "torque_limits"),
    display=Display(
        label="Resolved-acceleration control",
        law=("a* = ẍD + K1 (xD − x) + K2 (ẋD − J q̇)",
             "u = M̂(q) J⁻¹ (a* − J̇ q̇) + ĥ(q, q̇)"),
        summary="Notes §2.3: a PD servo of the end effector in task space, resolved to joint accelerations "
                "through the Jacobian and applied with the model's inverse dynamics; on an exact model each task "
                "coordinate's error obeys ë + K2 ė + K1 e = 0 away from singular configurations.",
    ),
    references=("line", "circle"),
    motion=motion,
    knobs=gain_knobs({"K1": ("1/s^2", "task position error gain (wn^2)"),
                      "K2": ("1/s", "task velocity error gain (2 zeta wn)")}, ("K1", "K2")) + (
        Knob("poles", "1/s", "error poles of each task coordinate (sets K1, K2)", 1e-3, 1e5, path="controller.poles"),),
    traits=("model_based",),
    per_joint_fields=PER_JOINT_FIELDS,
)
