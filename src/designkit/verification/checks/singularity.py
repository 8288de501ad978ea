"""Check ``singularity``: the conditioning of the task Jacobian along the path of a task-space design."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.singularity import singularity_check

    return (singularity_check(design, design.motion),)


def _figure(result: Any, check: Any) -> Any:
    from designkit.verification.figures.singularity import singularity_figure

    return singularity_figure(result, check)


def _diagnose(result: Any, check: Any) -> Any:
    from designkit.verification.diagnoses.singularity import explain

    return explain(result, check)


RULE = CheckRule(name="singularity", order=90, applies=lambda d, c: d.motion is not None, run=_run,
                 label="Distance from singular configurations", figures=(_figure,), diagnose=_diagnose)
