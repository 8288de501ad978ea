"""Which figures a report has, and :func:`design_figures` that draws them all.

In report order: the design's own figures (:data:`DESIGN_FIGURES`: pole-zero map, ideal linear response,
nonlinear simulation per joint), then the figures the design's family contributes
(:attr:`designkit.synthesis.family.Family.figures`), then, for each check of the run, the figures its rule
declares (:attr:`designkit.verification.suite.CheckRule.figures`).  No table here names a check or a family.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from designkit.display.figure import Figure
from designkit.report.figures.linear import linear_figure
from designkit.report.figures.nyquist import nyquist_figure
from designkit.report.figures.pole_zero import pole_zero_figure
from designkit.report.figures.simulation import simulation_figure

__all__ = ["DESIGN_FIGURES", "design_figures"]


DESIGN_FIGURES: tuple[Callable[[Any], Figure | None], ...] = (pole_zero_figure, linear_figure, simulation_figure,
                                                               nyquist_figure)
"""Figures drawn from the design and the simulation, in report order."""


def design_figures(result: Any, *, processes: int = 1) -> tuple[Figure, ...]:
    """Every figure of a report, in report order (figures without data are left out).

    File names are unique (a later figure with a taken name is left out).  With ``processes=2`` the
    figures are drawn on two cores (:func:`designkit.report.parallel.run_tasks`; same figures).
    """
    from functools import partial

    from designkit.families import check_rules, family
    from designkit.report.parallel import run_tasks
    from designkit.verification.suite import owner

    kind = result.design.kind
    tasks: list[Callable[[], Figure | None]] = [partial(draw, result) for draw in DESIGN_FIGURES]
    tasks += [partial(draw, result) for draw in family(kind).figures]
    rules = check_rules(kind)
    for check in result.checks:
        rule = owner(rules, check.name)
        tasks.extend(partial(draw, result, check) for draw in (rule.figures if rule is not None else ()))
    out = [f for f in run_tasks(tasks, processes=processes) if f is not None]
    seen: set[str] = set()
    return tuple(f for f in out if not (f.filename in seen or seen.add(f.filename)))
