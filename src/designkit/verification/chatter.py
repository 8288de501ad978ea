"""Chattering of a commanded input: detected from the run, measured, and traced to what switches.

A command chatters when it jumps back and forth: the law, or an element of the loop, switches
faster than the loop can follow.  For each input ``u_j`` of a run (``SimulationResult.u_command``,
sampled every ``dt``):

* a **jump** is a step-to-step change ``|du_k|`` above :data:`JUMP` of the command's range
  (peak-to-peak) that no jump of the reference explains (a step or square-wave edge within one
  sample is the reference's, not chattering);
* the input **chatters** when it has at least :data:`MIN_JUMPS` jumps and at least 80 % of the
  consecutive ones reverse direction (up, down, up: switching, not a staircase).

The measurements are the jump count, their rate (1/s, from the first to the last), the median
swing ``|du|`` (N*m), the total variation ``TV = sum |du_k|`` and the share of it the jumps make.

Where it comes from (:func:`source`), in this order: a law that switches by design
(``Law.discontinuous``: the sign of a sliding function); a switching element of the loop (relay,
quantizer); the Coulomb friction compensation ``Fc sign(q')`` of the controller's model, when most
jumps happen where the joint's speed is near zero (``|q'_j|`` below 5 % of its peak, or 1e-9); otherwise
the chattering is **not explained** by any nonlinear element and is said so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["JUMP", "MIN_JUMPS", "InputChatter", "input_chatter", "source"]

JUMP = 0.1
"""A step-to-step change above this share of the command's range is a jump."""

MIN_JUMPS = 10
"""Fewer jumps than this are not chattering (a few switches of a relay, a limit cycle's edges)."""

SLOW = 0.05
"""Share of a joint's peak speed below which its speed counts as near zero."""


@dataclass(frozen=True)
class InputChatter:
    """The chattering measurements of one input.

    Parameters
    ----------
    name : str
        The input.
    chatters : bool
        The module docstring's criterion holds.
    jumps : int
        Jumps in the run (those of the reference excluded).
    rate : float
        Jumps per second from the first to the last (1/s).
    swing : float
        Median ``|du|`` of a jump (the input's unit).
    variation : float
        ``TV`` (the input's unit).
    jump_share : float
        Share of ``TV`` the jumps make.
    span : (float, float)
        First and last jump (s).
    slow_share : float
        Share of the jumps where the matching joint's speed is near zero (nan without one).
    """

    name: str
    chatters: bool
    jumps: int
    rate: float
    swing: float
    variation: float
    jump_share: float
    span: tuple[float, float]
    slow_share: float


def _reference_jumps(reference: np.ndarray | None, n: int) -> np.ndarray:
    """Per step ``k`` (``n - 1`` of them): the reference jumps at ``k`` or a sample either side."""
    out = np.zeros(max(n - 1, 0), dtype=bool)
    if reference is None or n < 2:
        return out
    r = np.asarray(reference, dtype=float).reshape(n, -1)
    dr = np.abs(np.diff(r, axis=0))
    ptp = np.ptp(r, axis=0)
    hit = np.any(dr > JUMP * np.where(ptp > 0, ptp, np.inf), axis=1)
    out |= hit
    out[1:] |= hit[:-1]
    out[:-1] |= hit[1:]
    return out


def input_chatter(name: str, t: np.ndarray, u: np.ndarray, speed: np.ndarray | None = None,
                  reference: np.ndarray | None = None) -> InputChatter:
    """Measure one input's command ``u`` (sampled at ``t``, s) for chattering (module docstring); a run that stops
    being finite is measured up to that instant (its divergence is ``finite_run``'s to report)."""
    u = np.asarray(u, dtype=float)
    bad = np.flatnonzero(~np.isfinite(u))
    if bad.size:
        n = int(bad[0])
        u, t = u[:n], np.asarray(t)[:n]
        speed = None if speed is None else np.asarray(speed, dtype=float)[:n]
        reference = None if reference is None else np.asarray(reference, dtype=float)[:n]
    du = np.diff(u)
    ptp = float(np.ptp(u)) if u.size else 0.0
    idx = np.flatnonzero((np.abs(du) > JUMP * ptp) & ~_reference_jumps(reference, u.size)) if ptp > 0 else \
        np.array([], dtype=int)
    signs = np.sign(du[idx])
    reversing = float(np.mean(signs[1:] != signs[:-1])) if idx.size > 1 else 0.0
    chatters = bool(idx.size >= MIN_JUMPS and reversing >= 0.8)
    tv = float(np.sum(np.abs(du)))
    share = float(np.sum(np.abs(du[idx])) / tv) if tv > 0 else 0.0
    span = (float(t[idx[0] + 1]), float(t[idx[-1] + 1])) if idx.size else (float("nan"), float("nan"))
    width = span[1] - span[0]
    rate = idx.size / width if idx.size > 1 and width > 0 else 0.0
    swing = float(np.median(np.abs(du[idx]))) if idx.size else 0.0
    slow = float("nan")
    if speed is not None and idx.size:
        v = np.abs(np.asarray(speed, dtype=float))
        top = float(np.max(v)) if v.size else 0.0
        slow = float(np.mean(v[idx] <= max(SLOW * top, 1e-9)))  # a joint that never moves is near zero throughout
    return InputChatter(name, chatters, int(idx.size), rate, swing, tv, share, span, slow)


def source(measured: InputChatter, law: Any, nonlinearity: Any, model_coulomb: float) -> str:
    """Where the chattering of one input comes from, in words (module docstring's order)."""
    if law is not None and getattr(law, "discontinuous", False):  # the check is not offered for one; the API may ask
        return "the control law switches by design (the sign of its sliding function)"
    kind = getattr(nonlinearity, "kind", None)
    if kind in ("relay", "quantizer"):
        return f"the {kind} element of the loop"
    if model_coulomb > 0 and measured.slow_share == measured.slow_share and measured.slow_share >= 0.5:
        return (f"the Coulomb friction compensation Fc sign(q̇) of the controller's model (Fc = {model_coulomb:.3g}): "
                f"{100 * measured.slow_share:.0f} % of the jumps happen where the joint's speed is near zero")
    return "not explained by any nonlinear element of the loop"
