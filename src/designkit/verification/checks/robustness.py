"""Check ``robustness``: the loop at the corners, on the lattice and at samples of the uncertainty box; a common
Lyapunov function of the corners (informational)."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.robustness import robustness_checks

    return robustness_checks(design, ctx.uncertainty(), solver=ctx.solver, plant=ctx.plant)


def _lattice(result: Any, check: Any) -> Any:
    from designkit.verification.figures.robustness import robustness_figure

    return robustness_figure(result, check)


def _migration(result: Any, check: Any) -> Any:
    from designkit.verification.figures.robustness import pole_migration_figure

    return pole_migration_figure(result, check)


RULE = CheckRule(
    name="robustness", order=60, linear=True,
    applies=lambda d, c: c.uncertainty() is not None and d.operating_point != {},
    run=_run, label="Robust stability over the parameter box",
    labels={"robust_vertices": "Stability at the corners of the parameter box",
            "robust_grid": "Stability on the parameter lattice",
            "common_lyapunov": "Common Lyapunov function over the parameter box"},
    figures=(_lattice, _migration),
)
