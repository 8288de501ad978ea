"""Check ``designed_loop``: the simulated loop starts at rest on the designed loop and follows its linearization in
the small (:mod:`designkit.verification.designed_loop`)."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.designed_loop import designed_loop_check

    return (designed_loop_check(ctx.spec, design),)


RULE = CheckRule(
    name="designed_loop", order=125, linear=True,
    applies=lambda d, c: c.simulation is not None and d.closed_loop is not None and d.law is not None,
    run=_run, label="The simulated loop is the designed loop",
)
