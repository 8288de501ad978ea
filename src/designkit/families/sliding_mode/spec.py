"""The ``controller`` section of the ``sliding_mode`` family, and its cross-section rules.

Fields (every number with its unit and range, refused with its key path otherwise):

* ``sliding_poles`` (1/s): on the link one real pole ``-c`` of the motion on the sliding line
  ``s = x2 + c e = 0`` (``e = x1 - xD``): on the line ``e' = -c e``; on a ``transfer_function`` or ``state_space``
  plant the ``n - 1`` poles of the sliding motion (:mod:`~designkit.families.sliding_mode.linear`).  A pole in the
  closed right half plane is refused (the line would not bring ``e`` to 0); ``|p|`` 1e-12 to 1e12.
* ``perturbation_bound`` (N*m, 1e-6 to 1e6): ``sup |xi|``, the input-equivalent perturbation the relay must
  dominate (notes section 5.4: "an evaluation of its upper value is required").  Default: ``|value|`` of
  ``simulation.perturbation``; with neither the spec is refused, and a bound below the simulated perturbation
  is refused too (the certificate would not cover the run).
* ``margin`` (1, above 0, at most 10; default 0.2): the design's relative margin on every condition
  (:mod:`~designkit.families.sliding_mode.design_lp`).
* ``chattering_band`` (rad/s, above 0, at most 1e6): the band ``|s| <= delta`` the held command may leave
  around the sliding line; it sets the integration step.  At most half the strip where ``s s' < 0`` holds
  (:func:`~designkit.families.sliding_mode.conditions.strip_width`), else refused.  Default ``1e-3 c e_max``
  (``e_max`` the largest error jump of the reference), so the error the chattering leaves is at most
  ``1e-3 e_max``.
* ``boundary_layer`` (rad/s, above 0, at most 1e6): replace ``sign(s)`` by ``sat(s/epsilon)`` (notes
  section 5.4); the band is then ``epsilon``, at most half the strip.  Not together with ``chattering_band``.
* ``reaching_frequency`` (rad/s, above 0, at most 1e6): ``omega_r``, a lower bound on the natural frequency
  ``sqrt(b alpha)`` of the ``alpha`` structure at every corner (faster reaching; the minimal-switching default
  reaches slowly against an opposing perturbation).  Default: none.
* ``alpha``, ``beta`` (N*m/rad, within 1e6), ``M`` (N*m, above 0, at most 1e6): gains given instead of
  designed (the design program then only chooses the others; the certificate judges them all).
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

from pydantic import Field, field_validator, model_validator

from designkit.spec.fields import Finite, Pole, Section, check_conjugates, fmt_pole
from designkit.spec.ranges import Ranged, check_poles

KIND = "sliding_mode"
"""The controller kind of this family (the spec's ``controller.kind``)."""

__all__ = ["SlidingModeSpec", "reference_amplitude", "perturbation_level", "validate"]


class SlidingModeSpec(Section):
    """Sliding-mode position servo ``u = -psi e - M sign(s)``, ``s = x2 + c e``, ``psi`` switching between
    ``alpha`` (``e s > 0``) and ``beta`` (module docstring for the fields)."""

    step_fields: ClassVar[dict[str, int]] = {"boundary_layer": 1, "chattering_band": 1, "M": -1}
    """Fields that set the law's largest step (name -> +1: the step grows with it, -1: shrinks), first given
    first: the step-bound refusal names it (:func:`designkit.simulation.timing.step_field`)."""

    kind: Literal[KIND]
    sliding_poles: list[Pole] = Field(
        description="The pole -c (1/s) of the motion on the sliding line s = x2 + c (x1 - xD) = 0: one real value.")
    perturbation_bound: Ranged(1e-6, 1e6, "N*m", base=Finite) | None = Field(
        default=None, description="sup |xi| (N*m) the relay must dominate; default |simulation.perturbation.value|.")
    margin: Ranged(0, 10, "", low_open=True, base=Finite) = Field(
        default=0.2, description="Relative margin of the designed gains on every condition.")
    chattering_band: Ranged(0, 1e6, "rad/s", low_open=True, base=Finite) | None = Field(
        default=None, description="Band |s| <= delta (rad/s) the held command may leave; sets the step.")
    boundary_layer: Ranged(0, 1e6, "rad/s", low_open=True, base=Finite) | None = Field(
        default=None, description="epsilon (rad/s): sat(s/epsilon) instead of sign(s) (notes section 5.4).")
    reaching_frequency: Ranged(0, 1e6, "rad/s", low_open=True, base=Finite) | None = Field(
        default=None, description="omega_r (rad/s): the alpha structure's natural frequency sqrt(b alpha) at least "
        "omega_r on the box (faster reaching, a larger switching amplitude).")
    alpha: Ranged(-1e6, 1e6, "N*m/rad", base=Finite) | None = None
    beta: Ranged(-1e6, 1e6, "N*m/rad", base=Finite) | None = None
    M: Ranged(1e-6, 1e6, "N*m", base=Finite) | None = None

    @field_validator("sliding_poles")
    @classmethod
    def _poles(cls, v: list[complex]) -> list[complex]:
        if not v:
            raise ValueError("must list the poles of the sliding motion (1 on the link: -c), got none")
        check_poles(v)
        return v

    @field_validator("M")
    @classmethod
    def _positive_relay(cls, v: float | None) -> float | None:
        if v is not None and v <= 0:
            raise ValueError(f"must be positive (the relay amplitude), got {v:g}")
        return v

    @model_validator(mode="after")
    def _one_band(self) -> SlidingModeSpec:
        if self.chattering_band is not None and self.boundary_layer is not None:
            raise ValueError("boundary_layer: give chattering_band (the sign held over a step) or boundary_layer "
                             "(sat(s/epsilon)), not both")
        return self


def perturbation_level(sim: Any) -> float | None:
    """``max |simulation.perturbation.value|`` (N*m), None without a perturbation."""
    pert = sim.perturbation
    if pert is None:
        return None
    values = pert.value if isinstance(pert.value, list | tuple) else [pert.value]
    return max(abs(float(v)) for v in values)


def reference_amplitude(sim: Any) -> tuple[float, float]:
    """``(A, e_max)`` (rad): the reference's displacement and the largest error jump it causes (``A`` for
    ``simulation.step``, ``2 A`` for a square wave or a PRBS, which switch between ``q0 + A`` and ``q0 - A``)."""
    traj = sim.trajectory
    if traj is None:
        value = sim.step
        jump = 1.0
    else:
        value = traj.amplitude
        jump = 2.0
    values = value if isinstance(value, list | tuple) else [value]
    amp = max(abs(float(v)) for v in values)
    return amp, jump * amp


def validate(spec: Any) -> None:
    """Cross-section rules (``ValueError("key.path: message")``): a perturbation bound must be known and cover
    the simulated perturbation; the law has no integral for an anti-windup; the reference must move."""
    ctl, sim = spec.controller, spec.simulation
    if spec.plant.kind == "link":
        if len(ctl.sliding_poles) != 1:
            raise ValueError(f"controller.sliding_poles: must list exactly 1 pole on the link (the sliding line's -c), "
                             f"got {len(ctl.sliding_poles)}")
        if ctl.sliding_poles[0].imag != 0:
            raise ValueError(f"controller.sliding_poles[0]: must be real (s = x2 + c e has one real pole -c), got "
                             f"{fmt_pole(ctl.sliding_poles[0])}")
    else:
        try:
            check_conjugates(list(ctl.sliding_poles))
        except ValueError as exc:
            raise ValueError(f"controller.sliding_poles{'' if str(exc).startswith('[') else ': '}{exc}") from None
    if spec.plant.kind != "link" and spec.requirements is not None and \
            spec.requirements.max_chatter_amplitude is not None:
        raise ValueError(f"requirements.max_chatter_amplitude: the sliding-mode servo measures its chatter on the link "
                         f"only, not on the {spec.plant.kind} plant")
    level = perturbation_level(sim)
    if ctl.perturbation_bound is None and not level:
        raise ValueError("controller.perturbation_bound: give sup |xi| (N*m), the perturbation the relay M must "
                         "dominate (notes section 5.4: its upper value is required), or a simulation.perturbation")
    if ctl.perturbation_bound is not None and level is not None and ctl.perturbation_bound < level:
        raise ValueError(f"controller.perturbation_bound: {ctl.perturbation_bound:g} N*m is below the simulated "
                         f"perturbation |xi| = {level:g} N*m (simulation.perturbation.value): the certificate "
                         "would not cover the run")
    if sim.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the sliding-mode law has no integral to wind up")
    key = sim.still_reference()
    if key is not None:
        raise ValueError(f"{key}: the reference does not move (amplitude 0): there is no error to slide to 0")
