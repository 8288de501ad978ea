"""Check ``time_domain``: the requirements (overshoot, settling, rise, steady-state and tracking error, peak control)
measured on the simulated run."""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.time_domain import time_domain_checks

    return time_domain_checks(ctx.spec.requirements, ctx.simulation)


RULE = CheckRule(
    name="time_domain", order=130,
    applies=lambda d, c: c.simulation is not None and c.spec.requirements is not None, run=_run,
    label="Time-domain requirements",
    reads=tuple(f"requirements.{k}" for k in ("overshoot", "settling_time", "rise_time", "steady_state_error",
                                              "tracking_error", "max_control", "settling_band")),
    labels={"overshoot": "Overshoot", "settling_time": "Settling time (2 % band)", "rise_time": "Rise time",
            "steady_state_error": "Steady-state error", "max_control": "Peak control effort |u|",
            "tracking_error": "Tracking error"},
)
