"""Check ``routh_hurwitz``: the Routh array of the closed-form characteristic and the notes' gain conditions."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.hurwitz_conditions import routh_hurwitz_design

    return (routh_hurwitz_design(design),)


RULE = CheckRule(
    name="routh_hurwitz", order=20, linear=True,
    applies=lambda d, c: d.characteristic is not None,
    run=_run, label="Stability of the nominal loop (Routh–Hurwitz)",
)
