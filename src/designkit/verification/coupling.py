"""What a decentralized design leaves to its per-joint loops: the intercoupling (notes section 3.3).

Each joint loop of a decentralized design is designed, and places its poles exactly, on its own
simplified link model.  On the real arm the joints are coupled (off-diagonal inertia, Coriolis
and centrifugal forces, gravity not cancelled, ``D_ii`` changing with the configuration), which
the simplified model lumps into the perturbation ``xi_i``.  Two measurements of that coupling:

* the poles of the coupled arm's linearized closed loop at the design configuration against the
  per-joint requested poles (the pole shift the intercoupling causes at rest);
* with a simulation, each joint's position on the full nonlinear coupled arm against the
  response its own loop predicts on its simplified model for the same reference (the exact linear
  response of the loop's linear closed loop,
  :func:`designkit.simulation.linear.forced_response`): the **intercoupling error** ``q_i - q_i,decoupled`` (rad),
  largest over the run.

The ``coupling`` check is informational: coupling is what the notes warn a PID may not
neutralise, not a requirement; the time-domain checks judge whether the result is acceptable.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.numbers import fmt_complex
from designkit.simulation.linear import linear_response
from designkit.verification.check import Check

__all__ = ["coupling_check", "decoupled_responses"]


def decoupled_responses(design: Any, simulation: Any) -> np.ndarray:
    """Each joint's position ``(N, n)`` (rad) predicted by its own loop on its simplified model, driven by
    the simulation's reference of that joint (relative to the loop's rest position)."""
    t = np.asarray(simulation.time, dtype=float)
    ref = np.asarray(simulation.reference, dtype=float)
    q0 = np.asarray(simulation.joint_positions, dtype=float)[0]
    out = np.empty((t.size, len(design.loops)))
    for j, loop in enumerate(design.loops):
        r = ref[:, j, :].copy()
        start = q0[j]
        r[:, 0] -= start
        pos, _ = linear_response(loop, t, r[:, None, :])
        out[:, j] = pos[:, 0] + start
    return out


def _pairs(z: Any) -> list[list[float]]:
    return [[complex(v).real, complex(v).imag] for v in z]


def coupling_check(design: Any, simulation: Any = None) -> Check:
    """Check ``"coupling"`` (informational; see the module docstring)."""
    requested = np.array([p for loop in design.loops for p in loop.poles], dtype=complex)
    coupled = np.asarray(design.closed_loop.poles, dtype=complex) if design.closed_loop is not None else np.array([])
    cert: dict[str, Any] = {"requested_poles": _pairs(requested), "coupled_poles": _pairs(coupled)}
    parts = []
    if coupled.size == requested.size and coupled.size:
        from scipy.optimize import linear_sum_assignment

        cost = np.abs(coupled[:, None] - requested[None, :])
        ci, ri = linear_sum_assignment(cost)
        shift = cost[ci, ri]
        rel = shift / np.maximum(np.abs(requested[ri]), 1e-300)
        k = int(np.argmax(rel))
        cert["pole_matching"] = [{"requested": [requested[r].real, requested[r].imag],
                                  "coupled": [coupled[c].real, coupled[c].imag], "shift": float(shift[i])}
                                 for i, (c, r) in enumerate(zip(ci, ri, strict=True))]
        parts.append(f"coupling moves the requested poles by up to {100 * rel[k]:.3g} % "
                     f"({fmt_complex(requested[ri[k]])} -> {fmt_complex(coupled[ci[k]])} 1/s)")
    stable = bool(np.all(coupled.real < 0)) if coupled.size else None
    data: dict[str, Any] = {}
    achieved = None
    if simulation is not None:
        q = np.asarray(simulation.joint_positions, dtype=float)
        pred = decoupled_responses(design, simulation)
        err = q - pred
        peak = np.max(np.abs(err), axis=0)
        when = np.asarray(simulation.time)[np.argmax(np.abs(err), axis=0)]
        cert["intercoupling_error"] = [{"joint": j + 1, "max_abs_rad": float(peak[j]), "at_s": float(when[j])}
                                       for j in range(len(peak))]
        j = int(np.argmax(peak))
        achieved = float(peak[j])
        parts.append(f"largest intercoupling error {peak[j]:.3g} rad on joint {j + 1} at t = {when[j]:.3g} s "
                     "(nonlinear coupled arm minus the joint's own loop on its simplified model)")
        data = {"time": np.asarray(simulation.time, dtype=float), "coupled": q, "decoupled": pred,
                "reference": np.asarray(simulation.desired, dtype=float)}
    detail = "; ".join(parts) if parts else "no per-joint loops to compare"
    return Check(
        name="coupling", passed=stable, target="reported (the intercoupling the per-joint loops must reject)",
        achieved=achieved, margin=None, unit="rad" if achieved is not None else "",
        detail=detail + " [informational]", certificate=cert, required=False, data=data,
    )
