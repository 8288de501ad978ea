"""Check ``robust_box``: the closed-loop Hurwitz conditions, affine in the plant parameters, on the whole box (LP)."""

from __future__ import annotations

import dataclasses
from typing import Any

from designkit.verification.suite import CheckRule, Context


def _applies(design: Any, ctx: Context) -> bool:
    unc = ctx.uncertainty()
    ch = design.characteristic
    return (unc is not None and ch is not None and ch.linear_conditions is not None
            and set(unc.intervals) <= set(ch.parameters))


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.lp import Polytope
    from designkit.verification.robust_linear import robust_linear_conditions

    intervals = ctx.uncertainty().intervals
    names = tuple(design.characteristic.parameters)
    lo = [intervals.get(n, (design.plant.parameter(n).value,) * 2)[0] for n in names]
    hi = [intervals.get(n, (design.plant.parameter(n).value,) * 2)[1] for n in names]
    conditions = design.characteristic.linear_conditions(design.gains)
    check = robust_linear_conditions("robust_box", conditions, Polytope.box(names, lo, hi), solver=ctx.solver)
    what = ("the closed-loop Hurwitz conditions, affine in " + ", ".join(names) + " for fixed gains, hold on the "
            "whole box (every plant in it, not a sample)")
    return (dataclasses.replace(check, detail=f"{what}: {check.detail}"),)


RULE = CheckRule(name="robust_box", order=50, linear=True, applies=_applies, run=_run,
                 label="Robust stability over the whole parameter box")
