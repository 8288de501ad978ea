"""The derivative-free searches: Nelder–Mead in log-parameter space with restarts, and a plain random search.

Nelder–Mead (:func:`scipy.optimize.minimize`, ``method="Nelder-Mead"``, bounded) maximises the candidate's score
(:mod:`designkit.tuning.evaluate`: the worst normalised requirement margin over the box, certificates enforced).  It
starts at the spec's own values with a simplex of ±30 % steps; each restart starts again from the best point found
with a simplex half as wide, and every other restart from a seeded random point of the box, until the budget is spent
(processor seconds of this process and the compilers it waited for, so that other work on a loaded machine does not
shorten a search) or two restarts in a row improve the score by less than :data:`TOLERANCE`.  The random search draws
seeded points uniformly in the same log box: the baseline the benchmark compares with.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.studies.core.budget import cpu_seconds

__all__ = ["Search", "TOLERANCE", "nelder_mead", "random_search"]

TOLERANCE = 1e-3
"""Smallest improvement of the score (normalised margin) a restart must make for the search to go on."""

STEP = np.log(1.3)
"""The first simplex's step in log space (a 30 % change of every coordinate)."""


class _OutOfTimeError(Exception):
    """The budget is spent (raised inside the objective to stop scipy's loop)."""


@dataclass(frozen=True)
class Search:
    """What a search did.

    Parameters
    ----------
    method : str
        The method in words.
    best : Evaluation
        The best candidate (largest score; the first one found among equals).
    evaluations : tuple of Evaluation
        Every candidate, in the order run.
    iterations : int
        Nelder–Mead iterations (random search: the draws).
    restarts : int
        Restarts made after the first descent.
    seconds : float
        Wall time (s).
    stopped : str
        Why it stopped (converged, budget spent).
    sensitivity_runs : int
        Runs of the loop with its forward sensitivities (the gradient search; counted among the simulations).
    """

    method: str
    best: Any
    evaluations: tuple[Any, ...]
    iterations: int
    restarts: int
    seconds: float
    stopped: str
    sensitivity_runs: int = 0

    @property
    def simulations(self) -> int:
        """Simulations run (every candidate at every point of the box, and the sensitivity runs)."""
        return sum(e.runs for e in self.evaluations) + self.sensitivity_runs

    @property
    def history(self) -> np.ndarray:
        """Row ``k``: the candidate's score and the best score after ``k + 1`` candidates."""
        scores = np.array([e.score for e in self.evaluations], dtype=float)
        return np.column_stack([scores, np.maximum.accumulate(scores)]) if scores.size else np.zeros((0, 2))


def _best(done: list[Any]) -> Any:
    """The candidate with the largest score (the first among equals)."""
    return max(done, key=lambda e: e.score)


def nelder_mead(evaluate: Callable[[np.ndarray], Any], x0: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], *,
                budget: float, seed: int = 0, max_restarts: int = 6) -> Search:
    """Maximise ``evaluate(x).score`` over the box ``bounds`` from ``x0`` (module docstring).

    Parameters
    ----------
    evaluate : callable
        ``(x, best score so far) -> Evaluation`` (the certificates of a candidate that cannot become the best may be
        left out, :func:`designkit.tuning.evaluate.evaluate`).
    x0 : ndarray
        The start (log space).
    bounds : (ndarray, ndarray)
        Lower and upper bounds (log space).
    budget : float
        Processor time the search may take (s); the candidate running when it is spent is finished.
    seed : int
        Seed of the random restarts.
    max_restarts : int
        Most restarts after the first descent.
    """
    from scipy.optimize import minimize

    lo, hi = bounds
    start, clock = time.perf_counter(), cpu_seconds()
    rng = np.random.default_rng(seed)
    done: list[Any] = []
    cache: dict[bytes, Any] = {}

    def objective(x: np.ndarray) -> float:
        x = np.clip(np.asarray(x, dtype=float), lo, hi)
        key = np.round(x, 10).tobytes()
        if key not in cache:
            if done and cpu_seconds() - clock > budget:
                raise _OutOfTimeError
            cache[key] = evaluate(x, max((e.score for e in done), default=-np.inf))
            done.append(cache[key])
        return -cache[key].score

    def best() -> Any:
        return _best(done)

    restarts, stopped = 0, "converged"
    count = [0]

    def tick(*_: Any) -> None:
        count[0] += 1

    point, width, previous = np.clip(np.asarray(x0, dtype=float), lo, hi), STEP, -np.inf
    n = point.size
    while True:
        steps = [np.clip(point + width * np.eye(n)[i] * (1 if point[i] + width <= hi[i] else -1), lo, hi)
                 for i in range(n)]
        try:
            minimize(objective, point, method="Nelder-Mead", bounds=list(zip(lo, hi, strict=True)),
                           options={"initial_simplex": np.vstack([point, *steps]), "xatol": 1e-3,
                                    "fatol": TOLERANCE / 4, "maxfev": 60 * n, "adaptive": n > 3}, callback=tick)
        except _OutOfTimeError:
            stopped = "budget spent"
            break
        score = best().score
        if restarts % 2 == 1 and score - previous < TOLERANCE:  # a restart from the best point found nothing better
            break
        if restarts >= max_restarts:
            stopped = "restarts done"
            break
        previous = max(previous, score)
        restarts += 1
        if restarts % 2 == 1:  # from the best point, with a narrower simplex
            point, width = best().x, max(width / 2, np.log(1.02))
        else:  # from a random point of the box
            point, width = lo + rng.random(n) * (hi - lo), STEP
    return Search("Nelder–Mead in log-parameter space (SciPy), restarted from the best point and from seeded random "
                  "points", best(), tuple(done), count[0], restarts, time.perf_counter() - start, stopped)


def random_search(evaluate: Callable[[np.ndarray], Any], x0: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], *,
                  budget: float, seed: int = 0, draws: int | None = None) -> Search:
    """The spec's own point, then seeded uniform draws in the log box until ``budget`` seconds or ``draws``."""
    lo, hi = bounds
    start, clock = time.perf_counter(), cpu_seconds()
    rng = np.random.default_rng(seed)
    done = [evaluate(np.clip(np.asarray(x0, dtype=float), lo, hi), -np.inf)]
    stopped = "budget spent"
    while cpu_seconds() - clock <= budget:
        if draws is not None and len(done) >= draws:
            stopped = "draws done"
            break
        done.append(evaluate(lo + rng.random(lo.size) * (hi - lo), _best(done).score))
    return Search("random search (seeded uniform draws in the log box)", _best(done),
                  tuple(done), len(done), 0, time.perf_counter() - start, stopped)
