"""Every verification check of a design, chosen by what the design exposes, in report order.

A check runs when the design's family offers it (``Family.checks``) *and* the design exposes what
it needs (:data:`CHECKS`, the ``applies`` column); the solver or simulation results never decide
which checks exist.  In report order:

================== ===================================== ==============================================
check              needs                                 what it proves
================== ===================================== ==============================================
pole_placement     requested ``poles``, ``closed_loop``  closed-loop poles/zeros are the requested ones
routh_hurwitz      a closed-form ``characteristic``      Routh array + the notes' gain conditions
lyapunov           ``closed_loop``                       quadratic Lyapunov function (LMI, NumPy re-check)
loops              per-joint ``loops``                   the three above for each joint loop
robust_box         ``characteristic.linear_conditions``  stability on the whole (Km, tau) box (LP + duality)
                   and an uncertainty on its parameters
robustness         ``plant.uncertainty``                 corners, lattice, samples; common Lyapunov P
workspace          per-joint ``loops`` and a workspace   every joint loop stable for every configuration of
                   box (``extra["workspace"]``)          the box (D_ii range; affine conditions at its ends)
error_poles        a trajectory design with poles        error poles along the path (joint or task space)
singularity        a task-space design (``motion``)      conditioning of J along the path; DLS bound
tracking_bounds    a trajectory design + uncertainty     tracking error over the box by simulation
loop_margins       ``input_loop``                        gain/phase/modulus margins (informational)
coupling           per-joint ``loops``                   intercoupling left to the loops (informational)
time_domain        a simulation and ``requirements``     overshoot, settling, rise, error, peak control
torque_limits      a simulation and ``plant.limits``     commanded torques within the actuator limits
================== ===================================== ==============================================
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from designkit.verification.check import Check

__all__ = ["CHECKS", "CheckRule", "applicable", "run_checks"]


@dataclass(frozen=True)
class Context:
    """What a check may read besides the design: the spec, the simulation and the true plant."""

    spec: Any
    simulation: Any
    solver: str
    plant: Any = None


@dataclass(frozen=True)
class CheckRule:
    """One entry of :data:`CHECKS`: when it applies and how to run it."""

    applies: Callable[[Any, Context], bool]
    run: Callable[[Any, Context], tuple[Check, ...]]


def _uncertainty(ctx: Context) -> Any:
    return getattr(ctx.spec.plant, "uncertainty", None)


def _pole_placement(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.pole_zero import pole_placement

    return (pole_placement(design),)


def _routh(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.hurwitz_conditions import routh_hurwitz_design

    return (routh_hurwitz_design(design),)


def _lyapunov(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.lyapunov import lyapunov_lmi

    return (lyapunov_lmi(design.closed_loop.A, solver=ctx.solver),)


def _loops(design: Any, ctx: Context) -> tuple[Check, ...]:
    out: list[Check] = []
    for name, loop in zip(design.loop_names, design.loops, strict=True):
        for key in ("pole_placement", "routh_hurwitz", "lyapunov"):
            rule = CHECKS[key]
            if rule.applies(loop, ctx):
                out.extend(dataclasses.replace(c, name=f"{c.name}[{name}]",
                                               detail=f"{name} on its simplified link model: {c.detail}")
                           for c in rule.run(loop, ctx))
    return tuple(out)


def _box_applies(design: Any, ctx: Context) -> bool:
    unc = _uncertainty(ctx)
    ch = design.characteristic
    return (unc is not None and ch is not None and ch.linear_conditions is not None
            and set(unc.intervals) <= set(ch.parameters))


def _robust_box(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.lp import Polytope, robust_linear_conditions

    intervals = _uncertainty(ctx).intervals
    names = tuple(design.characteristic.parameters)
    lo = [intervals.get(n, (design.plant.parameter(n).value,) * 2)[0] for n in names]
    hi = [intervals.get(n, (design.plant.parameter(n).value,) * 2)[1] for n in names]
    conditions = design.characteristic.linear_conditions(design.gains)
    check = robust_linear_conditions("robust_box", conditions, Polytope.box(names, lo, hi), solver=ctx.solver)
    what = ("the closed-loop Hurwitz conditions, affine in " + ", ".join(names) + " for fixed gains, hold on the "
            "whole box (every plant in it, not a sample)")
    return (dataclasses.replace(check, detail=f"{what}: {check.detail}"),)


def _robustness(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.robustness import robustness_checks

    return robustness_checks(design, _uncertainty(ctx), solver=ctx.solver, plant=ctx.plant)


def _workspace(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.workspace import workspace_check

    return (workspace_check(design),)


def _error_poles(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.tracking import error_poles_check

    return (error_poles_check(ctx.spec, design, ctx.plant),)


def _singularity(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.simulation.motion import motion_of
    from designkit.verification.singularity import singularity_check

    return (singularity_check(design, motion_of(ctx.spec, design)),)


def _task_space(design: Any, ctx: Context) -> bool:
    from designkit.families import family

    return family(design.kind).motion is not None


def _tracking_bounds(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.tracking import tracking_bounds_check

    return (tracking_bounds_check(ctx.spec, design, ctx.plant if ctx.plant is not None else design.plant),)


def _torque_limits(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.tracking import torque_limits_check

    return (torque_limits_check(ctx.spec, ctx.simulation),)


def _limits(ctx: Context) -> Any:
    limits = getattr(ctx.spec.plant, "limits", None)
    return None if limits is None else limits.torque


def _loop_margins(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.loop import loop_margins_check

    return (loop_margins_check(design),)


def _coupling(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.coupling import coupling_check

    return (coupling_check(design, ctx.simulation),)


def _time_domain(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.verification.time_domain import time_domain_checks

    return time_domain_checks(ctx.spec.requirements, ctx.simulation)


CHECKS: dict[str, CheckRule] = {
    "pole_placement": CheckRule(lambda d, c: bool(d.poles) and d.closed_loop is not None, _pole_placement),
    "routh_hurwitz": CheckRule(lambda d, c: d.characteristic is not None, _routh),
    "lyapunov": CheckRule(lambda d, c: d.closed_loop is not None, _lyapunov),
    "loops": CheckRule(lambda d, c: bool(d.loops), _loops),
    "robust_box": CheckRule(_box_applies, _robust_box),
    "robustness": CheckRule(lambda d, c: _uncertainty(c) is not None and d.operating_point != {}, _robustness),
    "workspace": CheckRule(lambda d, c: bool(d.loops) and d.extra.get("workspace") is not None, _workspace),
    "error_poles": CheckRule(lambda d, c: d.reference == "trajectory" and bool(d.poles), _error_poles),
    "singularity": CheckRule(_task_space, _singularity),
    "tracking_bounds": CheckRule(lambda d, c: _uncertainty(c) is not None and d.reference == "trajectory",
                                 _tracking_bounds),
    "loop_margins": CheckRule(lambda d, c: d.input_loop is not None, _loop_margins),
    "coupling": CheckRule(lambda d, c: bool(d.loops), _coupling),
    "time_domain": CheckRule(lambda d, c: c.simulation is not None and c.spec.requirements is not None,
                             _time_domain),
    "torque_limits": CheckRule(lambda d, c: c.simulation is not None and _limits(c) is not None, _torque_limits),
}
"""Check name -> :class:`CheckRule`, in report order (a table, not if/elif)."""


def applicable(design: Any, spec: Any, simulation: Any = None, plant: Any = None) -> tuple[str, ...]:
    """Names of the checks that run for ``design`` (offered by its family and exposed by the design)."""
    from designkit.families import family

    offered = set(family(design.kind).checks)
    ctx = Context(spec, simulation, spec.numerics.solver, plant)
    return tuple(name for name, rule in CHECKS.items() if name in offered and rule.applies(design, ctx))


def run_checks(spec: Any, design: Any, simulation: Any = None, plant: Any = None) -> tuple[Check, ...]:
    """Run every applicable check (see the module docstring).

    Parameters
    ----------
    spec : Spec
        Validated spec (``plant.uncertainty``, ``requirements`` and ``numerics.solver`` are read).
    design : Design
        The synthesised controller.
    simulation : SimulationResult or None
        Closed-loop run for the time-domain and coupling checks.
    plant : Plant, optional
        The true plant (default: the design's); differs when the controller's model does.

    Returns
    -------
    tuple of Check
    """
    ctx = Context(spec, simulation, spec.numerics.solver, plant)
    checks: list[Check] = []
    for name in applicable(design, spec, simulation, plant):
        checks.extend(CHECKS[name].run(design, ctx))
    return tuple(checks)
