"""The gradient search of a smooth loop: SLSQP on the epigraph of the worst requirement margin over the box.

The worst normalised margin ``min over requirements r and box points p of m_rp(x)`` is not differentiable where two
margins cross (the optimum of a trade-off is such a point); its epigraph is::

    maximise t   over (x, t),  x in the log box,   subject to   m_rp(x) - t >= 0   for every r and p

whose constraints are smooth where each margin is.  SciPy's SLSQP (:func:`scipy.optimize.minimize`,
``method="SLSQP"``) solves it with the margins and their gradients of :func:`designkit.tuning.sensitivity.gradients`
(one sensitivity run per box point for each new ``x``).  Every iterate SLSQP accepts, and the point it ends on, is
run as any candidate is (``evaluate``: the family's own run at every box point, then its certificates when it could
be the best): the answer is the best of those candidates, never a value of the sensitivity runs.  From the best
candidate the search starts again, and every other time from a seeded random point of the box, until a restart from
the best point improves its score by less than :data:`~designkit.tuning.search.TOLERANCE`, or the budget is spent
(the first gradient is always computed, and the point SLSQP steps to when the budget runs out is still run as a
candidate), or six restarts are done.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from designkit.studies.core.budget import cpu_seconds
from designkit.tuning.search import TOLERANCE, Search, _best, _OutOfTimeError

__all__ = ["METHOD", "slsqp"]

METHOD = ("gradient: SLSQP (SciPy) on the epigraph of the worst margin over the box's points, the margins' "
          "gradients by CasADi forward sensitivities of the RK4 step through the run (the design map by central "
          "differences)")
"""The method in words."""

MAX_ITERATIONS = 40
"""SLSQP iterations per descent."""


def slsqp(evaluate: Callable[[np.ndarray, float], Any], gradient: Callable[[np.ndarray], Any], x0: np.ndarray,
          bounds: tuple[np.ndarray, np.ndarray], *, budget: float, seed: int = 0, max_restarts: int = 6) -> Search:
    """Maximise the worst margin by SLSQP on its epigraph (module docstring).

    Parameters
    ----------
    evaluate : callable
        ``(x, best score so far) -> Evaluation``: the candidate's run (:func:`designkit.tuning.evaluate.evaluate`).
    gradient : callable
        ``x -> Gradient``: the margins at every box point and their gradients
        (:func:`designkit.tuning.sensitivity.gradients`).
    x0 : ndarray
        The start (log space).
    bounds : (ndarray, ndarray)
        Lower and upper bounds (log space).
    budget : float
        Processor time the search may take (s); the run going on when it is spent is finished.
    seed : int
        Seed of the random restarts.
    max_restarts : int
        Most restarts after the first descent.

    Returns
    -------
    Search
        ``iterations`` the SLSQP iterations, ``sensitivity_runs`` the sensitivity runs (counted among the
        simulations).
    """
    from scipy.optimize import minimize

    lo, hi = bounds
    n = lo.size
    start, clock = time.perf_counter(), cpu_seconds()
    rng = np.random.default_rng(seed)
    done: list[Any] = []
    tried: dict[bytes, Any] = {}
    grads: dict[bytes, Any] = {}
    sens = [0]
    pending: list[np.ndarray] = []  # the point SLSQP stepped to when the budget ran out
    count = [0]

    def key(x: np.ndarray) -> bytes:
        return np.round(np.clip(np.asarray(x, dtype=float), lo, hi), 10).tobytes()

    def candidate(x: np.ndarray, *, last: bool = False) -> Any:
        k = key(x)
        if k not in tried:
            if done and not last and cpu_seconds() - clock > budget:
                raise _OutOfTimeError
            tried[k] = evaluate(np.clip(np.asarray(x, dtype=float), lo, hi), max((e.score for e in done),
                                                                                   default=-np.inf))
            done.append(tried[k])
        return tried[k]

    def model(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The constraints ``m_rp(x) - t`` and their Jacobian in ``(x, t)``."""
        x = np.clip(v[:n], lo, hi)
        k = key(x)
        if k not in grads:
            if grads and cpu_seconds() - clock > budget:
                pending[:] = [x]
                raise _OutOfTimeError
            grads[k] = gradient(x)
            sens[0] += grads[k].runs
        g = grads[k]
        values = [m[r] for m in g.margins for r in m]
        rows = [np.r_[gr[r], -1.0] for gr in g.gradients for r in gr]
        return np.asarray(values) - v[n], np.asarray(rows)

    def tick(v: np.ndarray) -> None:
        count[0] += 1
        candidate(v[:n])

    restarts, stopped, previous = 0, "converged", -np.inf
    point = np.clip(np.asarray(x0, dtype=float), lo, hi)
    while True:
        try:
            candidate(point)
            values, _ = model(np.r_[point, 0.0])
            t0 = float(np.min(values))
            res = minimize(lambda v: -v[n], np.r_[point, t0], jac=lambda v: np.r_[np.zeros(n), -1.0],
                           method="SLSQP", bounds=[*zip(lo, hi, strict=True), (-1e3, 1e3)],
                           constraints=[{"type": "ineq", "fun": lambda v: model(v)[0],
                                         "jac": lambda v: model(v)[1]}],
                           options={"maxiter": MAX_ITERATIONS, "ftol": TOLERANCE / 10}, callback=tick)
            candidate(res.x[:n])  # the point it ends on, run as every candidate is
        except _OutOfTimeError:
            stopped = "budget spent"
            if pending:  # the step SLSQP took last is run as a candidate, the budget spent or not
                candidate(pending[0], last=True)
            break
        score = _best(done).score
        if restarts % 2 == 1 and score - previous < TOLERANCE:  # a restart from the best point found nothing better
            break
        if restarts >= max_restarts:
            stopped = "restarts done"
            break
        previous = max(previous, score)
        restarts += 1
        point = _best(done).x if restarts % 2 == 1 else lo + rng.random(n) * (hi - lo)
    return Search(METHOD + ", restarted from the best point and from seeded random points", _best(done), tuple(done),
                  count[0], restarts, time.perf_counter() - start, stopped, sensitivity_runs=sens[0])
