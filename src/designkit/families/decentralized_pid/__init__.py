"""Decentralized PID of a manipulator (notes sections 3.1-3.3, the SIMNOG simulator): ``decentralized_pid``.

Each joint ``i`` is servoed by its own PID, designed on the simplified link model of that
joint (notes section 1.2) at a chosen configuration ``q*``: freezing the arm at ``q*`` and
keeping only the diagonal inertia, ``D_ii(q*) q_i'' + f_i q_i' = u_i + xi_i`` with ``f_i`` the
joint's viscous friction, so ``Km_i = 1/f_i`` and ``tau_i = D_ii(q*)/f_i``
(:func:`designkit.models.link.simplified_link`).  Everything the simplified model leaves out --
the off-diagonal inertia, Coriolis and centrifugal forces, the change of ``D_ii`` with the
configuration, gravity not cancelled -- is the perturbation ``xi_i`` the PID must reject.  The
law, with the integrals ``x3_i' = q_i - qD_i`` and a centralized gravity feed-forward
``g^`` computed with the nominal model::

    u_i = -K1_i (q_i - qD_i) - K2_i q_i' - K3_i x3_i + K3_i K4_i qD_i + g^_i(q)

``gravity_feedforward``: ``measured`` (``g^(q)``, as SIMNOG), ``desired`` (``g^(qD)``) or ``none``
(the integrals alone take the gravity load).  The per-joint gains are the one-link PID servo's
(:mod:`designkit.synthesis.servo_loop`), so each joint loop places its requested poles exactly *on
its simplified model*; the coupled arm's poles differ by the intercoupling, which the
``coupling`` check measures.

``workspace`` (optional): a box of configurations, ``{low, high}`` (rad or m per joint, either
omitted: the robot's joint limits) or ``joint_limits``, over which the family's ``workspace`` check
(:mod:`designkit.families.decentralized_pid.workspace_check`) certifies every joint loop for every
``D_ii(q)`` of the box, not only at ``q*``.  Velocity limits are not asked for: ``Km_i`` and ``tau_i`` do not depend on
the joint velocities (the velocity-dependent torques are part of ``xi``).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Literal

import casadi as ca
import numpy as np
from pydantic import Field, field_validator

from designkit.errors import ModelError, SpecError
from designkit.families.decentralized_pid import workspace_check as workspace_certificate
from designkit.families.decentralized_pid.data import DecentralizedPidData
from designkit.families.decentralized_pid.diagnoses import diagnose
from designkit.models.link import simplified_link
from designkit.spec.controllers import three_poles
from designkit.spec.fields import PositiveFinite, Section, joint_values, parse_pole
from designkit.spec.ranges import Ranged, RangedPerJoint, check_poles
from designkit.spec.workspace import Workspace, joint_limits_word, workspace_box, workspace_schema
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import Knob, gain_knobs
from designkit.synthesis.law import Law, integral_law
from designkit.synthesis.pid import GAIN_INFO, SERVO_FORMULAS
from designkit.synthesis.requirements import poles_from_spec, poles_or_requirements
from designkit.synthesis.servo_loop import servo_design, servo_law
from designkit.synthesis.variation import with_gains

KIND = "decentralized_pid"


class DecentralizedPidSpec(Section):
    """One PID servo per joint on its simplified link model, plus a gravity feed-forward.

    ``poles`` (1/s): three poles for every joint, or a list with one set of three per joint (every
    ``|p|`` 1e-12 to 1e12, all of them spread at most 1e12); or omitted, with the poles derived from
    ``requirements.overshoot`` and ``settling_time`` (as for ``pid_servo``; ``third_pole_factor`` 1 to
    100, ``design_margin`` 0 to 0.9).  ``zero``: the zero of each joint's ``q_i/qD_i`` (1/s, -1e12 to
    -1e-12, one for all or one per joint; omitted: ``K4 = 0``).  ``configuration`` (rad per joint,
    within 100): where each link's ``Km_i``, ``tau_i`` are computed (default:
    ``simulation.initial_position``, else zero).
    ``workspace``: the box of configurations the ``workspace`` check certifies the loops over
    (:class:`~designkit.spec.workspace.Workspace`, or ``joint_limits`` for the robot's joint limits; default: no
    such check).
    """

    kind: Literal["decentralized_pid"]
    poles: list[Any] | None = Field(default=None, description="Three poles (1/s) for every joint, or one set "
                                    "of three per joint.")
    zero: RangedPerJoint(-1e12, -1e-12, "1/s") | None = None
    configuration: RangedPerJoint(-100, 100, "rad or m") | None = None
    gravity_feedforward: Literal["measured", "desired", "none"] = "measured"
    third_pole_factor: Ranged(1, 100, "", base=PositiveFinite) = 5.0
    design_margin: Ranged(0, 0.9, "") = 0.1
    workspace: Workspace | None = Field(default=None, json_schema_extra=workspace_schema,
                                        description="Box of configurations {low, high} (rad or m per joint) "
                                        "certified by the workspace check, or 'joint_limits'.")

    @field_validator("workspace", mode="before")
    @classmethod
    def _joint_limits(cls, v: Any) -> Any:
        return joint_limits_word(v)

    @field_validator("poles")
    @classmethod
    def _pole_sets(cls, v: list[Any] | None) -> list[Any] | None:
        if v is None:
            return v
        nested = [isinstance(p, list | tuple) for p in v]
        if any(nested) and not all(nested):
            raise ValueError("give three poles, or a list of three poles per joint, not a mix")
        if not all(nested):
            return three_poles([_pole(p, f"[{k}]") for k, p in enumerate(v)])
        if not v:
            raise ValueError("needs at least one set of three poles")
        out = []
        for i, row in enumerate(v):
            poles = [_pole(p, f"[{i}][{k}]") for k, p in enumerate(row)]
            check_poles(poles, f"[{i}]")
            try:
                out.append(three_poles(poles))
            except ValueError as exc:
                raise ValueError(f"[{i}]: {exc}") from None
        check_poles([p for row in out for p in row])  # one closed loop: the spread over every joint
        return out

    @field_validator("zero")
    @classmethod
    def _lhp_zeros(cls, v: float | list[float] | None) -> float | list[float] | None:
        for z in (v if isinstance(v, list) else [] if v is None else [v]):
            if z >= 0:
                raise ValueError(f"must be negative (left half plane), got {z:g}")
        return v


def _pole(value: Any, where: str) -> complex:
    try:
        return parse_pole(value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _pole_sets(spec: Any, n: int) -> tuple[list[tuple[complex, ...]], tuple[str, ...], dict]:
    ctrl = spec.controller
    if ctrl.poles is None:
        poles, notes, extra = poles_from_spec(ctrl, spec.requirements)  # same rule as pid_servo
        return [tuple(poles)] * n, notes, extra
    if isinstance(ctrl.poles[0], list):
        if len(ctrl.poles) != n:
            raise SpecError("controller.poles", f"needs one set of three poles per joint ({n}), got {len(ctrl.poles)}")
        return [tuple(p) for p in ctrl.poles], (), {}
    return [tuple(ctrl.poles)] * n, (), {}


def configuration(spec: Any, n: int) -> np.ndarray:
    """The configuration ``q*`` (rad) of the per-link models: ``controller.configuration``, else the
    simulation's initial position, else zero."""
    if spec.controller.configuration is not None:
        return np.array(joint_values(spec.controller.configuration, n, "controller.configuration"))
    if spec.simulation.initial_position is not None:
        return np.array(joint_values(spec.simulation.initial_position, n, "simulation.initial_position"))
    return np.zeros(n)


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u_i = -K1_i e_i - K2_i q_i' - K3_i x3_i + K3_i K4_i qD_i + g^_i`` (N*m per joint)."""
    plant = design.plant
    K1, K2, K3, K4 = (np.asarray(design.gains[k], dtype=float) for k in ("K1", "K2", "K3", "K4"))
    n = plant.n_joints
    vel = list(plant.velocities)
    pos = list(plant.positions)
    mode = design.data.gravity_feedforward
    gravity = plant.robot.functions["gravity_torque"]
    p = plant.model_parameters()

    def g_hat(q: ca.SX) -> ca.SX:
        return gravity(q, ca.DM(p)) if p is not None else gravity(q)

    def output(y, xc, r, e):
        qd = ca.vertcat(*[y[i] for i in vel])
        u = -K1 * e - K2 * qd - K3 * xc + K3 * K4 * r[0:n]
        if mode == "measured":
            u = u + g_hat(ca.vertcat(*[y[i] for i in pos]))
        elif mode == "desired":
            u = u + g_hat(r[0:n])
        return u

    return integral_law(KIND, plant, K3, anti_windup, output,
                        {"gains": design.gains.to_json(), "gravity_feedforward": mode})


