"""Check ``coupling`` (informational): what the intercoupling of the joints leaves to the per-joint loops."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.coupling import coupling_check

    return (coupling_check(design, ctx.simulation),)


def _figure(result: Any, check: Any) -> Any:
    from designkit.verification.figures.coupling import coupling_figure

    return coupling_figure(result, check)


RULE = CheckRule(name="coupling", order=120, linear=True, applies=lambda d, c: bool(d.loops), run=_run,
                 label="Decoupling of the joints", figures=(_figure,))
