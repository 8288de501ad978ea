"""The ``controller`` section of the PID/sliding-mode family (notes §5.3-5.4), and its cross-section rules.

Fields (every number with its unit and range, refused with its key path otherwise):

* ``poles`` (1/s): three closed-loop poles of the linear PID part, real or a conjugate pair and a real pole;
  the zero of ``x1/xD`` is put on the real pole ``p3`` (the third one when all are real) and the sliding
  motion keeps ``p1, p2``.  A pole in the closed right half plane is refused (``slm' = p3 slm`` and the
  sliding motion ``1/(1 + a1 s + a2 s^2)`` would not be stable).
* ``form``: ``servo`` (figure 3.1, a step, square wave or PRBS reference) or ``tracking`` (figure 3.2, a smooth
  trajectory with its velocity and acceleration).
* ``perturbation_bound`` (N*m, 1e-6 to 1e6): ``sup |xi|`` of the external input-equivalent perturbation.
  Default ``|simulation.perturbation.value|`` (0 without one); a bound below the simulated perturbation is
  refused.  The parameter part of ``xi`` (§5.4) is computed by the design, not given.
* ``margin`` (1, above 0, at most 10; default 0.2): ``M = (1 + margin) sup|xi|`` when ``M`` is not given.
* ``M`` (N*m, 1e-6 to 1e6): the relay amplitude given instead of designed (the certificate judges it).
* ``epsilon`` (rad*s, above 0, at most 1e6): the boundary layer ``|slm| <= epsilon`` (§5.4); ``layer`` says
  how ``sign(slm)`` is replaced: ``saturation`` (``sat(slm/epsilon)``, continuous, default) or ``dead_zone``
  (the notes' printed form: 0 inside the layer, ``sign`` outside).
* ``switching_band`` (rad*s, above 0, at most 1e6): without a layer, the band ``|slm| <= delta`` the command
  held over an integration step leaves; sets the step.  Default: ``1e-3 e_max/||s/N||_1``, so the position
  error it leaves is at most ``1e-3`` of the largest reference jump.
* On a robot (:mod:`~designkit.families.pid_sliding_mode.robot`): ``workspace`` (a
  :class:`~designkit.spec.workspace.Workspace`, or ``joint_limits``; required, with
  ``plant.limits.velocity`` and ``plant.limits.acceleration``), ``gravity_feedforward`` (``measured`` or
  ``none``) and ``work_limit`` (1 to 100000 boxes per joint, default 150).  ``M`` is then one amplitude for
  every joint.
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

from pydantic import Field, field_validator, model_validator

from designkit.spec.controllers import three_poles
from designkit.spec.fields import Finite, Pole, Section, fmt_pole
from designkit.spec.ranges import Ranged, RangedInt
from designkit.spec.workspace import Workspace, joint_limits_word, workspace_schema

KIND = "pid_sliding_mode"
"""The controller kind of this family (the spec's ``controller.kind``)."""

IN_BAND, PRECISION, CHATTERING = "pid_sm_in_band", "pid_sm_precision", "pid_sm_chattering"
"""The names of the run checks the figures are the evidence of."""

__all__ = ["KIND", "PidSlidingModeSpec", "perturbation_level", "validate"]

SERVO_REFERENCES = ("step", "square", "prbs")
TRACKING_REFERENCES = ("quintic", "sine", "trapezoidal", "via_points")


class PidSlidingModeSpec(Section):
    """PID/sliding-mode link controller ``u = u0 - M sign(slm)``, ``slm = a1 x1 + a2 x2 + x3`` (module docstring
    for the fields)."""

    step_fields: ClassVar[dict[str, int]] = {"epsilon": 1, "switching_band": 1, "M": -1}
    """Fields that set the law's largest step (name -> +1: the step grows with it, -1: shrinks), first given
    first: the step-bound refusal names it (:func:`designkit.simulation.timing.step_field`)."""

    kind: Literal[KIND]
    poles: list[Pole] = Field(description="Three closed-loop poles (1/s) of the PID part; the zero goes on the "
                              "real one p3, the sliding motion keeps the other two.")
    form: Literal["servo", "tracking"] = Field(default="servo", description="servo (figure 3.1) or trajectory "
                                               "tracking (figure 3.2).")
    perturbation_bound: Ranged(1e-6, 1e6, "N*m", base=Finite) | None = Field(
        default=None, description="sup |xi| (N*m) of the external perturbation; default |simulation.perturbation|.")
    margin: Ranged(0, 10, "", low_open=True, base=Finite) = Field(
        default=0.2, description="M = (1 + margin) sup|xi| when M is not given.")
    M: Ranged(1e-6, 1e6, "N*m", base=Finite) | None = None
    epsilon: Ranged(0, 1e6, "rad*s", low_open=True, base=Finite) | None = Field(
        default=None, description="Boundary layer |slm| <= epsilon (rad*s) replacing sign(slm) (notes section 5.4).")
    layer: Literal["saturation", "dead_zone"] = Field(
        default="saturation", description="sat(slm/epsilon) (continuous) or the notes' dead zone.")
    switching_band: Ranged(0, 1e6, "rad*s", low_open=True, base=Finite) | None = Field(
        default=None, description="Without a layer: the band |slm| <= delta (rad*s) the held relay leaves.")
    workspace: Workspace | None = Field(
        default=None, json_schema_extra=workspace_schema,
        description="Robot: the box of configurations {low, high} (rad per joint) or 'joint_limits' the hierarchy "
        "of control bounds xi over (with plant.limits.velocity and plant.limits.acceleration).")
    gravity_feedforward: Literal["measured", "none"] = Field(
        default="measured", description="Robot: the model's gravity torque g(q) fed forward, or none (then g is "
        "part of xi).")
    work_limit: RangedInt(1, 100000) = Field(
        default=150, description="Robot: configuration boxes per joint the proven bound of sup|xi_i| may bisect.")

    @field_validator("workspace", mode="before")
    @classmethod
    def _joint_limits(cls, v: Any) -> Any:
        return joint_limits_word(v)

    @field_validator("poles")
    @classmethod
    def _stable_poles(cls, v: list[complex]) -> list[complex]:
        three_poles(v)
        for i, p in enumerate(v):
            if p.real >= 0:
                raise ValueError(f"[{i}]: must be in the open left half plane (Re p < 0), got {fmt_pole(p)}")
        return v

    @field_validator("M")
    @classmethod
    def _positive_relay(cls, v: float | None) -> float | None:
        if v is not None and v <= 0:
            raise ValueError(f"must be positive (the relay amplitude), got {v:g}")
        return v

    @field_validator("epsilon", "switching_band")
    @classmethod
    def _positive_width(cls, v: float | None) -> float | None:
        if v is not None and v <= 0:
            raise ValueError(f"must be positive, got {v:g}")
        return v

    @model_validator(mode="after")
    def _one_band(self) -> PidSlidingModeSpec:
        if self.epsilon is not None and self.switching_band is not None:
            raise ValueError("switching_band: give epsilon (a boundary layer) or switching_band (the relay held over "
                             "a step), not both")
        return self


def perturbation_level(sim: Any) -> float:
    """``max |simulation.perturbation.value|`` (N*m), 0 without a perturbation."""
    pert = sim.perturbation
    if pert is None:
        return 0.0
    values = pert.value if isinstance(pert.value, list | tuple) else [pert.value]
    return max(abs(float(v)) for v in values)


def validate(spec: Any) -> None:
    """Cross-section rules (``ValueError("key.path: message")``)."""
    ctl, sim = spec.controller, spec.simulation
    level = perturbation_level(sim)
    if ctl.perturbation_bound is not None and ctl.perturbation_bound < level:
        raise ValueError(f"controller.perturbation_bound: {ctl.perturbation_bound:g} N*m is below the simulated "
                         f"perturbation |xi| = {level:g} N*m (simulation.perturbation.value): the bound would not "
                         "cover the run")
    if sim.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the integral is part of the sliding variable; an anti-windup "
                         "would change the sliding motion")
    kinds = SERVO_REFERENCES if ctl.form == "servo" else TRACKING_REFERENCES
    traj = sim.trajectory
    if ctl.form == "tracking" and traj is None:
        raise ValueError("simulation.trajectory: the tracking form (figure 3.2) follows a trajectory "
                         f"({', '.join(TRACKING_REFERENCES)})")
    if traj is not None and traj.kind not in kinds:
        raise ValueError(f"simulation.trajectory.kind: the {ctl.form} form follows {', '.join(kinds)}, not "
                         f"{traj.kind} (controller.form)")
    key = sim.still_reference()
    if key is not None:
        raise ValueError(f"{key}: the reference does not move (amplitude 0): there is no error to slide to 0 (the "
                         "switching band and the integration step are sized on the reference's displacement)")


def refuse_chatter_limit(spec: Any, plant_kind: str) -> None:
    """``requirements.max_chatter_amplitude`` is judged on the link only (its ``pid_sm_chattering`` check): refused,
    naming the key, on the ``plant_kind`` (elastic joint, robot) whose checks do not measure it."""
    req = getattr(spec, "requirements", None)
    if req is not None and getattr(req, "max_chatter_amplitude", None) is not None:
        from designkit.errors import SpecError

        raise SpecError("requirements.max_chatter_amplitude", f"the pid_sliding_mode controller measures the chatter "
                        f"amplitude on the link only, not on the {plant_kind} plant")

