"""Check ``lyapunov``: a quadratic Lyapunov function of the closed loop (LMI, re-checked in NumPy)."""

from __future__ import annotations

import dataclasses
from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.lyapunov import lyapunov_lmi

    check = lyapunov_lmi(design.closed_loop.A, solver=ctx.solver)
    frozen = design.linearization.describe() if design.linearization.kind == "frozen" else ""
    if frozen:
        check = dataclasses.replace(check, detail=f"{frozen}: {check.detail}")
    return (check,)


RULE = CheckRule(
    name="lyapunov", order=30, linear=True,
    applies=lambda d, c: d.closed_loop is not None,
    run=_run, label="Lyapunov stability certificate",
)
