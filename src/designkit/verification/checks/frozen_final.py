"""Check ``frozen_final``: an adaptive design's loop with its adaptation frozen at the values the run ends with.

The design's own linear checks (pole placement, Lyapunov, robustness) judge the loop frozen at the
*initial* adapted values (:mod:`designkit.synthesis.linearization`); this check judges the loop the run
*ends* with: the law ``linearization.freeze(final)``, ``final`` read from the last sample of the
controller states named by ``linearization.parameters``, linearized on the plant the run ends with (the true
plant, after ``simulation.plant_change`` when there is one) at the design's operating point, certified by a
Lyapunov LMI (re-checked in NumPy), with its poles in the certificate.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context


def final_values(design: Any, simulation: Any) -> np.ndarray:
    """The adapted parameters at the end of the run (the last finite sample of their controller states)."""
    names = list(simulation.controller_state_names)
    idx = [names.index(p) for p in design.linearization.parameters]
    xc = np.asarray(simulation.controller_state, dtype=float)[:, idx]
    finite = np.all(np.isfinite(xc), axis=1)
    return xc[np.flatnonzero(finite)[-1]] if finite.any() else np.full(len(idx), np.nan)


def _run(design: Any, ctx: Context) -> tuple[Check, ...]:
    from designkit.synthesis.closed_loop import linearize
    from designkit.verification.lyapunov import lyapunov_lmi

    lin = design.linearization
    final = final_values(design, ctx.simulation)
    words = lin.describe(final)
    if not np.all(np.isfinite(final)):
        return (Check("frozen_final", False, "the loop frozen at the final adapted values is stable", None, None, "",
                      "the adapted parameters did not stay finite along the run", {"final": final.tolist()}),)
    op = design.operating_point
    plant = ctx.true_plant(design)
    change = getattr(ctx.spec.simulation, "plant_change", None)
    if change is not None:  # the run ends on the changed plant
        plant = plant.with_params(**change.values)
    try:
        closed, _, _ = linearize(plant, lin.freeze(final), op["r"], z0=[*op["x"], *op["xc"]])
    except ValueError as exc:
        return (Check("frozen_final", None, "the loop frozen at the final adapted values is stable", None, None, "",
                      f"{words}: {exc}", {"final": final.tolist()}),)
    check = lyapunov_lmi(closed.A, solver=ctx.solver)
    poles = np.linalg.eigvals(closed.A)
    cert = {**dict(check.certificate), "final": final.tolist(), "parameters": list(lin.parameters),
            "poles": [[float(p.real), float(p.imag)] for p in poles]}
    return (dataclasses.replace(check, name="frozen_final", detail=f"{words} (the run's last values): {check.detail}",
                                certificate=cert),)


RULE = CheckRule(
    name="frozen_final", order=35, linear=True,
    applies=lambda d, c: d.linearization.kind == "frozen" and c.simulation is not None and d.operating_point != {},
    run=_run, label="Stability with the adaptation frozen at its final values",
)
