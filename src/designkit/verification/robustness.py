"""Robust stability of a design over a box of any named plant parameters.

The box comes from the spec's ``plant.uncertainty`` (``{Km: [1.5, 2.5], tau: [0.4, 0.6]}``,
``{m2: [2.5, 3.5]}``, ...).  For every sampled parameter vector ``p`` the designed law acts on
``plant.with_params(p)``: the closed loop's equilibrium for the design's reference is found by
Newton's method and its Jacobian ``A(p)`` taken (:mod:`designkit.synthesis.closed_loop`), all
samples at once (CasADi ``map`` and batched NumPy; a loop over Newton iterations, never over
plants).  Each ``A(p)`` is judged twice: the Routh array of its characteristic polynomial
(Faddeev-LeVerrier, on ``A`` scaled to unit norm) and its eigenvalues; a disagreement (possible
only within rounding of the stability boundary) is undecided.

``robust_vertices``
    Stable at every corner of the box?
``robust_grid``
    Stable on the lattice of the box (``grid`` points per parameter, capped at
    :data:`~designkit.spec.plants.MAX_GRID_POINTS` plants), refined by bisection between neighbours until the
    stability margin is resolved between them (:mod:`designkit.verification.refine`, at most
    :data:`~designkit.verification.refine.MAX_REFINED_PLANTS` plants added), and at ``samples`` seeded random
    interior points?  Reports the worst (largest) spectral abscissa and where it occurs; the
    margin is minus that abscissa, the decay rate (1/s) of the slowest mode.  Sampling, not proof: the
    verdict says how many plants it rests on.
``common_lyapunov`` (informational)
    One quadratic Lyapunov function for the corner closed loops: quadratic stability of their
    convex hull, even under arbitrarily fast variation inside it.  It covers every plant of the
    box only when the plant says its closed-loop ``A`` is affine in coordinates that map the
    box onto the hull of its corners (the link, whose ``A`` is affine in ``(1/tau, Km/tau)``);
    otherwise it is evidence, not proof, for the continuum.  Sufficient, not necessary: not
    finding one is undecided, never a failure of the design.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np

from designkit.spec.plants import MAX_GRID_POINTS
from designkit.synthesis.closed_loop import equilibria, loop_functions, state_matrices
from designkit.verification.check import Check
from designkit.verification.lyapunov import common_lyapunov
from designkit.verification.refine import MAX_REFINED_PLANTS, MIN_WIDTH_FRACTION, RESOLVED_FRACTION, refine
from designkit.verification.routh import MARGINAL, STABLE, UNSTABLE, routh_batch
from designkit.verification.tolerances import LMI_EPS

__all__ = ["Box", "Sweeper", "box_from_uncertainty", "characteristic_coefficients", "grid_check",
           "lyapunov_vertex_check", "robustness_checks", "stable_fraction", "vertex_check"]

MAX_LISTED_POINTS = 10
"""At most this many failing points are listed in a certificate."""
MAX_ROUTH_ORDER = 10
"""Above this closed-loop order the verdict rests on the eigenvalues alone (Faddeev-LeVerrier
coefficients lose accuracy as the order grows)."""


@dataclass(frozen=True)
class Box:
    """A box of named plant parameters.

    Parameters
    ----------
    names : tuple of str
        Parameter names (plant parameters).
    lo, hi : tuple of float
        Bounds (units of the parameters).
    units : tuple of str
        Units, for reports.
    grid : int
        Lattice points per parameter (before the cap).
    samples : int
        Seeded random interior points.
    seed : int
        Their seed.
    """

    names: tuple[str, ...]
    lo: tuple[float, ...]
    hi: tuple[float, ...]
    units: tuple[str, ...] = ()
    grid: int = 21
    samples: int = 0
    seed: int = 0

    @property
    def vertices(self) -> np.ndarray:
        """Distinct corners, shape ``(V, k)`` (a degenerate axis contributes one value)."""
        axes = [sorted({lo, hi}) for lo, hi in zip(self.lo, self.hi, strict=True)]
        return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(self.names))

    @property
    def points_per_axis(self) -> int:
        """Lattice points per non-degenerate axis, reduced so that the lattice has at most the cap."""
        k = sum(lo != hi for lo, hi in zip(self.lo, self.hi, strict=True)) or 1
        return max(2, min(self.grid, int(np.floor(MAX_GRID_POINTS ** (1.0 / k) + 1e-9))))

    @property
    def axes(self) -> tuple[np.ndarray, ...]:
        """The lattice's values along each parameter."""
        g = self.points_per_axis
        return tuple(np.linspace(lo, hi, g) if lo != hi else np.array([lo])
                     for lo, hi in zip(self.lo, self.hi, strict=True))

    @property
    def lattice(self) -> np.ndarray:
        """Every lattice point, shape ``(G, k)``, the first parameter varying slowest."""
        mesh = np.meshgrid(*self.axes, indexing="ij")
        return np.stack([m.ravel() for m in mesh], axis=-1)

    @property
    def random(self) -> np.ndarray:
        """``samples`` seeded uniform points, shape ``(samples, k)``."""
        rng = np.random.default_rng(self.seed)
        lo, hi = np.asarray(self.lo), np.asarray(self.hi)
        return lo + (hi - lo) * rng.random((self.samples, len(self.names)))

    def describe(self) -> dict[str, list[float]]:
        """``{name: [lo, hi]}``."""
        return {n: [lo, hi] for n, lo, hi in zip(self.names, self.lo, self.hi, strict=True)}


