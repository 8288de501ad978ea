"""Check ``command_chatter`` (every simulated loop, informational): does a commanded input chatter, and why.

See :mod:`designkit.verification.chatter` for the criterion and the attribution.  PASS: no input
chatters.  FAIL (informational): an input chatters; the detail and ``warnings`` say which, how fast and
how much, and from what.  It is not offered for a switching law (``Law.discontinuous``), which chatters by
design: its family judges that switching as physics, and ``command_switching`` measures every law's command.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.verification.suite import CheckRule, Context


def _coulomb(design: Any, j: int) -> float:
    robot = getattr(design.plant, "robot", None)
    if robot is None or not getattr(robot, "friction", False):
        return 0.0
    from designkit.models.chain import numeric_value

    links = robot.description.links
    value = numeric_value(links[j].coulomb) if j < len(links) else None
    return float(value or 0.0)


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.verification.chatter import input_chatter, source
    from designkit.verification.check import Check

    sim = ctx.simulation
    law = ctx.law if ctx.law is not None else design.law
    nonlinearity = getattr(ctx.spec.simulation, "nonlinearity", None)
    rows, warnings, certificate = [], [], []
    for j, name in enumerate(sim.input_names):
        speed = sim.state[:, sim.velocities[j]] if j < len(sim.velocities) else None
        m = input_chatter(name, sim.time, sim.u_command[:, j], speed, sim.reference)
        row = {"input": name, "chatters": m.chatters, "jumps": m.jumps, "rate_per_s": m.rate,
               "swing": m.swing, "total_variation": m.variation, "jump_share": m.jump_share, "span_s": list(m.span)}
        if m.chatters:
            why = source(m, law, nonlinearity, _coulomb(design, j))
            row["source"] = why
            warnings.append(f"The commanded {name} chatters: it jumps back and forth {m.jumps} times ({m.rate:.3g} per "
                            f"second between {m.span[0]:.3g} s and {m.span[1]:.3g} s) by {m.swing:.3g} each, "
                            f"{100 * m.jump_share:.0f} % of its total variation ({m.variation:.3g}); source: {why}.")
            rows.append(m)
        certificate.append(row)
    from designkit.verification.certificate import to_json

    cert = {"inputs": to_json(certificate),
            "criterion": "at least 10 step-to-step jumps above 10 % of the command's range that no jump of the "
                         "reference explains, at least 80 % of consecutive ones reversing direction"}
    if rows:
        worst = max(rows, key=lambda m: m.rate)
        rate = worst.rate if np.isfinite(worst.rate) else None
        return (Check("command_chatter", False, "no commanded input chatters", rate, None, "jumps per second",
                      " ".join(warnings), cert, required=False, warnings=tuple(warnings)),)
    return (Check("command_chatter", True, "no commanded input chatters", 0.0, None, "jumps per second",
                  f"none of the {len(sim.input_names)} commanded inputs chatters", cert, required=False),)


def _applies(design: Any, ctx: Context) -> bool:
    """A simulated loop whose law is not a switching law (a switching family measures its own chattering band); a
    design without a law (a learned input sequence played to the plant) computes no command that could chatter."""
    law = ctx.law if ctx.law is not None else design.law
    return (law is not None and ctx.simulation is not None and getattr(ctx.simulation, "u_command", None) is not None
            and not getattr(law, "discontinuous", False))


RULE = CheckRule(name="command_chatter", order=145, universal=True, applies=_applies,
                 run=_run, label="Chattering of the commanded inputs",
                 glossary=(("jump", "a step-to-step change of the command above 10 % of its range"),
                           ("total variation", "the sum of the command's step-to-step changes")))
"""Offered for every family (``universal``): a property of any simulated loop."""
