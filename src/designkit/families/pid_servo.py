"""PID position servo of one link (notes section 3.2, fig. 2.1): the ``pid_servo`` family.

Plant: the simplified link ``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)`` (also the elastic joint, on its rigid
approximation, and any single-input linear plant of order 2 -- ``transfer_function`` or ``state_space`` -- placed
through the closed-loop characteristic polynomial, :mod:`designkit.synthesis.linear_servo`).  Law, with the
integral ``x3' = x1 - xD``::

    u = -K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD

Gains from three closed-loop poles and the zero of ``x1/xD`` by matching the characteristic
polynomial (derivation in :mod:`designkit.synthesis.pid`); K1 N*m/rad, K2 N*m*s/rad,
K3 N*m/(rad*s), K4 s.  The loop (gains, characteristic polynomial, law, closed loop) is
:mod:`designkit.synthesis.servo_loop`'s; this module adds the spec, the elastic joint and the
family's declaration.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from pydantic import field_validator, model_validator

from designkit.spec.controllers import LinearPoleRequirementsController
from designkit.spec.fields import Finite
from designkit.spec.ranges import Ranged
from designkit.synthesis import pid
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, FamilyData, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import Knob, Metric, gain_knobs
from designkit.synthesis.law import Law
from designkit.synthesis.linear_servo import linear_servo_design, linear_servo_law, pid_poles, pid_spec_rule
from designkit.synthesis.pid import GAIN_INFO
from designkit.synthesis.servo_loop import servo_design, servo_law

KIND = "pid_servo"

class PidServoSpec(LinearPoleRequirementsController):
    """PID position servo ``u = -K1 (x1 - xD) - K2 x2 - K3 int(x1 - xD) + K3 K4 xD``.

    ``zero`` (1/s, -1e12 to -1e-12) is the closed-loop zero of ``x1/xD``; when omitted, ``K4 = 0`` and
    the zero falls at ``-K3/K1`` (reported), or, with poles derived from requirements, on the third pole.
    """

    kind: Literal["pid_servo"]
    zero: Ranged(-1e12, -1e-12, "1/s", base=Finite) | None = None

    @field_validator("zero")
    @classmethod
    def _lhp_zero(cls, v: float | None) -> float | None:
        if v is not None and v >= 0:
            raise ValueError(f"must be negative (left half plane), got {v:g}")
        return v

    @model_validator(mode="after")
    def _zero_not_pole(self) -> PidServoSpec:
        if self.zero is not None and self.poles is not None:
            for p in self.poles:
                if abs(p - self.zero) <= 1e-9 * (1 + abs(p)):
                    raise ValueError(f"zero: must differ from every pole, got {self.zero:g} equal to a pole")
        return self


LINEAR = ("transfer_function", "state_space")
"""The general linear plant kinds, designed by :mod:`designkit.synthesis.linear_servo`."""


def law_lines(design: Any) -> tuple[str, ...]:
    """The law in the linear plant's signal names (``()`` on the link and the elastic joint: the family's own)."""
    plant = design.plant
    if plant.kind not in LINEAR:
        return ()
    y = plant.states[plant.positions[0]].name
    u = plant.inputs[0].name
    return (f"{u} = −K1 ({y} − xD) − K2 r x − K3 ∫({y} − xD) dt + K3 K4 xD,   r x = c A x "
            f"(= {y}' when the relative degree is 2)",)


def loop_line(design: Any) -> str | None:
    """The loop at the plant input of a linear plant of relative degree 2 in closed form, ``""`` at relative degree 1
    (the rate row then reads part of the input), None on the other plants (the family's own line)."""
    plant = design.plant
    if plant.kind not in LINEAR:
        return None
    A, B, _, _ = plant.matrices()
    c = np.eye(A.shape[0])[plant.positions[0]]
    if abs(float(c @ B[:, 0])) > 1e-12 * (1.0 + float(np.abs(B).max())):
        return ""
    written = (plant.equations()[0].split("=", 1)[1].strip() if plant.kind == "transfer_function"
               else "c (sI − A)⁻¹ b")
    return f"L(s) = (K2 s² + K1 s + K3) P(s) / s,   P(s) = {written}"


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = -K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD``, ``x3' = x1 - xD`` (N*m;
    :func:`~designkit.synthesis.servo_loop.servo_law`); on a linear plant the rate is ``c A x``
    (:func:`~designkit.synthesis.linear_servo.linear_servo_law`)."""
    if design.plant.kind in LINEAR:
        return linear_servo_law(design, anti_windup)
    return servo_law(design, anti_windup)


def design(plant: Any, poles: Sequence[complex], zero: float | None = None, *, notes: tuple[str, ...] = (),
           extra: dict | None = None) -> Design:
    """The PID servo of the link ``plant`` placing ``poles`` (1/s) and ``zero`` (1/s)
    (:func:`~designkit.synthesis.servo_loop.servo_design`).

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> d = design(LinkPlant(Km=2.0, tau=0.5), [-4, -5, -20], -3.0)
    >>> [round(float(d.gains[k]), 6) for k in ("K1", "K2", "K3", "K4")]
    [50.0, 6.75, 100.0, -0.166667]
    >>> sorted(round(float(p.real), 6) for p in d.closed_loop.poles)
    [-20.0, -5.0, -4.0]
    """
    return servo_design(plant, poles, zero, kind=KIND, notes=notes, extra=extra)


@dataclass(frozen=True)
class ElasticServoData(FamilyData):
    """The elastic joint's servo design data (:attr:`~designkit.synthesis.design.Design.data`).

    Attributes
    ----------
    rigid_Km, rigid_tau : float
        The rigid approximation the gains are placed on ((rad/s) per input unit, s).
    requested_poles : tuple of complex
        The poles placed on the rigid approximation (1/s).
    zero : float
        The zero of ``x3/xD`` there (1/s).
    loop_poles : tuple of complex
        The poles of the loop with the elastic transmission (1/s).
    elastic_mode_damping : float
        The damping ratio of its most oscillatory pole (dimensionless).
    controlled : str
        What the servo controls, in words.
    """

    rigid_Km: float
    rigid_tau: float
    requested_poles: tuple[complex, ...]
    zero: float
    loop_poles: tuple[complex, ...]
    elastic_mode_damping: float
    controlled: str


def elastic_design(plant: Any, poles: Sequence[complex], zero: float | None, *, notes: tuple[str, ...] = (),
                   extra: dict | None = None) -> Design:
    """The PID servo of the **load** position ``x3`` (rate feedback on the load speed ``x4``) of the elastic joint
    ``plant``, its gains placing ``poles`` and ``zero`` on the rigid approximation
    (:func:`~designkit.models.elastic.rigid_approximation`), verified on the 4-state loop.

    The loop with the transmission has five poles (the integral, the link and the lightly damped elastic mode),
    not the three requested: the design carries no requested poles (``pole_placement`` and ``routh_hurwitz`` are
    statements about the rigid link), and the generic checks judge the true loop (``lyapunov``, ``robustness``,
    ``loop_margins``, ``designed_loop``, ``time_domain``); its poles are in the notes and in its
    :class:`ElasticServoData`.
    """
    import numpy as np

    from designkit.models.elastic import rigid_approximation
    from designkit.models.link import LinkPlant

    Km_r, tau_r = rigid_approximation(plant.params)
    rigid = LinkPlant(Km=Km_r, tau=tau_r)
    values = pid.servo_gains(rigid, poles, zero)
    u_unit = plant.inputs[0].unit
    g = Gains.of(Gain(k, v, GAIN_INFO[k][0].replace("N*m", u_unit), GAIN_INFO[k][1]) for k, v in values.items())
    z = zero if zero is not None else -float(g["K3"]) / float(g["K1"])
    d = Design(kind=KIND, plant=plant, gains=g, poles=(), zeros=(), reference="step", formulas=pid.SERVO_FORMULAS,
               notes=tuple(notes), extra=dict(extra or {}))
    d = with_closed_loop(d, law(d), [0.0, 0.0, 0.0], field="controller.poles")
    true_poles = np.linalg.eigvals(d.closed_loop.A)
    slowest = max(float(p.real) for p in true_poles)
    flex = max(true_poles, key=lambda p: abs(p.imag))
    damping = -flex.real / abs(flex) if abs(flex) > 0 else 1.0
    fmt = ", ".join(f"{p.real:.4g}{p.imag:+.4g}j" if abs(p.imag) > 1e-9 else f"{p.real:.4g}" for p in true_poles)
    note = (f"Gains placed on the rigid approximation (Km = {Km_r:.4g} rad/s per {u_unit}, τ = {tau_r:.4g} s): poles "
            f"{', '.join(f'{complex(p).real:.4g}' for p in poles)} 1/s and zero {z:.4g} 1/s there. With the elastic "
            f"transmission the loop has the poles {fmt} 1/s (elastic mode damping {damping:.3g}); "
            + ("it is stable." if slowest < 0 else "it is UNSTABLE: slow the poles down."))
    info = ElasticServoData(rigid_Km=Km_r, rigid_tau=tau_r, requested_poles=tuple(complex(p) for p in poles), zero=z,
                            loop_poles=tuple(complex(p) for p in true_poles), elastic_mode_damping=damping,
                            controlled="load position x3 (rate feedback on x4)")
    import dataclasses

    return dataclasses.replace(d, notes=(*d.notes, note), data=info)


def synthesize(spec: Any, plant: Any) -> Design:
    """The servo a spec asks for: poles given, or derived from the requirements (zero on the third pole)."""
    poles, notes, extra = pid_poles(spec.controller, spec.requirements, plant, LINEAR)
    zero = spec.controller.zero
    if zero is None and spec.controller.poles is None and len(poles) == 3:
        zero = poles[2].real
        notes = (*notes, f"No zero given: placed on the third pole ({zero:.6g} 1/s) so that the "
                 "reference response is the dominant second-order one.")
    if plant.kind in LINEAR:
        return linear_servo_design(plant, poles, zero, kind=KIND, notes=notes, extra=extra)
    if plant.kind == "elastic_joint":
        from designkit.synthesis.state_space import check_controllable, linear_model

        model = linear_model(plant)
        unc = spec.plant.uncertainty
        box = {k: tuple(v) for k, v in (unc.intervals.items() if unc is not None else ()) if k in model.names}
        check_controllable(spec, model, box, "no controller on the motor moves the link")
        return elastic_design(plant, poles, zero, notes=notes, extra=extra)
    return design(plant, poles, zero, notes=notes, extra=extra)


def strategy(result: Any) -> tuple[str, ...]:
    """What the servo measures and what its design needs, with the design's poles and zero (1/s) (a study's
    ``strategy`` answer, :data:`designkit.synthesis.family.ANSWER_TOPICS`)."""
    from designkit.display.numbers import fmt_number, fmt_poles

    d = result.design
    poles, zero = fmt_poles(d.poles), fmt_number(d.zeros[0].real if d.zeros else None, 4)
    info = d.data if isinstance(d.data, ElasticServoData) else None
    if info is not None:
        poles, zero = fmt_poles(info.requested_poles), fmt_number(info.zero, 4)
        return (f"u = −K1 (x3 − xD) − K2 x4 − K3 ∫(x3 − xD) dt + K3 K4 xD on the link's position and speed: its gains "
                f"place the poles {poles} 1/s and the zero {zero} 1/s on the rigid approximation (Km = "
                f"{fmt_number(info.rigid_Km, 4)}, τ = {fmt_number(info.rigid_tau, 4)} s) by matching the "
                f"characteristic polynomial; with the elastic transmission the loop's poles are "
                f"{fmt_poles(info.loop_poles)} 1/s. Its integral action removes a constant load's offset.",)
    return (f"u = −K1 (x1 − xD) − K2 x2 − K3 ∫(x1 − xD) dt + K3 K4 xD: its gains place the poles {poles} 1/s and "
            f"the zero {zero} 1/s by matching the characteristic polynomial on the link (notes §3.2). Its integral "
            "action removes a constant load's offset.",)


def load_offset(result: Any) -> float | None:
    """The static offset (rad) a constant load of the spec's ``simulation.perturbation`` leaves: 0, the integral of
    the controlled position's error being held at rest; None without a perturbation."""
    return 0.0 if result.loaded.spec.simulation.perturbation is not None else None