def box_from_uncertainty(plant: Any, uncertainty: Any) -> Box:
    """The box of a spec's ``plant.uncertainty`` (parameters in the order written)."""
    intervals = uncertainty.intervals
    names = tuple(intervals)
    return Box(
        names=names, lo=tuple(intervals[n][0] for n in names), hi=tuple(intervals[n][1] for n in names),
        units=tuple(plant.parameter(n).unit for n in names), grid=int(uncertainty.grid),
        samples=int(uncertainty.samples), seed=int(uncertainty.seed),
    )


def characteristic_coefficients(A: np.ndarray) -> np.ndarray:
    """Coefficients of ``det(sI - A)`` (highest power first, monic) for a batch ``(N, n, n)`` (Faddeev-LeVerrier)."""
    A = np.asarray(A, dtype=float)
    N, n, _ = A.shape
    c = np.zeros((N, n + 1))
    c[:, 0] = 1.0
    M = np.zeros_like(A)
    eye = np.eye(n)[None, :, :]
    for k in range(1, n + 1):
        M = A @ M + c[:, k - 1][:, None, None] * eye
        c[:, k] = -np.einsum("nii->n", A @ M) / k
    return c


@dataclass(frozen=True)
class SweepResult:
    """Stability of the loop at a batch of parameter vectors.

    Parameters
    ----------
    theta : ndarray, shape (N, k)
        The uncertain parameters' values.
    status : ndarray of int8, shape (N,)
        1 stable, 0 undecided (marginal, no equilibrium, or Routh and eigenvalues disagree), -1 unstable.
    abscissa : ndarray, shape (N,)
        Spectral abscissa ``max Re(eig A)`` (1/s); NaN without an equilibrium.
    routh_margin : ndarray, shape (N,)
        Smallest scaled Routh first-column entry (NaN when not used).
    A : ndarray, shape (N, nz, nz)
        The closed-loop Jacobians.
    """

    theta: np.ndarray
    status: np.ndarray
    abscissa: np.ndarray
    routh_margin: np.ndarray
    A: np.ndarray


