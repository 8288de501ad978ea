"""Check ``tracking_bounds``: the tracking error over the uncertainty box, by simulation at its corners and samples."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.tracking import tracking_bounds_check

    return (tracking_bounds_check(ctx.spec, design, ctx.true_plant(design), law=ctx.law),)


def _figure(result: Any, check: Any) -> Any:
    from designkit.verification.figures.tracking_bounds import tracking_bounds_figure

    return tracking_bounds_figure(result, check)


RULE = CheckRule(name="tracking_bounds", order=100, figures=(_figure,),
                 applies=lambda d, c: c.uncertainty() is not None and d.reference == "trajectory", run=_run,
                 label="Tracking error within bounds", reads=("requirements.tracking_error",))