def synthesize(spec: Any, plant: Any) -> Design:
    """One PID servo per joint on its simplified link at ``configuration`` (see the module docstring)."""
    n = plant.n_joints
    if not plant.robot.friction:
        raise SpecError("plant.friction", "decentralized_pid designs each joint on Km = 1/f (f the joint's viscous "
                        "friction), so the plant needs its friction: set plant.friction: true")
    q_star = configuration(spec, n)
    box = workspace_box(spec, plant)
    pole_sets, notes, extra = _pole_sets(spec, n)
    ctrl = spec.controller
    zeros: tuple[float | None, ...] = (None,) * n
    if ctrl.zero is not None:
        zeros = joint_values(ctrl.zero, n, "controller.zero")
    elif ctrl.poles is None:
        zeros = tuple(float(ps[2].real) for ps in pole_sets)
        notes = (*notes, "No zero given: each joint's zero placed on its third pole, so that its reference "
                         "response is the dominant second-order one.")
    loops, links = [], []
    for i in range(n):
        try:
            link = simplified_link(plant.robot, i, q_star, p=plant.model_parameters())
        except ModelError as exc:
            raise SpecError("plant", f"joint {i + 1}: {exc.message}") from None
        links.append(link)
        loops.append(servo_design(link, pole_sets[i], zeros[i], kind=KIND))
    gains = Gains.of(
        Gain(k, [float(loop.gains[k]) for loop in loops], *GAIN_INFO[k]) for k in ("K1", "K2", "K3", "K4")
    )
    notes = (*notes, "Per-link models at q* = [" + ", ".join(f"{q:.4g}" for q in q_star) + "] rad: "
             + "; ".join(f"joint {i + 1}: Km = {lk.Km:.4g} (rad/s)/(N*m), tau = {lk.tau:.4g} s "
                         f"(D_ii = {lk.inertia:.4g} kg*m^2, f = {lk.damping:.4g} N*m*s/rad)"
                         for i, lk in enumerate(links)) + ".")
    design = Design(
        kind=KIND, plant=plant, gains=gains, reference="step", loops=tuple(loops),
        loop_names=tuple(f"joint{i + 1}" for i in range(n)),
        formulas=("Km_i = 1/f_i,  tau_i = D_ii(q*)/f_i  (simplified link, notes §1.2)",
                  *SERVO_FORMULAS[2:]),
        notes=notes,
        extra={**extra, "codegen_terms": [] if ctrl.gravity_feedforward == "none" else ["g_hat"]},
        data=DecentralizedPidData(configuration=tuple(q_star.tolist()), links=tuple(links),
                                  gravity_feedforward=ctrl.gravity_feedforward, workspace=box),
    )
    r0 = np.concatenate([q_star, np.zeros(2 * n)])
    return with_closed_loop(design, law(design), r0, field="controller.configuration")