class Sweeper:
    """The design's loop on many plants: builds the CasADi functions once, evaluates batches.

    Parameters
    ----------
    design : Design
        Its linear law (``design.linear_law``: the law, or the adaptive law with its adaptation frozen at
        the initial values) and operating point.
    names : sequence of str
        The plant parameters that vary.
    plant : Plant, optional
        The true plant whose parameters vary (default: the design's).
    """

    def __init__(self, design: Any, names: tuple[str, ...], plant: Any = None) -> None:
        self.design = design
        self.names = tuple(names)
        self.law = design.linear_law
        if self.law is None:
            raise ValueError(f"this {design.kind} design has no linearization to sweep "
                             f"({design.linearization.reason})")
        plant = design.plant if plant is None else plant
        self.plant = plant
        self._index = [plant.parameter_names.index(plant.parameter(n).name) for n in self.names]  # ModelError
        self._p0 = np.asarray(plant.parameter_vector, dtype=float)
        op = design.operating_point
        self._r0 = np.asarray(op["r"], dtype=float)
        self._z0 = np.concatenate([np.asarray(op["x"], dtype=float), np.asarray(op["xc"], dtype=float)])

    @cached_property
    def _functions(self) -> Any:
        return loop_functions(self.plant, self.law)

    def parameters(self, theta: np.ndarray) -> np.ndarray:
        """Full parameter vectors ``(N, n_par)`` for the varying values ``theta`` ``(N, k)``."""
        P = np.tile(self._p0, (theta.shape[0], 1))
        P[:, self._index] = theta
        return P

    def sweep(self, theta: Any) -> SweepResult:
        """Stability of the loop at every row of ``theta``."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        P = self.parameters(theta)
        eq = equilibria(self._functions, self._z0, self._r0, P)
        A = state_matrices(self._functions, eq.z, self._r0, P)
        usable = eq.converged & np.all(np.isfinite(A), axis=(1, 2))
        A_safe = np.where(usable[:, None, None], A, 0.0)
        with np.errstate(all="ignore"):
            eig = np.linalg.eigvals(A_safe)
        abscissa = np.where(usable, eig.real.max(axis=1), np.nan)
        n = A.shape[1]
        if n <= MAX_ROUTH_ORDER:
            # any positive scale makes the coefficients dimensionless; the largest entry is the cheapest
            scale = np.maximum(np.max(np.abs(A_safe), axis=(1, 2)), 1e-300)
            coeffs = characteristic_coefficients(A_safe / scale[:, None, None])
            rb = routh_batch(coeffs)
            status = rb.status.copy()
            margin = rb.margin
            stable_eig = abscissa < 0
            status[(status == STABLE) & ~stable_eig] = MARGINAL
            status[(status == UNSTABLE) & stable_eig] = MARGINAL
        else:
            status = np.where(abscissa < 0, STABLE, UNSTABLE).astype(np.int8)
            margin = np.full(len(status), np.nan)
        status[~usable] = MARGINAL
        return SweepResult(theta=theta, status=status, abscissa=abscissa, routh_margin=margin, A=A)


def stable_fraction(design: Any, samples: dict[str, Any]) -> np.ndarray:
    """Which plants of a batch the design stabilises.

    Parameters
    ----------
    design : Design
    samples : dict
        Parameter name -> array of values (broadcast together).

    Returns
    -------
    ndarray of bool, the broadcast shape of the samples
        True where the closed loop is asymptotically stable (undecided counts as not stable).

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> from designkit.synthesis.servo_loop import servo_design
    >>> d = servo_design(LinkPlant(2.0, 0.5), [-4, -5, -20], -3.0, kind="servo")
    >>> stable_fraction(d, {"Km": [1.0, 2.0, 4.0], "tau": 0.5}).tolist()
    [True, True, True]
    """
    names = tuple(samples)
    arrays = np.broadcast_arrays(*[np.asarray(samples[k], dtype=float) for k in names])
    theta = np.stack([a.ravel() for a in arrays], axis=-1)
    res = Sweeper(design, names).sweep(theta)
    return (res.status == STABLE).reshape(arrays[0].shape)


def _verdict(status: np.ndarray) -> bool | None:
    if np.any(status == UNSTABLE):
        return False
    if np.any(status == MARGINAL):
        return None
    return True


def _word(code: int) -> str:
    return {STABLE: "stable", MARGINAL: "undecided", UNSTABLE: "unstable"}[int(code)]


def _where(box: Box, theta: np.ndarray) -> str:
    return ", ".join(f"{n}={v:.4g}" for n, v in zip(box.names, theta, strict=True))


def vertex_check(design: Any, box: Box, sweeper: Sweeper | None = None) -> Check:
    """Check ``"robust_vertices"``: stability at the corners of the box."""
    sweeper = sweeper or Sweeper(design, box.names)
    res = sweeper.sweep(box.vertices)
    rows = [{**dict(zip(box.names, map(float, th), strict=True)), "status": _word(s), "routh_margin": float(m),
             "spectral_abscissa": float(a)}
            for th, s, m, a in zip(res.theta, res.status, res.routh_margin, res.abscissa, strict=True)]
    passed = _verdict(res.status)
    finite = np.where(np.isfinite(res.abscissa), res.abscissa, np.inf)
    worst = int(np.argmax(finite))
    bad = [(th, s) for th, s in zip(res.theta, res.status, strict=True) if s != STABLE]
    if passed:
        detail = f"all {len(rows)} corners stable; slowest pole Re = {res.abscissa[worst]:.4g} 1/s at " + \
            _where(box, res.theta[worst])
    else:
        detail = "corner(s) not stable: " + "; ".join(f"({_where(box, th)}) {_word(s)}" for th, s in bad[:3])
    achieved = float(res.abscissa[worst]) if np.isfinite(res.abscissa[worst]) else None
    return Check(
        name="robust_vertices", passed=passed, target="stable at every corner of the parameter box",
        achieved=achieved, margin=None if achieved is None else -achieved, unit="1/s", detail=detail,
        certificate={"box": box.describe(), "vertices": rows},
    )


MAX_MIGRATION_PLANTS = 5000
"""Up to this many plants of the lattice, their closed-loop poles are kept for the pole-migration figure."""


def _merge(results: list[SweepResult]) -> SweepResult:
    """One :class:`SweepResult` of several batches (in order)."""
    if len(results) == 1:
        return results[0]
    return SweepResult(*(np.concatenate([getattr(r, f) for r in results])
                         for f in ("theta", "status", "abscissa", "routh_margin", "A")))


def grid_check(design: Any, box: Box, sweeper: Sweeper | None = None, *,
               cap: int = MAX_REFINED_PLANTS) -> Check:
    """Check ``"robust_grid"``: the lattice of the box refined between neighbours until the stability margin is
    resolved (:func:`designkit.verification.refine.refine`, at most ``cap`` plants added), plus seeded random
    samples.  Sampling, not proof: the verdict says how many plants it rests on."""
    sweeper = sweeper or Sweeper(design, box.names)
    lattice = box.lattice
    theta = np.vstack([lattice, box.random]) if box.samples else lattice
    batches = [sweeper.sweep(theta)]

    def evaluate(points: np.ndarray) -> np.ndarray:
        batches.append(sweeper.sweep(points))
        return -batches[-1].abscissa

    shape = tuple(len(a) for a in box.axes)
    span = np.asarray(box.hi, dtype=float) - np.asarray(box.lo, dtype=float)
    refined = refine(lattice, -batches[0].abscissa[: len(lattice)], shape, span, evaluate, cap=cap)
    res = _merge(batches)
    n_unstable = int(np.count_nonzero(res.status == UNSTABLE))
    n_undecided = int(np.count_nonzero(res.status == MARGINAL))
    total = len(res.status)
    finite = np.where(np.isfinite(res.abscissa), res.abscissa, np.inf)
    worst = int(np.argmax(finite))
    bad = np.flatnonzero(res.status != STABLE)
    listed = [{**dict(zip(box.names, map(float, res.theta[i]), strict=True)), "status": _word(res.status[i])}
              for i in bad[:MAX_LISTED_POINTS]]
    passed = _verdict(res.status)
    where = _where(box, res.theta[worst])
    sampled = (f"{len(lattice)} lattice plants ({box.points_per_axis} per axis)"
               + (f", {refined.plants} added by bisection between neighbours in {refined.rounds} rounds"
                  if refined.plants else ", no bisection needed (the margin is resolved between neighbours)")
               + (f", {box.samples} seeded samples" if box.samples else ""))
    left = (f"; {refined.unresolved} neighbour pairs still unresolved at the cap of {cap} added plants"
            if refined.unresolved else "")
    if passed:
        detail = (f"{total} sampled plants stable ({sampled}){left}; slowest pole Re = {res.abscissa[worst]:.4g} "
                  f"1/s at {where}; sampled, not proven for the continuum of the box")
    else:
        detail = f"{n_unstable} unstable and {n_undecided} undecided of {total} sampled plants ({sampled}); e.g. " + \
            "; ".join(f"({_where(box, res.theta[i])})" for i in bad[:3])
    cert: dict[str, Any] = {
        "box": box.describe(), "points_per_axis": box.points_per_axis, "lattice_plants": len(lattice),
        "refined_plants": refined.plants, "refinement_rounds": refined.rounds,
        "unresolved_pairs": refined.unresolved, "finest_unresolved_pairs": refined.finest,
        "refinement": {"resolved_fraction": RESOLVED_FRACTION, "min_width_fraction": MIN_WIDTH_FRACTION,
                       "cap": cap},
        "random_samples": box.samples, "seed": box.seed if box.samples else None, "plants": total,
        "stable": total - n_unstable - n_undecided, "unstable": n_unstable, "undecided": n_undecided,
        "worst_abscissa": {**dict(zip(box.names, map(float, res.theta[worst]), strict=True)),
                           "spectral_abscissa": float(res.abscissa[worst])},
        "failing_points": listed, "proof": "sampled: the lattice, its refinement and the samples only",
    }
    varying = [k for k, (lo, hi) in enumerate(zip(box.lo, box.hi, strict=True)) if lo != hi]
    if len(varying) in (1, 2):
        values = (-res.abscissa[: len(lattice)]).reshape(shape)
        axes = [{"name": box.names[k], "unit": box.units[k] if box.units else "", "values": box.axes[k].tolist()}
                for k in varying]
        cert["grid"] = {
            "axes": axes,
            "values": np.squeeze(values).T.tolist() if len(varying) == 2 else np.squeeze(values).tolist(),
            "label": "stability margin -max Re(pole) (1/s); > 0 is stable",
        }
    achieved = float(res.abscissa[worst]) if np.isfinite(res.abscissa[worst]) else None
    data: dict[str, Any] = {}
    if varying and res.A.ndim == 3 and res.A.shape[0] <= MAX_MIGRATION_PLANTS and np.all(np.isfinite(res.A)):
        data = {"poles": np.linalg.eigvals(res.A), "values": np.asarray(res.theta, float)[:, varying[0]],
                "theta": np.asarray(res.theta, float), "names": tuple(box.names),
                "parameter": box.names[varying[0]], "unit": box.units[varying[0]] if box.units else ""}
    return Check(
        name="robust_grid", passed=passed, data=data,
        target=f"stable at every sampled plant: the {box.points_per_axis}-point lattice refined until the margin "
               "is resolved between neighbours" + (f", and {box.samples} random samples" if box.samples else "")
               + " (sampled, not a proof)",
        achieved=achieved, margin=None if achieved is None else -achieved, unit="1/s", detail=detail,
        certificate=cert,
    )


def lyapunov_vertex_check(design: Any, box: Box, sweeper: Sweeper | None = None, *, eps: float = LMI_EPS,
                          solver: str = "CLARABEL") -> Check:
    """Check ``"common_lyapunov"`` (informational): one ``P`` for the corner closed loops."""
    sweeper = sweeper or Sweeper(design, box.names)
    res = sweeper.sweep(box.vertices)
    c = common_lyapunov(list(res.A), eps=eps, solver=solver)
    cert = dict(c.certificate)
    cert["vertices"] = [dict(zip(box.names, map(float, th), strict=True)) for th in res.theta]
    hull = set(getattr(design.plant, "hull_parameters", ()))
    covers = set(box.names) <= hull
    cert["covers_box"] = (
        f"yes: {design.plant.kind} plant, closed-loop A affine in coordinates that map the box onto the hull of its "
        "corners, so a common P proves quadratic stability of every plant in the box"
        if covers else "not claimed: A is not known to be affine in these parameters; the common P proves "
        "quadratic stability of the hull of the corner loops only")
    meaning = {
        True: (" -> quadratic stability over the whole box" if covers
               else " -> quadratic stability of the corners' hull"),
        False: "",
        None: " (corners stable; robust stability rests on the lattice check, not proven for the continuum)",
    }[c.passed]
    return replace(c, detail=c.detail + meaning + " [informational]", certificate=cert, required=False)


def robustness_checks(design: Any, uncertainty: Any, *, eps: float = LMI_EPS, solver: str = "CLARABEL",
                      plant: Any = None) -> tuple[Check, Check, Check]:
    """``robust_vertices``, ``robust_grid`` and ``common_lyapunov`` for a spec's ``plant.uncertainty`` (over the
    true ``plant``, default the design's)."""
    plant = design.plant if plant is None else plant
    box = box_from_uncertainty(plant, uncertainty)
    sweeper = Sweeper(design, box.names, plant)
    return (
        vertex_check(design, box, sweeper),
        grid_check(design, box, sweeper),
        lyapunov_vertex_check(design, box, sweeper, eps=eps, solver=solver),
    )
