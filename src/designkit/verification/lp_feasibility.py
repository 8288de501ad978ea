"""Linear feasibility of ``G x <= h`` on the LP core, decided by a re-checked primal point or Farkas vector.

The LP ``max t`` subject to ``G_i x + t ||G_i|| <= h_i`` (``t <= t_max``) gives the distance from
``x`` to the nearest constraint boundary; a feasible system is certified by ``x`` (its slacks
recomputed in NumPy), an infeasible one by the normalised dual, a Farkas vector
(:mod:`designkit.verification.lp_certificates`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.verification.certificate import Recheck, to_json
from designkit.verification.check import Check
from designkit.verification.lp import solve_lp
from designkit.verification.lp_certificates import FarkasCertificate, FeasiblePointCertificate, _row_norms
from designkit.verification.tolerances import LP_SOLVER_OK

__all__ = ["LinearFeasibility", "linear_feasibility"]


def _named(names: Sequence[str], theta: np.ndarray) -> dict[str, float]:
    return {n: float(v) for n, v in zip(names, theta, strict=True)}


@dataclass(frozen=True)
class LinearFeasibility:
    """Outcome of :func:`linear_feasibility`.

    Parameters
    ----------
    feasible : bool or None
        True: ``x`` re-checked.  False: Farkas vector re-checked.  None: undecided.
    names : tuple of str
        Names of the unknowns.
    x : ndarray or None
        The solver's point (the Chebyshev-like centre, margin ``t``).
    slacks : ndarray or None
        ``h - G x`` computed by NumPy.
    t : float or None
        The solver's uniform margin (units of ``x``; capped at ``t_max``).
    point : FeasiblePointCertificate or None
    farkas : FarkasCertificate or None
    recheck : Recheck or None
        The re-check that decided (or the last one tried).
    status : str
    solver : str
    detail : str
    """

    feasible: bool | None
    names: tuple[str, ...]
    x: np.ndarray | None
    slacks: np.ndarray | None
    t: float | None
    point: FeasiblePointCertificate | None
    farkas: FarkasCertificate | None
    recheck: Recheck | None
    status: str
    solver: str
    detail: str

    def to_check(self, name: str = "linear_feasibility", *, required: bool = True) -> Check:
        """The outcome as a :class:`Check` (True feasible, False infeasible, None undecided)."""
        cert: dict[str, Any] = {"parameters": list(self.names), "solver": self.solver, "solver_status": self.status,
                                "t": self.t}
        if self.x is not None:
            cert["x"] = to_json(_named(self.names, self.x))
        if self.slacks is not None:
            cert["slacks"] = to_json(self.slacks)
        if self.recheck is not None:
            cert["recheck"] = self.recheck.to_dict()
        if self.feasible is False and self.farkas is not None:
            cert["evidence"] = {"farkas_y": to_json(self.farkas.y), **dict(self.recheck.values)}
        margin = None if self.recheck is None or self.feasible is None else self.recheck.margin
        if self.feasible is False and margin is not None:
            margin = -margin  # the constraints miss each other by this much
        return Check(name=name, passed=self.feasible, target="G x <= h has a solution", achieved=margin,
                     margin=margin, unit="units of x", detail=self.detail, certificate=cert, required=required)


def _polish_farkas(G: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Reduce ``G'y`` of the solver's dual in NumPy; only a proposal, the re-check decides.

    Candidates: on the support ``{i : y_i > delta max y}`` (``delta`` = 1e-6, 1e-3; the rest set
    to zero), ``y`` projected onto ``null(G_S')`` by least squares; and alternate projections onto
    ``null(G')`` and clipping at zero.  The candidate with the smallest ``||G'y|| / sum y_i ||G_i||``
    among those that stay ``>= 0`` is returned (``y`` itself if none is better).
    """
    norms = _row_norms(G)

    def residual(v: np.ndarray) -> float:
        weight = float(v @ norms)
        return float(np.linalg.norm(G.T @ v)) / weight if weight > 0 and np.all(v >= 0) else np.inf

    candidates = [y]
    top = float(np.max(y)) if y.size else 0.0
    for delta in (1e-6, 1e-3):
        support = y > delta * top
        if np.any(support):
            v = np.zeros_like(y)
            ys, Gs = y[support], G[support]
            v[support] = ys - Gs @ np.linalg.lstsq(Gs, ys, rcond=None)[0]
            candidates.append(v)
    v = y
    for _ in range(3):
        v = np.maximum(v - G @ np.linalg.lstsq(G, v, rcond=None)[0], 0.0)
        candidates.append(v)
    return min(candidates, key=residual)


