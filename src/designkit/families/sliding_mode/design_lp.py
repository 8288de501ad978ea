"""The gains ``(alpha, beta, M)`` from a linear program over the corners of the ``(Km, tau)`` box.

For a fixed sliding pole ``c`` every condition is linear in ``(alpha, beta, M)``, and multiplied by ``Km`` or
``4 Km tau`` it is affine or multi-affine in ``(Km, tau)``, so its worst case over the box is at a corner
(:mod:`~designkit.families.sliding_mode.conditions`).  With the relative margin ``m`` (spec ``margin``), at
every corner ``(Km, tau)``::

    4 Km tau alpha          >= 1 + m                                    alpha >= (1 + m) a^2/(4 b)   (reaching)
    Km alpha                >= c (1 - c tau) + m |c (1 - c tau)|        alpha >= k + m |k|          (existence)
    Km beta                 <= c (1 - c tau) - m (c + c^2 tau)          beta <= k - m (c + c^2 tau)/Km
    M                       >= (1 + m) xi_bar                                                         (perturbation)

(the margin on ``beta`` is taken on the size of ``k``'s two terms, so it does not vanish where ``k`` does, at
``c tau = 1``).

Minimal switching means a slow ``alpha`` structure, hence slow reaching (against an opposing perturbation
especially); ``controller.reaching_frequency`` ``omega_r`` (rad/s) adds ``Km alpha >= omega_r^2 tau`` at every
corner: the ``alpha`` structure's natural frequency ``sqrt(b alpha)`` at least ``omega_r`` (a performance row, not
a condition of the sliding mode: it is not certified).  With ``requirements.max_control`` = ``u_max`` two coupled
rows bound the command for ``|e| <= e_max``: ``alpha e_max + M <= u_max`` and ``-beta e_max + M <= u_max``; they
are dropped (and the design says so) when they cannot be met together with the conditions, and the
``max_control`` check judges the run.

Objective: the switching amplitude.  Across ``s = 0`` the command jumps by ``(alpha - beta)|e| + 2 M``, at most
``(alpha - beta) e_max + 2 M`` (N*m), so the program minimises ``e_max (alpha - beta) + 2 M``: the weights are
``(e_max, -e_max, 2)`` on ``(alpha, beta, M)``.  A gain the spec gives is fixed (two rows ``x = value``) and its
margin rows dropped: the certificate judges it.

The LP is solved on the LP core (:func:`designkit.verification.lp.solve_lp`, cvxpy with Clarabel) in scaled
variables (each gain over the largest bound its own rows give, unit-norm rows).  Its answer is a proposal: every
margin row is re-checked in NumPy at the returned gains; a row violated by more than the solver's rounding
(``LP_ROW_TOL``) makes the design fail loudly, and a gain within ``SNAP_TOL`` of its tightest bound is put on it.
Without the torque rows the program is separable (each row bounds one gain), so its optimum is the tightest
corner bound of each gain; the tests check the solver against that closed form.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.families.sliding_mode.conditions import Box, vertices

__all__ = ["LP_ROW_TOL", "LpDesign", "design_gains"]

LP_ROW_TOL = 1e-7
"""Largest violation of a margin row accepted from the solver, relative to the row's size (Clarabel's default
feasibility tolerance is 1e-8)."""
SNAP_TOL = 1e-6
"""A gain this close (relative) to its tightest corner bound is the bound: the solver's interior-point answer is put
on the vertex of the feasible set it approximates (moving a gain onto its bound in the objective's direction only
loosens the torque rows)."""
NAMES = ("alpha", "beta", "M")


@dataclass(frozen=True)
class LpDesign:
    """The program's outcome.

    Parameters
    ----------
    alpha, beta, M : float
        Gains (N*m/rad, N*m/rad, N*m).
    weights : tuple of float
        Objective weights on ``(alpha, beta, M)``: ``(e_max, -e_max, 2)``.
    objective : float
        ``e_max (alpha - beta) + 2 M`` (N*m): the largest jump of the command across ``s = 0``.
    status : str
        The solver's status.
    rows : int
        Number of inequality rows.
    fixed : tuple of str
        Gains given by the spec.
    torque_rows : str
        ``"none"`` (no ``max_control``), ``"kept"`` or ``"dropped: ..."``.
    """

    alpha: float
    beta: float
    M: float
    weights: tuple[float, float, float]
    objective: float
    status: str
    rows: int
    fixed: tuple[str, ...] = ()
    torque_rows: str = "none"
    certificate: Mapping[str, Any] = field(default_factory=dict)


def _margin_rows(c: float, box: Box, xi_bar: float, m: float, fixed: Mapping[str, float],
                 omega_r: float | None = None) -> tuple[list, list]:
    G, h = [], []
    for Km, tau in vertices(box):
        k_num = c * (1.0 - c * tau)  # = Km k
        if "alpha" not in fixed:
            G += [[-4.0 * Km * tau, 0.0, 0.0], [-Km, 0.0, 0.0]]
            h += [-(1.0 + m), -(k_num + m * abs(k_num))]
            if omega_r is not None:  # b alpha >= omega_r^2: the alpha structure's natural frequency
                G.append([-Km, 0.0, 0.0])
                h.append(-omega_r * omega_r * tau)
        if "beta" not in fixed:
            G.append([0.0, Km, 0.0])
            h.append(k_num - m * (c + c * c * tau))
    if "M" not in fixed:
        G.append([0.0, 0.0, -1.0])
        h.append(-(1.0 + m) * xi_bar)
    for j, name in enumerate(NAMES):
        if name in fixed:
            row = [0.0, 0.0, 0.0]
            row[j] = 1.0
            G += [row, [-x for x in row]]
            h += [fixed[name], -fixed[name]]
    return G, h


_TINY = 1e-100
"""A bound below which a gain is not rescaled by it: a gain fixed at 1e-308 would scale its rows to numbers whose
squares underflow (and the row norms to 0)."""


def _solve(G: list, h: list, w: np.ndarray, solver: str) -> tuple[np.ndarray | None, str]:
    """The LP in scaled variables ``x_j = scale_j y_j`` (``scale_j`` the largest bound a single-gain row puts on
    gain ``j``) with unit-norm rows, so that the solver's tolerance is relative to every gain (``beta`` can be
    hundreds of times ``alpha``)."""
    from designkit.verification.lp import solve_lp

    G, h = np.array(G, float), np.array(h, float)
    scale = np.ones(G.shape[1])
    for j in range(G.shape[1]):
        alone = (G[:, j] != 0) & (np.count_nonzero(G, axis=1) == 1)
        bounds = np.abs(h[alone] / G[alone, j])
        if bounds.size and bounds.max() > _TINY:
            scale[j] = bounds.max()
    Gs = G * scale
    peaks = np.max(np.abs(Gs), axis=1)  # each row's norm taken on the row scaled to 1: a gain given as 1e-308 would
    norms = peaks * np.linalg.norm(Gs / peaks[:, None], axis=1)  # underflow in the sum of squares
    sol = solve_lp(w * scale / np.max(np.abs(w * scale)), Gs / norms[:, None], h / norms, solver=solver)
    return (None if sol.x is None else np.asarray(sol.x, float) * scale), sol.status


def design_gains(c: float, box: Box, xi_bar: float, margin: float, e_max: float, *,
                 fixed: Mapping[str, float] | None = None, u_max: float | None = None,
                 omega_r: float | None = None, solver: str = "CLARABEL") -> LpDesign:
    """Minimum-switching gains ``(alpha, beta, M)`` meeting every condition with ``margin`` at every corner.

    Parameters
    ----------
    c : float
        Sliding-line slope (1/s), ``> 0``.
    box : Mapping
        ``{"Km": (lo, hi), "tau": (lo, hi)}``.
    xi_bar : float
        ``sup |xi|`` (N*m).
    margin : float
        Relative margin ``m > 0``.
    e_max : float
        Largest ``|e|`` the servo meets (rad): the weight of ``alpha - beta``.
    fixed : Mapping, optional
        Gains given by the spec (name -> value).
    u_max : float, optional
        ``requirements.max_control`` (N*m): adds the two torque rows.
    omega_r : float, optional
        ``controller.reaching_frequency`` (rad/s): adds ``Km alpha >= omega_r^2 tau`` at every corner.

    Raises
    ------
    RuntimeError
        The solver fails or returns gains that violate a margin row beyond :data:`LP_ROW_TOL` (a bug or a solver
        failure: the margin rows alone are always feasible).
    """
    fixed = dict(fixed or {})
    G, h = _margin_rows(c, box, xi_bar, margin, fixed, omega_r)
    n_margin = len(G)
    w = np.array([e_max, -e_max, 2.0])
    torque = "none"
    x = status = None
    if u_max is not None:
        x, status = _solve([*G, [e_max, 0.0, 1.0], [0.0, -e_max, 1.0]], [*h, u_max, u_max], w, solver)
        if x is not None and status == "optimal":
            torque = "kept"
            G, h = [*G, [e_max, 0.0, 1.0], [0.0, -e_max, 1.0]], [*h, u_max, u_max]
        else:
            torque = (f"dropped: |u| <= {u_max:g} N*m for |e| <= {e_max:g} rad cannot be met together with the "
                      f"conditions (solver status {status}); the max_control check judges the run")
            x = None
    if x is None:
        x, status = _solve(G, h, w, solver)
    if x is None or status != "optimal":
        raise RuntimeError(f"the sliding-mode gain LP did not solve (status {status})")
    Ga, ha = np.array(G[:n_margin]), np.array(h[:n_margin])
    x = np.array(x, float)
    size = np.abs(Ga) @ np.abs(x) + np.abs(ha)
    excess = Ga @ x - ha
    if np.any(excess > LP_ROW_TOL * np.maximum(size, 1.0)):
        raise RuntimeError(f"the sliding-mode gain LP returned gains violating a margin row by {excess.max():.3g}")
    for j in range(3):  # a gain within the solver's tolerance of its tightest bound is put on it (exactly)
        rows = np.flatnonzero(Ga[:, j] != 0)  # every margin row bounds one gain
        lower = [ha[i] / Ga[i, j] for i in rows if Ga[i, j] < 0]
        upper = [ha[i] / Ga[i, j] for i in rows if Ga[i, j] > 0]
        for bound in ([max(lower)] if lower else []) + ([min(upper)] if upper else []):
            if abs(x[j] - bound) <= SNAP_TOL * max(abs(bound), abs(x[j])):
                x[j] = bound
        for i in rows:  # and a gain rounding left a hair outside a bound is moved onto it
            if Ga[i] @ x > ha[i]:
                x[j] = ha[i] / Ga[i, j]
    objective = float(w @ x)
    cert = {"variables": list(NAMES), "weights": w.tolist(), "G": np.array(G).tolist(), "h": list(map(float, h)),
            "margin_rows": n_margin, "x": x.tolist(), "objective": objective, "status": status,
            "vertices": vertices(box).tolist()}
    return LpDesign(float(x[0]), float(x[1]), float(x[2]), (float(w[0]), float(w[1]), 2.0), objective, str(status),
                    len(G), tuple(sorted(fixed)), torque, cert)
