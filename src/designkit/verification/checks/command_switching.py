"""Check ``command_switching`` (every simulated loop, every law): how each commanded input switches, as physics.

See :mod:`designkit.verification.switching` for the measurements.  Without a requirement the check is
informational (PASS): its certificate holds each input's switching amplitude against its averaged control, its
reversal rate against the integration step and the sampling rate, and its total variation; ``warnings`` (page 1
and ``--json``) say when the switching part dominates or the step (or the sampling) sets the rate (an input of a
law that is not a switching law whose chattering ``command_chatter`` already warns of, with its source, is not
warned of twice).  With
``requirements.max_reversal_rate`` (1/s) or ``requirements.max_command_variation`` (the input's unit per second)
it returns the checks ``max_reversal_rate`` and ``max_command_variation``, part of the verdict: the largest value
over the inputs within the bound.
"""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _unit(design: Any, j: int) -> str:
    from designkit.verification.switching import input_unit

    return input_unit(design, j)


def _bound(name: str, limit: float, measured: list, value: Any, unit: str, what: str) -> Any:
    from designkit.verification.check import Check

    worst = max(measured, key=value)
    achieved = float(value(worst))
    return Check(name, achieved <= limit, f"<= {limit:.6g} {unit}", achieved, float(limit - achieved), unit,
                 f"largest {what}: {achieved:.4g} {unit} ({worst.name}) against {limit:.6g} {unit}",
                 {"inputs": [m.to_dict() for m in measured]})


def _told_by_chatter(design: Any, ctx: Context) -> set[int]:
    """The inputs whose chattering the ``command_chatter`` check already warns of, with its source: that check runs
    on a law that is not a switching law, and one warning per input is enough."""
    law = ctx.law if ctx.law is not None else getattr(design, "law", None)
    if law is None or getattr(law, "discontinuous", False):
        return set()
    from designkit.verification.chatter import input_chatter

    sim = ctx.simulation
    told = set()
    for j, name in enumerate(sim.input_names):
        speed = sim.state[:, sim.velocities[j]] if j < len(sim.velocities) else None
        if input_chatter(name, sim.time, sim.u_command[:, j], speed, sim.reference).chatters:
            told.add(j)
    return told


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.check import Check
    from designkit.verification.switching import of_run, warning

    sim = ctx.simulation
    measured = [of_run(design, sim, ctx.spec, j) for j in range(len(sim.input_names))]
    told = _told_by_chatter(design, ctx)
    warnings = tuple(w for j, m in enumerate(measured)
                     if j not in told and (w := warning(m, _unit(design, j))) is not None)
    worst = max(measured, key=lambda m: m.rate)
    cert = {"inputs": [m.to_dict() for m in measured],
            "criterion": "switching part dominates: RMS of u - u_avg above the RMS of u_avg (u_avg the moving "
                         "average over the loop's time scale); rate set by the step: reversals per second above "
                         "0.1/dt"}
    summary = (f"fastest reversal rate {worst.rate:.3g}/s ({worst.name}; step {worst.step:.3g} s), switching RMS "
               f"{worst.switching_rms:.3g} on an averaged control of RMS {worst.averaged_rms:.3g}")
    out = [Check("command_switching", True, "how the commands switch", float(worst.rate), None, "1/s", summary,
                 cert, required=False, warnings=warnings)]
    req = getattr(ctx.spec, "requirements", None)
    if req is not None and getattr(req, "max_reversal_rate", None) is not None:
        out.append(_bound("max_reversal_rate", float(req.max_reversal_rate), measured, lambda m: m.rate, "1/s",
                          "reversal rate of a commanded input"))
    if req is not None and getattr(req, "max_command_variation", None) is not None:
        out.append(_bound("max_command_variation", float(req.max_command_variation), measured,
                          lambda m: m.variation_rate, f"{_unit(design, 0) or 'unit'}/s",
                          "total variation per second of a commanded input"))
    return tuple(out)


def _applies(design: Any, ctx: Context) -> bool:
    """A simulated loop with a recorded command computed by a law (a design without one plays a learned input
    sequence, held over each of its samples: there is no switching to characterise)."""
    sim = ctx.simulation
    law = ctx.law if ctx.law is not None else design.law
    return law is not None and sim is not None and getattr(sim, "u_command", None) is not None and len(sim.time) > 1


RULE = CheckRule(name="command_switching", order=146, universal=True, applies=_applies, run=_run,
                 label="How the commanded inputs switch",
                 labels={"max_reversal_rate": "Reversal rate of the commands",
                         "max_command_variation": "Total variation of the commands per second"},
                 glossary=(("reversal", "the command turning back by more than half the RMS of its switching "
                                        "component"),
                           ("averaged control", "the command's moving average over the loop's time scale"),
                           ("switching component", "the command minus its averaged control")),
                 reads=("requirements.max_reversal_rate", "requirements.max_command_variation"))
"""Offered for every family (``universal``): any law's command can switch."""
