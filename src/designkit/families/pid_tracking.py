"""PID trajectory tracking of one link (notes section 3.2, fig. 2.2): the ``pid_tracking`` family.

Law, with ``e = x1 - xD`` and the integral ``x3' = e``, ``tau0``, ``Km0`` the nominal link::

    u = (tau0/Km0) xD'' + x2/Km0 - K1 e - K2 (x2 - xD') - K3 x3

The ``x2/Km0`` term cancels the link damping, so on the nominal link the error obeys
``tau e''' + Km K2 e'' + Km K1 e' + Km K3 e = Km xi'``: ``x1/xD = 1`` and the gains differ from
the servo's (``K2`` by ``1/Km``; see :mod:`designkit.synthesis.pid` and the errata page).

On a ``transfer_function`` or ``state_space`` plant of any order (relative degree 1 or 2, minimum phase) the
feedforward is the nominal plant's inverse and the gains place the error loop's poles through its characteristic
polynomial (:mod:`designkit.synthesis.linear_tracking`): ``y/xD = 1`` on the nominal plant there too.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal

from designkit.spec.controllers import LinearPoleRequirementsController
from designkit.synthesis import pid
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Characteristic, Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import gain_knobs
from designkit.synthesis.law import Law, integral_law
from designkit.synthesis.linear_servo import pid_poles, pid_spec_rule
from designkit.synthesis.linear_tracking import linear_tracking_design, linear_tracking_law
from designkit.synthesis.pid import GAIN_INFO

KIND = "pid_tracking"
LINEAR = ("transfer_function", "state_space")
"""The general linear plant kinds, designed by :mod:`designkit.synthesis.linear_tracking`."""


class PidTrackingSpec(LinearPoleRequirementsController):
    """PID trajectory tracking ``u = (tau/Km) xD'' + x2/Km - K1 dx1 - K2 dx2 - K3 int(dx1)``."""

    kind: Literal["pid_tracking"]


def characteristic(nominal: Any) -> Characteristic:
    """``tau s^3 + (1 - Km/Km0 + Km K2) s^2 + Km K1 s + Km K3`` on a plant ``(Km, tau)``."""
    return Characteristic(
        parameters=("Km", "tau"),
        coefficients=lambda g, Km, tau: pid.tracking_characteristic(dict(g), Km, tau, nominal),
        labels=("tau", "1 - Km/Km0 + Km K2", "Km K1", "Km K3"),
        gain_labels={"a1": ("K2", "K2 > (Km/Km0 - 1)/Km"), "a2": ("K1", "K1 > tau K3/(1 - Km/Km0 + Km K2)"),
                     "a3": ("K3", "K3 > 0")},
        linear_conditions=lambda g: pid.tracking_conditions(dict(g), nominal),
    )


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = (tau0/Km0) xD'' + x2/Km0 - K1 e - K2 (x2 - xD') - K3 x3``, ``x3' = e`` (N*m); on a linear plant
    :func:`~designkit.synthesis.linear_tracking.linear_tracking_law`."""
    if design.plant.kind in LINEAR:
        return linear_tracking_law(design, anti_windup)
    K1, K2, K3 = (float(design.gains[k]) for k in ("K1", "K2", "K3"))
    Km0, tau0 = float(design.plant.Km), float(design.plant.tau)
    v = design.plant.velocities[0]
    return integral_law(
        KIND, design.plant, [K3], anti_windup,
        lambda y, xc, r, e: (tau0 / Km0) * r[2] + y[v] / Km0 - K1 * e[0] - K2 * (y[v] - r[1]) - K3 * xc[0],
        {"gains": design.gains.to_json(), "nominal_plant": {"Km": Km0, "tau": tau0}},
    )


def design(plant: Any, poles: Sequence[complex], *, notes: tuple[str, ...] = (), extra: dict | None = None) -> Design:
    """The PID tracker of the link ``plant`` whose error dynamics have ``poles`` (1/s).

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> d = design(LinkPlant(Km=2.0, tau=0.5), [-10, -12, -15])
    >>> [round(float(d.gains[k]), 6) for k in ("K1", "K2", "K3")]
    [112.5, 9.25, 450.0]
    """
    values = pid.tracking_gains(plant, poles)
    g = Gains.of(Gain(k, v, *GAIN_INFO[k]) for k, v in values.items())
    d = Design(
        kind=KIND, plant=plant, gains=g, poles=tuple(poles), zeros=(), reference="trajectory",
        characteristic=characteristic(plant), formulas=pid.TRACKING_FORMULAS, notes=notes,
        extra=dict(extra or {}),
    )
    return with_closed_loop(d, law(d), [0.0, 0.0, 0.0], field="controller.poles")


def synthesize(spec: Any, plant: Any) -> Design:
    """The tracker a spec asks for (poles given or derived from the requirements)."""
    poles, notes, extra = pid_poles(spec.controller, spec.requirements, plant, LINEAR)
    if plant.kind in LINEAR:
        return linear_tracking_design(plant, poles, kind=KIND, notes=notes, extra=extra)
    return design(plant, poles, notes=notes, extra=extra)


def law_lines(design: Any) -> tuple[str, ...]:
    """The law in the linear plant's signal names (``()`` on the link: the family's own)."""
    plant = design.plant
    if plant.kind not in LINEAR:
        return ()
    y = plant.states[plant.positions[0]].name
    u = plant.inputs[0].name
    return (f"{u} = u_ff − K1 ({y} − xD) − K2 (r x − ρ_D) − K3 ∫({y} − xD) dt,   r x = c A x,   "
            "ρ_D = xD' − (c b) u_ff",
            "u_ff = G⁻¹(s) xD = q0 xD + q1 xD' + q2 xD'' (+ a filter at the plant's zeros): y = xD on the nominal "
            "plant")


def loop_line(design: Any) -> str | None:
    """No closed form on a linear plant (``""``); None on the link (the family's own line)."""
    return "" if design.plant.kind in LINEAR else None


FAMILY = Family(
    kind=KIND,
    spec=PidTrackingSpec,
    plants=("link", *LINEAR),
    uses=("simulation.anti_windup", "plant.uncertainty", "plant.uncertainty.grid", "plant.uncertainty.samples"),
    reference="trajectory",
    synthesize=synthesize,
    law=law,
    checks=("pole_placement", "routh_hurwitz", "lyapunov", "robust_box", "robustness", "loop_margins",
            "designed_loop", "time_domain"),
    display=Display(
        label="PID trajectory tracking",
        law=("u = (τ/Km) xD'' + x2/Km - K1 (x1 - xD) - K2 (x2 - xD') - K3 ∫(x1 - xD) dt",),
        loop_transfer="L(s) = ((Km K2 − 1) s² + Km K1 s + Km K3) / (s² (τ s + 1))  (x2/Km cancels the link damping)",
        law_of=law_lines,
        loop_transfer_of=loop_line,
        summary="Notes §3.2: one link tracking a trajectory with acceleration and damping feedforward; the "
                "error dynamics have the requested poles and x1/xD = 1 on the nominal link.",
    ),
    validate=pid_spec_rule,
    knobs=gain_knobs(GAIN_INFO, ("K1", "K2", "K3")),
    traits=("pid",),
)
