"""PID trajectory tracking of one link (notes section 3.2, fig. 2.2): the ``pid_tracking`` family.

Law, with ``e = x1 - xD`` and the integral ``x3' = e``, ``tau0``, ``Km0`` the nominal link::

    u = (tau0/Km0) xD'' + x2/Km0 - K1 e - K2 (x2 - xD') - K3 x3

The ``x2/Km0`` term cancels the link damping, so on the nominal link the error obeys
``tau e''' + Km K2 e'' + Km K1 e' + Km K3 e = Km xi'``: ``x1/xD = 1`` and the gains differ from
the servo's (``K2`` by ``1/Km``; see :mod:`designkit.synthesis.pid` and the errata page).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal

from designkit.spec.controllers import PoleRequirementsController
from designkit.synthesis import pid
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Characteristic, Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import gain_knobs
from designkit.synthesis.law import Law, integral_law
from designkit.synthesis.pid import GAIN_INFO
from designkit.synthesis.requirements import poles_from_spec, poles_or_requirements

KIND = "pid_tracking"


class PidTrackingSpec(PoleRequirementsController):
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
    """``u = (tau0/Km0) xD'' + x2/Km0 - K1 e - K2 (x2 - xD') - K3 x3``, ``x3' = e`` (N*m)."""
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
    poles, notes, extra = poles_from_spec(spec.controller, spec.requirements)
    return design(plant, poles, notes=notes, extra=extra)


FAMILY = Family(
    kind=KIND,
    spec=PidTrackingSpec,
    plants=("link",),
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
        summary="Notes §3.2: one link tracking a trajectory with acceleration and damping feedforward; the "
                "error dynamics have the requested poles and x1/xD = 1 on the nominal link.",
    ),
    validate=poles_or_requirements,
    knobs=gain_knobs(GAIN_INFO, ("K1", "K2", "K3")),
    traits=("pid",),
)