def regain(design: Design, gains: Gains, anti_windup: Any = None) -> Design:
    """``design`` with other per-joint gains: each joint's loop (the servo on its simplified link) and the arm's law
    and closed loop rebuilt from them (:func:`designkit.synthesis.variation.with_gains`)."""
    loops = []
    for i, loop in enumerate(design.loops):
        own = loop.gains.replace(**{k: float(np.asarray(gains[k], dtype=float)[i]) for k in ("K1", "K2", "K3", "K4")})
        loops.append(with_gains(loop, own, servo_law))
    arm = with_gains(dataclasses.replace(design, loops=()), gains, law, anti_windup)
    return dataclasses.replace(arm, loops=tuple(loops))


def _one_pole_set(design: Design) -> bool:
    """Every joint places the same poles (the ``poles`` knob moves that one set; a set per joint is not a knob)."""
    return len({tuple(np.round(np.asarray(loop.poles, dtype=complex), 12)) for loop in design.loops}) <= 1


FAMILY = Family(
    kind=KIND,
    spec=DecentralizedPidSpec,
    plants=("robot",),
    uses=("simulation.anti_windup", "plant.uncertainty", "plant.uncertainty.grid", "plant.uncertainty.samples"),
    reference="step",
    synthesize=synthesize,
    law=law,
    checks=("loops", "lyapunov", "robustness", "loop_margins", "time_domain", "coupling", "designed_loop",
            workspace_certificate.RULE),
    display=Display(
        label="Decentralized PID with gravity feed-forward",
        law=("u_i = -K1_i (q_i - qD_i) - K2_i q̇_i - K3_i ∫(q_i - qD_i) dt + K3_i K4_i qD_i + ĝ_i(q)",),
        loop_transfer="L_i(s) = Km_i (K2_i s² + K1_i s + K3_i) / (s² (τ_i s + 1)) on joint i's simplified link; "
                      "the margins are measured on the coupled arm with the other joints' loops closed",
        summary="Notes §3.1-3.3 and SIMNOG: each joint servoed by its own PID designed on its simplified link "
                "model (Km_i = 1/f_i, τ_i = D_ii(q*)/f_i); a centralized feed-forward cancels gravity.",
    ),
    validate=poles_or_requirements,
    knobs=gain_knobs(GAIN_INFO, ("K1", "K2", "K3", "K4")) + (
        Knob("poles", "1/s", "closed-loop poles each joint's gains place on its simplified link", 1e-3, 1e6,
             path="controller.poles", when=_one_pole_set),
        Knob("zero", "1/s", "zero of each joint's q_i/qD_i (sets K4)", 1e-6, 1e6, path="controller.zero")),
    traits=("pid",),
    regain=regain,
    diagnoses=(diagnose,),
)
