"""Check ``finite_run`` (every simulated loop that diverged): the run stays finite.

Offered only for a run that diverged, so a finite run's list of checks is that of its family.  FAIL when a
plant state, a controller state or a command stops being finite (or leaves
:data:`~designkit.simulation.integrate.DIVERGED` in magnitude), or the integrator stopped: the loop
diverged, and the detail names the instant.  Every other check of a diverged run reads records that are
not finite from that instant on; this one says so first.
"""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context

TARGET = "every state and command finite over the whole run"


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.check import Check

    sim = ctx.simulation
    at = sim.diverged_at
    failure = sim.settings.get("integrator_failure")
    end = float(sim.time[-1])
    cert = {"diverged_at_s": at, "integrator_failure": failure, "duration_s": end}
    where = f"t = {at:.6g} s" if at is not None else "the integrator's failure"
    detail = f"the run diverged at {where}: the records are not finite from there on"
    if failure:
        detail += f" ({failure})"
    return (Check("finite_run", False, TARGET, at, None, "s", detail, cert),)


def _diagnose(result: Any, check: Any) -> tuple[str, str]:
    """The divergence as the root cause; the fix is what the run's other failed checks propose."""
    others = [c.name for c in getattr(result, "checks", ()) if c.passed is False and c.name != "finite_run"]
    cause = (f"The closed loop diverged: {check.detail}. Every measurement after that instant is of records that "
             "are not finite.")
    fix = ("Keep the loop bounded: the other failed checks of this run"
           + (f" ({', '.join(others)})" if others else "") + " say which part of the design or scenario drives "
           "the divergence and what would do instead.")
    return cause, fix


def _applies(design: Any, ctx: Context) -> bool:
    """A simulated run that diverged (a record not finite, or the integrator stopped)."""
    sim = ctx.simulation
    if sim is None or getattr(sim, "state", None) is None:
        return False
    return sim.diverged_at is not None or "integrator_failure" in sim.settings


RULE = CheckRule(name="finite_run", order=5, universal=True, applies=_applies, run=_run,
                 label="The run stays finite", diagnose=_diagnose,
                 glossary=(("diverged", "a state or command not finite, or beyond 1e150 in magnitude"),))
"""Offered for every family (``universal``): a property of any simulated loop."""
