"""Falsification: a local search of the box for the worst margin, started from the worst samples.

The objective is a sample's worst requirement margin over the requirement's limit (dimensionless;
negative breaks a requirement; an undefined metric, a diverged or unsettled run, counts as
:data:`UNDEFINED`, and so does anything worse: a diverging loop's error is not ranked by its size).
The search first evaluates the box's corners (when there are at most
:data:`MAX_CORNERS`; a monotone margin is worst at one), then runs a derivative-free bounded Powell
search (``scipy.optimize.minimize(method="Powell")``) from the best point found so far, within
:data:`BUDGET` evaluations.  The margins are not smooth in the parameters (a maximum over time, a last
crossing of a band), so no gradient is used; each evaluation is one run of the batched compiled loop.
The noise seed, when swept, is held at the start's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["BUDGET", "MAX_CORNERS", "UNDEFINED", "Falsification", "falsify"]

BUDGET = 120
"""Largest number of runs the Powell search may make."""
MAX_CORNERS = 64
"""The corners are evaluated when the box has at most this many (six dimensions)."""
UNDEFINED = -10.0
"""The objective of a run whose worst metric is undefined (below any met or near-met requirement)."""


@dataclass(frozen=True)
class Falsification:
    """The worst case the search found.

    Parameters
    ----------
    values : ndarray
        The point (the sample space's dimensions, SI units).
    noise_seed : int
        The noise seed held during the search (-1 without noise).
    objective : float
        Its worst normalized margin (negative: a requirement broken).
    requirement : str
        The requirement with that margin.
    margins : dict
        Every requirement's margin there (requirement unit; None where undefined).
    start_objective : float
        The worst normalized margin among the sampled points it started from.
    evaluations : int
        Runs made.
    method : str
        What was run, in words.
    """

    values: np.ndarray
    noise_seed: int
    objective: float
    requirement: str
    margins: dict[str, float | None]
    start_objective: float
    evaluations: int
    method: str

    @property
    def broken(self) -> bool:
        """True when the worst case found breaks a requirement."""
        return self.objective < 0


def _objective(m: Any, fail: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    norm = m.normalized()
    norm = np.maximum(np.where(np.isfinite(norm), norm, UNDEFINED), UNDEFINED)
    norm[fail] = UNDEFINED
    return norm.min(axis=1), norm.argmin(axis=1)


def falsify(prep: Any, starts: np.ndarray, seeds: np.ndarray, *, budget: int = BUDGET) -> Falsification:
    """Search the box from ``starts`` (``(k, d)`` sample values, the worst first) for the worst margin.

    Parameters
    ----------
    prep : Prepared
        The spec made ready (:func:`designkit.sweep.chunk.prepared`).
    starts : ndarray, shape (k, d)
        Sampled points to start from.
    seeds : ndarray, shape (k,)
        Their noise seeds.
    budget : int
        Largest number of runs of the Powell search.
    """
    from scipy.optimize import minimize

    from designkit.sweep.chunk import run_samples

    space = prep.space
    lo, hi = space.low, space.high
    d = lo.size
    seed = int(seeds[0]) if seeds.size else -1
    names = list(_names(prep))
    count = 0
    best: dict[str, Any] = {}

    def evaluate(points: np.ndarray) -> np.ndarray:
        nonlocal count
        out = np.empty(points.shape[0])
        for a in range(0, points.shape[0], prep.batch.batch):
            chunk = points[a:a + prep.batch.batch]
            m, fail = run_samples(prep, chunk, np.full(chunk.shape[0], seed))
            obj, which = _objective(m, fail)
            out[a:a + chunk.shape[0]] = obj
            for i in range(chunk.shape[0]):
                if not best or obj[i] < best["objective"]:
                    best.update(objective=float(obj[i]), values=chunk[i].copy(), requirement=names[which[i]],
                                margins={k: (float(m.margin[k][i]) if np.isfinite(m.margin[k][i]) else None)
                                         for k in names})
        count += points.shape[0]
        return out

    start_obj = evaluate(np.atleast_2d(starts)[:1])[0] if d else 0.0
    steps = ["the worst sample"]
    if d and 2**d <= MAX_CORNERS:
        corners = np.array([[hi[k] if (c >> k) & 1 else lo[k] for k in range(d)] for c in range(2**d)])
        evaluate(corners)
        steps.append(f"the box's {2**d} corners")
    wide = hi > lo
    if d and np.any(wide) and budget > 0:
        x0 = best["values"].copy()
        span = np.where(wide, hi - lo, 1.0)

        def f(u: np.ndarray) -> float:
            x = lo + u * span
            return float(evaluate(x[None, :])[0])

        u0 = np.clip((x0 - lo) / span, 0.0, 1.0)
        before = count
        minimize(f, u0, method="Powell", bounds=[(0.0, 1.0)] * d,
                 options={"maxfev": int(budget), "xtol": 1e-3, "ftol": 1e-6})
        steps.append(f"a bounded Powell search from the worst point so far ({count - before} runs)")
    return Falsification(values=np.asarray(best["values"], dtype=float), noise_seed=seed,
                         objective=float(best["objective"]), requirement=str(best["requirement"]),
                         margins=dict(best["margins"]), start_objective=float(start_obj), evaluations=count,
                         method=", then ".join(steps))


def _names(prep: Any) -> tuple[str, ...]:
    from designkit.sweep.chunk import _names as names

    return names(prep)
