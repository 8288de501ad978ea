"""Check ``error_poles``: the linearized error dynamics along the reference are the decoupled requested ones."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.tracking import error_poles_check

    return (error_poles_check(ctx.spec, design, ctx.plant),)


RULE = CheckRule(name="error_poles", order=80, linear=True,
                 applies=lambda d, c: d.reference == "trajectory" and bool(d.poles), run=_run,
                 label="Error dynamics poles as requested")
