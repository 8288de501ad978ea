"""Where the gradient rule loses stability as the adaptation gain (or the reference amplitude) grows.

Three estimates of the largest scale ``s`` of the adaptation gains ``Gamma -> s Gamma`` that keeps the
adaptive loop stable:

1. **Simulation** (:func:`gamma_boundary`): the spec's scenario re-simulated with scaled gains,
   each run judged by :func:`~designkit.families.mrac.runs.assess`; the bracket ``[lo, hi]`` (``lo``
   stable, ``hi`` not) is found by steps of :data:`STEP` then geometric bisection to a ratio
   :data:`RATIO`, at most :data:`MAX_RUNS` runs.
2. **Frozen-signal bound** (:func:`frozen_signal_bound`), the argument of Åström and Wittenmark for the
   MIT rule (*Adaptive Control*, 2nd ed., Addison-Wesley 1995, ch. 5, the MIT rule: its stability
   depends on the adaptation gain times the square of the command amplitude, shown by freezing the
   signals and applying Routh to the resulting third-order loop).  Linearize about the matched
   trajectory (plant on the model, ``alpha = alpha*``): with ``dx = x - ym`` and ``alpha~ = alpha -
   alpha*``, ``dx' = A_m dx + k Phi alpha~`` (``Phi = df_m/da = b phi'``, ``b = (0, 1)'``,
   ``phi = (xD - ym1, -ym2)``, ``k = Km tau_n/(Km_n tau)`` the true link's scaling of the
   coefficients) and ``alpha~' = -s Gamma S' Q dx``.  Frozen at an instant, the characteristic
   polynomial is ``s_ (s_^3 + a2 s_^2 + (a1 + s k c1) s_ + s k c0)`` with
   ``c_j = phi' Gamma S' Q[:, j]``; Routh gives stability iff ``c0 > 0`` and
   ``s k (c0 - a2 c1) < a1 a2``.  The bound is ``s_AW = a1 a2 / (k max_t (c0 - a2 c1))`` over one
   reference period (the worst instant): closed form in the model's signals, and -- since ``S`` and
   ``phi`` scale with the amplitude ``A`` -- exactly proportional to ``1/(k A^2)``, the dependence
   Åström and Wittenmark point out.  Freezing time-varying signals is a heuristic (they change on the
   loop's own time scale), so this bound is not a guarantee either way; the comparison says how far
   off it is.
3. **Linearized periodic loop** (:func:`floquet_boundary`): the same linearization, *not* frozen: the
   4-state periodic system over one period of a square-wave (or PRBS) reference, its monodromy
   matrix by RK4 on the run's grid and the first scale whose Floquet multipliers leave the unit
   circle.  Exact for small deviations from the matched trajectory (it also scales as ``1/(k A^2)``);
   the nonlinear run, which starts from a finite parameter error after a plant change, may lose
   stability a little earlier or later.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.families.mrac.runs import adaptive_variant, assess, final_link, plant_ratio, rms, sensitivities, simulate

__all__ = ["Boundary", "GammaRun", "MAX_RUNS", "RATIO", "STEP", "floquet_boundary", "frozen_signal_bound",
           "gamma_boundary", "period_indices"]

STEP = 4.0
"""Factor between the scales tried before the boundary is bracketed."""
RATIO = 1.25
"""Bisection stops when ``hi / lo`` is at most this."""
MAX_RUNS = 10
"""Most simulations of one bisection (the spec's own run included when given)."""
FLOQUET_GRID = 24
"""Scales evaluated at once on the first, logarithmic, grid of the Floquet boundary search."""
RK4_RESOLUTION = 1.0
"""Largest ``dt |lambda|`` (grid step times the reference model's fastest pole) at which the monodromy matrix is
integrated on the run's grid; RK4 itself turns unstable near 2.8, so a coarser grid gives no Floquet estimate."""


@dataclass(frozen=True)
class GammaRun:
    """One re-simulation at ``scale`` times the spec's adaptation gains."""

    scale: float
    stable: bool
    rms: float
    growth: float | None
    final: tuple[float, float]
    reason: str


@dataclass(frozen=True)
class Boundary:
    """The simulated bracket: ``lo`` the largest stable scale tried, ``hi`` the smallest unstable one (None when
    not found within the budget); ``runs`` in the order simulated."""

    lo: float | None
    hi: float | None
    runs: tuple[GammaRun, ...]

    @property
    def monotone(self) -> bool:
        """Every run below ``hi`` stable and every run at or above it not (as the bracket assumes)."""
        return all(r.stable == (self.hi is None or r.scale < self.hi) for r in self.runs)


def _one(spec: Any, design: Any, plant: Any, scale: float) -> GammaRun:
    sim = simulate(spec, design, plant, adaptive_variant(design, gamma_scale=scale))
    a = assess(sim, spec)
    final = (float(sim.signals["a1"][-1]), float(sim.signals["a2"][-1]))
    return GammaRun(float(scale), a.stable, rms(sim.signals["e"]), a.growth, final, a.reason)


def gamma_boundary(spec: Any, design: Any, plant: Any, *, known: GammaRun | None = None,
                   max_runs: int = MAX_RUNS) -> Boundary:
    """The simulated stability bracket of the adaptation-gain scale (module docstring, estimate 1).

    Parameters
    ----------
    spec, design, plant
        The scenario, the design and the true plant.
    known : GammaRun, optional
        The run at scale 1 already made (the pipeline's), not repeated.
    max_runs : int
        Budget of simulations, ``known`` included.
    """
    runs = [known if known is not None else _one(spec, design, plant, 1.0)]
    lo = 1.0 if runs[0].stable else None
    hi = None if runs[0].stable else 1.0
    while len(runs) < max_runs and (lo is None or hi is None):
        s = lo * STEP if hi is None else hi / STEP  # up from a stable scale, down from an unstable one
        run = _one(spec, design, plant, s)
        runs.append(run)
        lo, hi = (s, hi) if run.stable else (lo, s)
    while len(runs) < max_runs and lo is not None and hi is not None and hi / lo > RATIO:
        s = math.sqrt(lo * hi)
        run = _one(spec, design, plant, s)
        runs.append(run)
        lo, hi = (s, hi) if run.stable else (lo, s)
    return Boundary(lo, hi, tuple(runs))


def period_indices(sim: Any) -> tuple[int, int] | None:
    """``(i0, i1)``: the samples spanning the run's last whole reference period (square wave, or a PRBS whose
    sequence repeats within the run after one period to settle), None for a reference that is not periodic."""
    ref = sim.settings.get("reference", {})
    if ref.get("kind") == "square":
        period = float(ref["period"])
    elif ref.get("kind") == "prbs":
        period = float(ref["bit"]) * float(ref["period_bits"])
    else:
        return None
    t = np.asarray(sim.time, dtype=float)
    dt = float(t[1] - t[0])
    steps = int(round(period / dt))
    if abs(steps * dt - period) > 1e-9 * period or t[-1] < 2 * period:
        return None
    i1 = t.size - 1 - ((t.size - 1) % steps)  # a multiple of the period: the model is periodic there
    return i1 - steps, i1


def _signals(sim: Any, design: Any, Q: Any = None) -> dict[str, np.ndarray]:
    x = design.data
    names = list(sim.controller_state_names)
    xc = np.asarray(sim.controller_state, dtype=float)
    ym = xc[:, [names.index("ym1"), names.index("ym2")]]
    r = np.asarray(sim.reference, dtype=float)[:, 0, 0]
    return {"S": sensitivities(sim), "phi": np.stack([r - ym[:, 0], -ym[:, 1]], axis=1),
            "G": np.diag(np.asarray(x.gamma, dtype=float)), "Q": np.asarray(x.Q if Q is None else Q, dtype=float),
            "a": np.asarray(x.reference_model.a, dtype=float)}


def frozen_signal_bound(sim: Any, design: Any, spec: Any, plant: Any, *, Q: Any = None) -> dict[str, float] | None:
    """Estimate 2 of the module docstring over the run's last reference period (or the whole run when the
    reference is not periodic): ``{"scale", "at", "k", "worst"}``, None when no instant is destabilizing.

    ``Q`` replaces the design's weighting (the model's signals do not depend on it, nor on the gains)."""
    sig = _signals(sim, design, Q)
    idx = period_indices(sim)
    sl = slice(idx[0], idx[1] + 1) if idx is not None else slice(None)
    S, phi = sig["S"][sl], sig["phi"][sl]
    W = np.einsum("ij,nkj,kl->nil", sig["G"], S, sig["Q"])  # Gamma S' Q, (N, params, states)
    c0 = np.einsum("ni,ni->n", phi, W[:, :, 0])
    c1 = np.einsum("ni,ni->n", phi, W[:, :, 1])
    a1, a2 = sig["a"]
    k = plant_ratio(design, final_link(spec, plant))
    worst = c0 - a2 * c1
    worst = np.where(c0 > 0, worst, -np.inf)
    j = int(np.argmax(worst))
    if not np.isfinite(worst[j]) or worst[j] <= 0:
        return None
    t = np.asarray(sim.time, dtype=float)[sl]
    return {"scale": float(a1 * a2 / (k * worst[j])), "at": float(t[j]), "k": float(k), "worst": float(worst[j])}


def _monodromy_radius(sig: dict[str, np.ndarray], i0: int, i1: int, dt: float, k: float,
                      scales: np.ndarray) -> np.ndarray:
    """Spectral radius of the monodromy matrix of the linearized periodic loop, per scale (RK4 on the grid)."""
    a1, a2 = sig["a"]
    m = scales.size
    W = np.einsum("ij,nkj,kl->nil", sig["G"], sig["S"][i0:i1 + 1], sig["Q"])
    phi = sig["phi"][i0:i1 + 1]

    def matrix(i: int) -> np.ndarray:
        A = np.zeros((m, 4, 4))
        A[:, 0, 1] = 1.0
        A[:, 1, 0], A[:, 1, 1] = -a1, -a2
        A[:, 1, 2:] = k * phi[i]
        A[:, 2:, :2] = -scales[:, None, None] * W[i][None, :, :]
        return A

    X = np.tile(np.eye(4), (m, 1, 1))
    A_next = matrix(0)
    with np.errstate(all="ignore"):  # a scale whose monodromy overflows is unstable: radius inf below
        for i in range(i1 - i0):
            A0, A_next = A_next, matrix(i + 1)
            Am = 0.5 * (A0 + A_next)
            k1 = A0 @ X
            k2 = Am @ (X + 0.5 * dt * k1)
            k3 = Am @ (X + 0.5 * dt * k2)
            k4 = A_next @ (X + dt * k3)
            X = X + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        finite = np.all(np.isfinite(X), axis=(1, 2))
        radius = np.full(m, np.inf)
        if finite.any():
            radius[finite] = np.max(np.abs(np.linalg.eigvals(X[finite])), axis=1)
    return np.where(np.isfinite(radius), radius, np.inf)


def floquet_boundary(sim: Any, design: Any, spec: Any, plant: Any, *, around: float | None = None,
                     Q: Any = None) -> dict[str, Any] | None:
    """Estimate 3 of the module docstring: ``{"scale", "k", "grid": [(scale, radius)...]}`` -- the smallest scale
    whose monodromy matrix has a multiplier outside the unit circle, refined to 1 %; None for a reference that
    is not periodic, a run's grid too coarse for RK4 on the model (:data:`RK4_RESOLUTION`) or no crossing on the
    grid (``around``: a scale to centre the grid on, default 1; ``Q``: another
    weighting, as for :func:`frozen_signal_bound`)."""
    idx = period_indices(sim)
    if idx is None:
        return None
    sig = _signals(sim, design, Q)
    if not (np.all(np.isfinite(sig["S"][idx[0]:idx[1] + 1])) and np.all(np.isfinite(sig["phi"]))):
        return None
    t = np.asarray(sim.time, dtype=float)
    dt = float(t[1] - t[0])
    a1, a2 = sig["a"]
    if dt * float(np.max(np.abs(np.roots([1.0, a2, a1])))) > RK4_RESOLUTION:
        return None  # the run's grid does not resolve the model's own dynamics: RK4 on it says nothing
    k = plant_ratio(design, final_link(spec, plant))
    centre = 1.0 if around is None else float(around)
    grid = np.geomspace(centre / 100.0, centre * 100.0, FLOQUET_GRID)
    radius = _monodromy_radius(sig, idx[0], idx[1], dt, k, grid)
    above = np.flatnonzero(radius > 1.0)
    if above.size == 0 or above[0] == 0:
        return None
    lo, hi = float(grid[above[0] - 1]), float(grid[above[0]])
    while hi / lo > 1.01:
        trial = np.geomspace(lo, hi, 6)[1:-1]
        rad = _monodromy_radius(sig, idx[0], idx[1], dt, k, trial)
        first = np.flatnonzero(rad > 1.0)
        if first.size:
            hi = float(trial[first[0]])
            lo = float(trial[first[0] - 1]) if first[0] > 0 else lo
        else:
            lo = float(trial[-1])
    return {"scale": math.sqrt(lo * hi), "k": float(k),
            "grid": [(float(g), float(r)) for g, r in zip(grid, radius, strict=True)]}
