"""The requirement margins' gradients with respect to the tuned coordinates, through the simulated loop.

For a **smooth** loop (:func:`smooth_loop`: a continuous law without discrete memory, sampling, delay, quantisation,
learning trials or a switching element, on a smooth plant: the simulation's own :class:`~designkit.simulation.regime.
Regime` says so) the trajectory's sensitivity to the coordinates is propagated through the loop's CasADi step
(``sim_step: (z, w) -> (z_next, record)``, the classical RK4 step on the output grid, :mod:`designkit.simulation.step`)
by forward sensitivities::

    S_{k+1} = (d z_next / d z)(z_k, w_k) S_k + (d z_next / d theta)(z_k, w_k)
    R_k     = (d record / d z)(z_k, w_k) S_k + (d record / d theta)(z_k, w_k)

``d/dz`` is CasADi's exact derivative of the step (algorithmic differentiation of its SX graph), evaluated for every
step of the run by one rolled ``mapaccum``.  The design map ``theta -> law`` (pole placement, the family's numeric
synthesis) is not symbolic: ``d/dtheta`` of the step is the central difference of the step built with the laws
designed at ``theta ± h`` (:data:`H`), at the same ``(z, w)``, and the start's sensitivity ``S_0`` the central
difference of the law's rest state.

A requirement's margin is a function of the records (an overshoot is a maximum, a settling time the last exit from a
band, interpolated; a loop margin a function of the design): its derivative along coordinate ``j`` is the central
difference of the family's own checks (:func:`designkit.tuning.evaluate.margins_on`) on the records moved to first
order, ``record ± h R_j``, with the design at ``theta ± h``.  So one sensitivity run per point of the box replaces the
``2 n`` simulations of a finite-difference gradient; the margins themselves are those of the RK4 run on the grid.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["H", "Gradient", "gradients", "smooth_loop"]

H = 1e-4
"""Step of the central differences in the log coordinates (a relative change of 1e-4 of every tuned value)."""
COARSER = (10, 5, 4, 2)
"""Factors the sensitivity run's step may be of the run's own (the run's default step is 0.02 of the fastest time
constant, RK4 staying accurate up to 0.2 of it; ``simulation.dt`` given in the spec is kept)."""
MIN_STEPS = 1000
"""Fewest steps of the sensitivity run on a coarser grid."""


@dataclass(frozen=True)
class Gradient:
    """The requirement margins at one point of the tuning space and their gradients, per point of the box.

    Parameters
    ----------
    x : ndarray
        The log-space point.
    margins : tuple of dict
        Per box point (the nominal first, then ``Problem.points``): requirement -> its normalised margin on the run
        the sensitivities were propagated along.
    gradients : tuple of dict
        Per box point: requirement -> ``d margin / d x`` (one entry per coordinate).
    runs : int
        Sensitivity runs made (one per box point reached).
    failed : str
        Why the gradients could not be computed (a design refused, a loop diverged); ``""`` when they were.
    """

    x: np.ndarray
    margins: tuple[dict[str, float], ...]
    gradients: tuple[dict[str, np.ndarray], ...]
    runs: int
    failed: str = ""


def smooth_loop(problem: Any, design: Any) -> str:
    """Why the loop of ``design`` is not one the gradient path runs (``""`` when it is: smooth, see the module
    docstring); the loop is built on the nominal plant as the tuner runs it."""
    from designkit.errors import DesignkitError
    from designkit.simulation.run import build

    spec = problem.loaded.spec
    if design.learning is not None:
        return "the law learns over trials (its requirements are read after an update between trials)"
    if getattr(spec, "implementation", None) is not None:
        return "the spec's implementation section samples, quantises or delays the controller"
    if design.law is None:
        return "the design carries no law to simulate"
    try:
        sim = build(spec, design, plant=problem.plant)
    except DesignkitError as exc:
        return f"its loop cannot be built ({exc})"
    regime = sim.regime
    if regime is None or not regime.smooth:
        return regime.why if regime is not None and regime.why else "the loop is held per step"
    if regime.resets:
        return "the law's projection resets its states"
    if not sim.step.is_a("SXFunction"):
        return "CasADi does not expand the step into SX (a CVODES step or compiled C)"
    return ""


def _designs(problem: Any, space: Any, x: np.ndarray, plant: Any) -> list[tuple[Any, Any]]:
    """``(loaded, design)`` at ``x`` and, per coordinate, at its two sides (kept inside the box)."""
    from designkit.families import synthesize
    from designkit.runner.variants import changed_spec

    lo, hi = space.bounds
    points = [x]
    for j in range(x.size):
        up, down = x.copy(), x.copy()
        up[j], down[j] = min(x[j] + H, hi[j]), max(x[j] - H, lo[j])
        points += [up, down]
    out = []
    for p in points:
        loaded = changed_spec(problem.loaded, space.changes(p))
        out.append((loaded, synthesize(loaded.spec, plant)))
    return out


def _sensitivity_step(step: Any, sides: list[Any], widths: np.ndarray) -> Any:
    """``(z, vec S), w -> (z_next, vec S_next), (record, vec R)`` (module docstring); ``sides`` the steps with the
    laws at ``theta_j ± h``, in pairs."""
    import casadi as ca

    nz, nw, n = step.size1_in(0), step.size1_in(1), widths.size
    z, w, S = ca.SX.sym("z", nz), ca.SX.sym("w", nw), ca.SX.sym("S", nz, n)
    z1, rec = step(z, w)
    dz, dr = [], []
    for j in range(n):
        (zp, rp), (zm, rm) = sides[2 * j](z, w), sides[2 * j + 1](z, w)
        dz.append((zp - zm) / widths[j])
        dr.append((rp - rm) / widths[j])
    S1 = ca.jtimes(z1, z, S) + ca.horzcat(*dz)
    R = ca.jtimes(rec, z, S) + ca.horzcat(*dr)
    return ca.Function("sensitivity_step", [ca.vertcat(z, ca.vec(S)), w], [ca.vertcat(z1, ca.vec(S1)),
                                                                         ca.vertcat(rec, ca.vec(R))])


def _coarse(loaded: Any, design: Any, plant: Any) -> Any:
    """The loop built on a grid :data:`COARSER` times coarser than the run's (the first factor leaving at least
    :data:`MIN_STEPS` steps that the spec's timing accepts), else on the run's own grid."""
    from designkit.errors import SpecError
    from designkit.runner.variants import changed_spec
    from designkit.simulation.run import build

    sim = build(loaded.spec, design, plant=plant)
    if "dt" in loaded.spec.simulation.model_fields_set:
        return sim
    dt, steps = float(sim.time[1] - sim.time[0]), sim.time.size - 1
    for k in COARSER:
        if steps / k < MIN_STEPS:
            continue
        try:
            coarse = changed_spec(loaded, [("simulation.dt", dt * k)])
            return build(coarse.spec, design, plant=plant)
        except SpecError:
            continue
    return sim


def _start(spec: Any, design: Any, plant: Any) -> np.ndarray:
    """The law's rest state at the run's start (the controller part of ``z0``)."""
    from designkit.simulation.reference import reference_of
    from designkit.synthesis.closed_loop import rest_state

    ref = reference_of(spec, design)
    x0 = np.asarray(plant.rest_state(ref.start), dtype=float)
    return np.asarray(rest_state(plant, design.law, x0, ref.rest()).xc, dtype=float)


def _at_point(problem: Any, space: Any, x: np.ndarray, plant: Any, designs: list[tuple[Any, Any]]
              ) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    """Margins and their gradients on ``plant`` (module docstring)."""
    from designkit.simulation.integrate import run_steps
    from designkit.simulation.run import CHUNK
    from designkit.tuning.evaluate import DIVERGED, margins_on

    lo, hi = space.bounds
    n = x.size
    widths = np.array([min(x[j] + H, hi[j]) - max(x[j] - H, lo[j]) for j in range(n)])
    loaded0, design0 = designs[0]
    sim = _coarse(loaded0, design0, plant)
    sides = [sim.restep(d.law) for _, d in designs[1:]]
    if any(s.size1_in(0) != sim.step.size1_in(0) for s in sides):
        raise ValueError("the laws at the sides of the point have another state layout")
    nz, nx = sim.step.size1_in(0), len(plant.states)
    nc = design0.law.n_state
    S0 = np.zeros((nz, n))
    for j in range(n):
        S0[nx:nx + nc, j] = (_start(designs[1 + 2 * j][0].spec, designs[1 + 2 * j][1], plant)
                             - _start(designs[2 + 2 * j][0].spec, designs[2 + 2 * j][1], plant)) / widths[j]
    F = _sensitivity_step(sim.step, sides, widths)
    failure: dict[str, Any] = {}
    rec = run_steps(F, np.concatenate([sim.z0, S0.ravel(order="F")]), sim.inputs, chunk=CHUNK, failure=failure)
    nr = sim.step.size1_out(1)
    base, sens = rec[:nr], rec[nr:]
    names = problem.requirements
    if failure or not np.all(np.isfinite(rec)):
        return dict.fromkeys(names, DIVERGED), {r: np.zeros(n) for r in names}
    margins = margins_on(problem, loaded0.spec, design0, plant, sim.result(np.array(base)))
    grads = {r: np.zeros(n) for r in names}
    for j in range(n):
        R = sens[nr * j:nr * (j + 1)]
        up = min(x[j] + H, hi[j]) - x[j]
        down = x[j] - max(x[j] - H, lo[j])
        (lp, dp), (lm, dm) = designs[1 + 2 * j], designs[2 + 2 * j]
        mp = margins_on(problem, lp.spec, dp, plant, sim.result(base + up * R))
        mm = margins_on(problem, lm.spec, dm, plant, sim.result(base - down * R))
        for r in names:
            grads[r][j] = (mp[r] - mm[r]) / widths[j]
    return margins, grads


def gradients(problem: Any, space: Any, x: np.ndarray) -> Gradient:
    """The requirement margins at ``x`` and their gradients at every point of the box (module docstring); never
    raises for values the family refuses or a run that cannot be made: ``failed`` says why, and the points not
    reached have the evaluation's score for it (:data:`~designkit.tuning.evaluate.REFUSED`, ``NOT_RUN``) with a zero
    gradient, so that every call gives as many margins."""
    from designkit.errors import DesignkitError
    from designkit.tuning.evaluate import NOT_RUN, REFUSED

    x = np.clip(np.asarray(x, dtype=float), *space.bounds)
    points = ({}, *problem.points)
    margins: list[dict[str, float]] = []
    grads: list[dict[str, np.ndarray]] = []
    failed, low = "", 0.0
    try:
        nominal = _designs(problem, space, x, problem.plant)
        for point in points:
            plant = problem.plant.with_params(**point) if point else problem.plant
            designs = _designs(problem, space, x, plant) if point and problem.each else nominal
            m, g = _at_point(problem, space, x, plant, designs)
            margins.append(m)
            grads.append(g)
    except DesignkitError as exc:
        failed, low = f"refused: {exc}", REFUSED
    except Exception as exc:  # noqa: BLE001 -- a run that cannot be made is that point's outcome, with its reason
        failed, low = f"not run: {type(exc).__name__}: {exc}", NOT_RUN
    runs = len(margins)
    for _ in points[runs:]:
        margins.append(dict.fromkeys(problem.requirements, low))
        grads.append({r: np.zeros(x.size) for r in problem.requirements})
    return Gradient(x, tuple(margins), tuple(grads), runs, failed)