FAMILY = Family(
    kind=KIND,
    spec=PidServoSpec,
    plants=("link", "elastic_joint", *LINEAR),
    uses=("simulation.anti_windup", "plant.uncertainty", "plant.uncertainty.grid", "plant.uncertainty.samples"),
    reference="step",
    synthesize=synthesize,
    law=law,
    checks=("pole_placement", "routh_hurwitz", "lyapunov", "robust_box", "robustness", "loop_margins",
            "designed_loop", "time_domain"),
    display=Display(
        label="PID position servo",
        law=("u = -K1 (x1 - xD) - K2 x2 - K3 ∫(x1 - xD) dt + K3 K4 xD",),
        loop_transfer="L(s) = Km (K2 s² + K1 s + K3) / (s² (τ s + 1))",
        law_of=law_lines,
        loop_transfer_of=loop_line,
        summary="Notes §3.2: one link positioned by a PID with reference feedforward; the gains place three "
                "closed-loop poles and the zero of x1/xD.",
    ),
    validate=pid_spec_rule,
    knobs=gain_knobs(GAIN_INFO, ("K1", "K2", "K3", "K4")) + (
        Knob("poles", "1/s", "closed-loop poles the gains place", 1e-3, 1e6, path="controller.poles"),
        Knob("zero", "1/s", "closed-loop zero of the controlled position over xD (sets K4)", 1e-6, 1e6,
             path="controller.zero")),
    traits=("pid",),
    answers=(("strategy", strategy),),
    predictions=(Metric("load_offset", "static offset a constant load leaves (closed form)", "rad", load_offset,
                        "0: the integral action holds the controlled position at xD"),),
)
