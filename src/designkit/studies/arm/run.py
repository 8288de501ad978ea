"""What every lab answer reads from the run: the commanded moves and their scales, the path samples, a check
by name and the family's label."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "MAX_PATH_SAMPLES",
    "NEGLIGIBLE_ERROR",
    "PathSamples",
    "check_named",
    "commanded_moves",
    "error_floors",
    "family_label",
    "motion_scales",
    "path_samples",
    "relative_to_moves",
]

NEGLIGIBLE_ERROR = 1e-6
"""An error below this fraction of the coordinate's move is at integrator precision."""
MAX_PATH_SAMPLES = 20000
"""At most this many instants of the path are evaluated (every k-th sample beyond)."""

def commanded_moves(sim: Any) -> np.ndarray:
    xd = np.asarray(sim.desired, dtype=float)
    if sim.kind == "step":
        return np.abs(xd[-1] - np.asarray(sim.tracked_positions, dtype=float)[0])
    return np.max(np.abs(xd - xd[0]), axis=0)


def motion_scales(moves: np.ndarray, units: Sequence[str]) -> np.ndarray:
    """The size of each coordinate's motion (its unit): its move, or for a coordinate that does not move itself
    the largest move in the same unit (1 when none moves)."""
    out = np.empty(len(moves))
    for c, m in enumerate(moves):
        same = [moves[k] for k in range(len(moves)) if units[k] == units[c] and np.isfinite(moves[k])]
        scale = m if np.isfinite(m) and m > 0 else max(same, default=0.0)
        out[c] = scale if scale > 0 else 1.0
    return out


def error_floors(moves: np.ndarray, units: Sequence[str]) -> np.ndarray:
    """Errors below these (per coordinate) are at the integrator's precision: :data:`NEGLIGIBLE_ERROR` of
    :func:`motion_scales`."""
    return NEGLIGIBLE_ERROR * motion_scales(moves, units)


def relative_to_moves(peaks: np.ndarray, moves: np.ndarray, units: Sequence[str]) -> np.ndarray:
    return peaks / motion_scales(moves, units)


@dataclass(frozen=True)
class PathSamples:
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    stride: int


def path_samples(sim: Any) -> PathSamples | None:
    t = np.asarray(sim.time, dtype=float)
    q = np.asarray(sim.state, dtype=float)[:, list(sim.positions)]
    qd = np.asarray(sim.state, dtype=float)[:, list(sim.velocities)]
    ok = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(qd), axis=1)
    end = int(np.argmin(ok)) if not np.all(ok) else t.size
    if end < 3:
        return None
    t, q, qd = t[:end], q[:end], qd[:end]
    qdd = np.gradient(qd, t, axis=0)
    stride = max(1, math.ceil(t.size / MAX_PATH_SAMPLES))
    return PathSamples(t[::stride], q[::stride], qd[::stride], qdd[::stride], stride)


def check_named(result: Any, name: str) -> Any:
    return next((c for c in result.checks if c.name == name), None)


def family_label(result: Any) -> str:
    """The label of the result's controller family (``"Computed torque"``)."""
    from designkit.families import family

    return family(result.design.kind).display.label
