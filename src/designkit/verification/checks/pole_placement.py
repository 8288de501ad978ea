"""Check ``pole_placement``: the closed-loop poles and zeros are the requested ones."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.pole_zero import pole_placement

    return (pole_placement(design),)


RULE = CheckRule(
    name="pole_placement", order=10, linear=True,
    applies=lambda d, c: bool(d.poles) and d.closed_loop is not None,
    run=_run, label="Closed-loop poles and zeros as requested",
)
