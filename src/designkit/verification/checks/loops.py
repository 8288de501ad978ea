"""Check ``loops``: pole placement, Routh--Hurwitz and Lyapunov on each per-joint loop of a decentralized design."""

from __future__ import annotations

import dataclasses
from typing import Any

from designkit.verification.suite import CheckRule, Context, generic

PER_LOOP = ("pole_placement", "routh_hurwitz", "lyapunov")
"""The checks run on each loop, named ``<check>[<loop>]``."""


def _run(design: Any, ctx: Context) -> tuple:
    out = []
    for name, loop in zip(design.loop_names, design.loops, strict=True):
        for key in PER_LOOP:
            rule = generic()[key]
            if rule.offered_for(loop, ctx):
                out.extend(dataclasses.replace(c, name=f"{c.name}[{name}]",
                                               detail=f"{name} on its simplified link model: {c.detail}",
                                               label=rule.label_for(f"{c.name}[{name}]"))
                           for c in rule.run(loop, ctx))
    return tuple(out)


RULE = CheckRule(name="loops", order=40, applies=lambda d, c: bool(d.loops), run=_run,
                 label="The per-joint loops")
