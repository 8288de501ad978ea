"""Check ``torque_limits``: the commanded torques of the run within ``plant.limits.torque``."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _limits(ctx: Context) -> Any:
    limits = getattr(ctx.spec.plant, "limits", None)
    return None if limits is None else limits.torque


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.tracking import torque_limits_check

    return (torque_limits_check(ctx.spec, ctx.simulation),)


RULE = CheckRule(name="torque_limits", order=140,
                 applies=lambda d, c: c.simulation is not None and _limits(c) is not None, run=_run,
                 label="Joint torques within limits")