def linear_feasibility(
    G: np.ndarray,
    h: np.ndarray,
    *,
    names: Sequence[str] | None = None,
    solver: str = "CLARABEL",
    t_max: float = 1.0,
) -> LinearFeasibility:
    """Decide ``G x <= h`` by the max-margin LP and re-check its primal or Farkas certificate.

    Parameters
    ----------
    G : ndarray, shape (m, n)
    h : ndarray, shape (m,)
    names : sequence of str, optional
        Names of the unknowns (default ``x0, x1, ...``).
    solver : str
        cvxpy solver name.
    t_max : float
        Cap on the margin ``t`` (units of ``x``), so that unbounded feasible sets keep the LP bounded.

    Returns
    -------
    LinearFeasibility
        Feasible iff the solver is optimal and ``x`` re-checks; infeasible iff the solver is
        optimal and its normalised dual re-checks as a Farkas vector; a zero row with ``h_i < 0`` is
        infeasible without the solver.  Anything else is undecided.
    """
    G = np.atleast_2d(np.asarray(G, dtype=float))
    h = np.asarray(h, dtype=float).reshape(-1)
    m, n = G.shape
    if h.shape != (m,):
        raise ValueError(f"h must have {m} entries, got {h.shape}")
    names = tuple(names) if names is not None else tuple(f"x{j}" for j in range(n))
    if len(names) != n:
        raise ValueError(f"{len(names)} names for {n} unknowns")
    norms = _row_norms(G)
    zero = norms == 0
    bad = np.flatnonzero(zero & (h < 0))
    if bad.size:
        y = np.zeros(m)
        y[bad[0]] = 1.0
        far = FarkasCertificate(G, h, y)
        rc = far.recheck()
        return LinearFeasibility(False, names, None, None, None, None, far, rc, "not solved", solver,
                                 f"infeasible: row {bad[0]} reads 0 <= {h[bad[0]]:.6g}")
    keep = ~zero
    Gn, hn = G[keep] / norms[keep, None], h[keep] / norms[keep]
    k = len(hn)
    Gz = np.block([[Gn, np.ones((k, 1))], [np.zeros((1, n)), np.ones((1, 1))]])
    hz = np.concatenate([hn, [t_max]])
    cz = np.concatenate([np.zeros(n), [-1.0]])
    sol = solve_lp(cz, Gz, hz, solver=solver)
    x = None if sol.x is None else sol.x[:n]
    t = None if sol.x is None else float(sol.x[n])
    slacks = None if x is None else h - G @ x
    if sol.status not in LP_SOLVER_OK or x is None:
        return LinearFeasibility(None, names, x, slacks, t, None, None, None, sol.status, solver,
                                 f"undecided: solver status {sol.status!r}")
    point = FeasiblePointCertificate(G, h, x)
    farkas = None
    if sol.dual is not None:
        y = np.zeros(m)
        y[keep] = np.maximum(sol.dual[:k], 0.0) / norms[keep]
        y = _polish_farkas(G, y)
        farkas = FarkasCertificate(G, h, y) if np.any(y > 0) else None
    order = ("point", "farkas") if t is not None and t >= 0 else ("farkas", "point")
    tried: Recheck | None = None
    for which in order:
        if which == "point":
            tried = point.recheck()
            if tried.ok:
                return LinearFeasibility(True, names, x, slacks, t, point, farkas, tried, sol.status, solver,
                                         f"feasible: {tried.detail}")
        elif farkas is not None:
            tried = farkas.recheck()
            if tried.ok:
                return LinearFeasibility(False, names, x, slacks, t, point, farkas, tried, sol.status, solver,
                                         f"infeasible: {tried.detail}")
    return LinearFeasibility(None, names, x, slacks, t, point, farkas, tried, sol.status, solver,
                             f"undecided: margin t = {t:.3g} and neither x nor the Farkas vector re-checks")

