"""Check ``loop_margins``: gain, phase and modulus margins of the loop broken at each plant input."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.loop import loop_margins_check

    return (loop_margins_check(design, ctx.spec),)


def _bode(result: Any, check: Any) -> Any:
    from designkit.verification.figures.loop_margins import bode_figure

    return bode_figure(result, check)


def _sensitivity(result: Any, check: Any) -> Any:
    from designkit.verification.figures.loop_margins import sensitivity_figure

    return sensitivity_figure(result, check)


RULE = CheckRule(name="loop_margins", order=110, linear=True, applies=lambda d, c: d.input_loop is not None,
                 run=_run, label="Stability margins at the plant input", figures=(_bode, _sensitivity),
                 reads=("requirements.gain_margin", "requirements.phase_margin", "requirements.modulus_margin"))
