"""Dispatch from a spec's ``controller.kind`` to its controller family.

A family bundles what the rest of the pipeline needs from a controller kind: how to
synthesise it from a spec, its closed loop on any plant of the family's plant type (for
robustness checks), and the characteristic polynomial as a vectorised function of the plant
parameters.  A new controller kind is one new module plus one entry in :data:`FAMILIES`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.models.link import LinkPlant
from designkit.spec.schema import Spec
from designkit.synthesis import pid
from designkit.synthesis.design import Design
from designkit.synthesis.linear_system import LinearSystem
from designkit.synthesis.requirements import dominant_poles


@dataclass(frozen=True)
class ControllerFamily:
    """What the pipeline needs from one controller kind.

    Parameters
    ----------
    kind : str
        The spec's ``controller.kind``.
    synthesize : callable
        ``Spec -> Design``.
    closed_loop : callable
        ``(Design, plant) -> LinearSystem``: the design's gains acting on another plant.
    characteristic : callable
        ``(Design, Km, tau) -> tuple of arrays``: closed-loop characteristic polynomial
        coefficients (highest power first) for arrays of plant parameters.
    reference : str
        ``"step"`` or ``"trajectory"``: what the simulation drives the loop with.
    """

    kind: str
    synthesize: Callable[[Spec], Design]
    closed_loop: Callable[[Design, Any], LinearSystem]
    characteristic: Callable[[Design, np.ndarray, np.ndarray], tuple[np.ndarray, ...]]
    reference: str


def _poles_from_spec(spec: Spec) -> tuple[tuple[complex, ...], tuple[str, ...], dict[str, float]]:
    ctrl = spec.controller
    if ctrl.poles is not None:
        return tuple(ctrl.poles), (), {}
    req = spec.requirements
    assert req is not None and req.overshoot is not None and req.settling_time is not None  # schema guarantees
    tighten = 1.0 - ctrl.design_margin
    overshoot, settling = tighten * req.overshoot, tighten * req.settling_time
    dom = dominant_poles(overshoot, settling, third_pole_factor=ctrl.third_pole_factor, band=req.settling_band)
    note = (
        f"Poles derived from requirements tightened by the design margin {ctrl.design_margin:g}: overshoot "
        f"{overshoot:g} % -> zeta = {dom.zeta:.4f}; settling time {settling:g} s "
        f"({100 * req.settling_band:g} % band, exact 2nd-order) -> wn = {dom.wn:.4f} rad/s; "
        f"third pole at {ctrl.third_pole_factor:g} x Re(p1)."
    )
    return dom.poles, (note,), {"zeta": dom.zeta, "wn": dom.wn}


def plant_from_spec(spec: Spec) -> LinkPlant:
    """The nominal plant of a spec."""
    return LinkPlant(Km=spec.plant.Km, tau=spec.plant.tau)


def _synthesize_servo(spec: Spec) -> Design:
    poles, notes, extra = _poles_from_spec(spec)
    zero = spec.controller.zero
    if zero is None and spec.controller.poles is None:
        zero = poles[2].real
        notes = (*notes, f"No zero given: placed on the third pole ({zero:.6g} 1/s) so that the "
                 "reference response is the dominant second-order one.")
    return pid.design_servo(plant_from_spec(spec), poles, zero, notes=notes, extra=extra)


def _synthesize_tracking(spec: Spec) -> Design:
    poles, notes, extra = _poles_from_spec(spec)
    return pid.design_tracking(plant_from_spec(spec), poles, notes=notes, extra=extra)


FAMILIES: dict[str, ControllerFamily] = {
    "pid_servo": ControllerFamily(
        kind="pid_servo",
        synthesize=_synthesize_servo,
        closed_loop=lambda design, plant: pid.servo_closed_loop(dict(design.gains), plant),
        characteristic=lambda design, Km, tau: pid.servo_characteristic(dict(design.gains), Km, tau),
        reference="step",
    ),
    "pid_tracking": ControllerFamily(
        kind="pid_tracking",
        synthesize=_synthesize_tracking,
        closed_loop=lambda design, plant: pid.tracking_closed_loop(dict(design.gains), plant, design.plant),
        characteristic=lambda design, Km, tau: pid.tracking_characteristic(
            dict(design.gains), Km, tau, design.plant
        ),
        reference="trajectory",
    ),
}


def family(kind: str) -> ControllerFamily:
    """The family registered for ``kind``; :class:`SpecError` naming ``controller.kind`` otherwise."""
    try:
        return FAMILIES[kind]
    except KeyError:
        raise SpecError("controller.kind", f"unknown controller kind {kind!r}; known: {sorted(FAMILIES)}") from None


def synthesize(spec: Spec) -> Design:
    """Synthesise the controller a spec asks for."""
    return family(spec.controller.kind).synthesize(spec)
