"""The plant composed with a control law, its equilibria, and its linearization.

The continuous loop (no nonlinear element, no sampling, anti-windup gates open, memory at its
initial value) is one CasADi function of the augmented state ``z = (x, xc)``::

    loop: (z, r, d, p) -> (z_dot, u),   z_dot = (f(x, u, d, p), law.derivative(x, xc, m0, r, 1)),
                                         u = law.command(x, xc, m0, r)

An operating point is an equilibrium ``z*`` of ``z_dot = 0`` for a constant reference ``r0``,
found by Newton's method from a guess (the reference position at rest): with integral action
the positions settle on the reference and the integrals absorb constant loads such as gravity,
so ``z*`` depends on the plant parameters.  :func:`equilibria` runs the Newton iteration on a
whole batch of parameter vectors at once (a loop over iterations, never over plants).

At ``z*`` the Jacobians give the linear closed loop (:func:`linearize`): inputs the reference
signals and the disturbances, outputs the joint positions and the plant inputs -- exactly the
python-control interconnection of the linearized plant with the law, which the tests check.

Where a run starts (:func:`rest_state`): the plant at rest at its initial position, the controller
states a law names in ``rest_start`` solved so that the whole loop is at rest at the reference
before the motion (Gauss--Newton on ``z_dot = 0`` in those states only), the others at the law's
``initial_state``.  That makes the simulated loop the designed one wherever the arm starts.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit.models.linear_system import LinearSystem
from designkit.synthesis.design import Design
from designkit.synthesis.law import Law
from designkit.synthesis.linearization import EXACT, Linearization

__all__ = ["Equilibria", "LoopFunctions", "RestState", "equilibria", "linearize", "loop_functions", "reference_names",
           "rest_state", "with_closed_loop", "with_law"]

BATCH = 4096
"""Largest block of plants evaluated by one mapped CasADi call."""
NEWTON_ITERATIONS = 40
"""Most Newton steps of the equilibrium search."""
NEWTON_TOL = 1e-12
"""Converged when ``|z_dot|`` is below this, scaled by ``1 + |z|`` (per component, 1/s)."""


def reference_names(n: int) -> tuple[str, ...]:
    """Names of the ``3 n`` reference signals: ``xD, xDd, xDdd`` (one joint) or ``xD1.. xDd1.. xDdd1..``."""
    if n == 1:
        return ("xD", "xDd", "xDdd")
    return tuple(f"{base}{j}" for base in ("xD", "xDd", "xDdd") for j in range(1, n + 1))


@dataclass(frozen=True)
class LoopFunctions:
    """The loop's CasADi functions (see the module docstring).

    Parameters
    ----------
    loop : casadi.Function
        ``(z, r, d, p) -> (z_dot, u)``.
    jacobians : casadi.Function
        ``(z, r, d, p) -> (z_dot, dz_dot/dz, dz_dot/d(r, d), du/dz, du/d(r, d), B_u)`` with ``B_u`` the
        Jacobian of ``z_dot`` in the plant input at fixed controller (where the control enters).
    n_state, n_controller, n_joints : int
    """

    loop: ca.Function
    jacobians: ca.Function
    n_state: int
    n_controller: int
    n_joints: int
    _maps: dict = field(default_factory=dict, repr=False, compare=False)

    def evaluate(self, z: np.ndarray, r0: np.ndarray, d0: np.ndarray, P: np.ndarray) -> list[np.ndarray]:
        """``jacobians`` at every row of ``z`` and ``P`` (and of ``r0`` when it is 2-D; ``d0`` constant), as
        arrays ``(N, rows, cols)``.

        Evaluated by ``map`` over blocks of at most :data:`BATCH` rows (the mapped function is built once per
        block size and cached), so the cost of building it does not grow with the batch.
        """
        N = P.shape[0]
        m = min(N, BATCH)
        if m not in self._maps:
            fn = self.jacobians if m == 1 else self.jacobians.map(m)
            self._maps[m] = (fn, *fn.buffer())
        fn, buf, call = self._maps[m]
        r_rows = np.asarray(r0, dtype=float)
        if r_rows.ndim == 1:  # map repeats every input
            r_rows = np.tile(r_rows.ravel(), (N, 1))
        d0 = np.ascontiguousarray(np.tile(np.asarray(d0, dtype=float).ravel(), m))
        sizes = [self.jacobians.size_out(i) for i in range(self.jacobians.n_out())]
        out = [np.empty((N, rows, cols)) for rows, cols in sizes]
        res = [np.empty(rows * cols * m) for rows, cols in sizes]
        for start in range(0, N, m):
            zb, Pb, rb = z[start:start + m], P[start:start + m], r_rows[start:start + m]
            k = zb.shape[0]
            if k < m:  # pad the last block
                zb = np.vstack([zb, np.repeat(zb[-1:], m - k, axis=0)])
                Pb = np.vstack([Pb, np.repeat(Pb[-1:], m - k, axis=0)])
                rb = np.vstack([rb, np.repeat(rb[-1:], m - k, axis=0)])
            # CasADi is column-major: a (rows, m) input is the (m, rows) C-ordered array
            zc, Pc = np.ascontiguousarray(zb, dtype=float), np.ascontiguousarray(Pb, dtype=float)
            rc = np.ascontiguousarray(rb, dtype=float)
            for i, arr in enumerate((zc, rc, d0, Pc)):
                buf.set_arg(i, memoryview(arr))
            for i, arr in enumerate(res):
                buf.set_res(i, memoryview(arr))
            call()
            for i, (rows, cols) in enumerate(sizes):
                # output i is (rows, cols * m) column-major: block j's column c is column j * cols + c
                out[i][start:start + k] = res[i].reshape(m, cols, rows).transpose(0, 2, 1)[:k]
        return out


def loop_functions(plant: Any, law: Law) -> LoopFunctions:
    """Compose ``plant`` (its symbolic ODE) with ``law``."""
    f = plant.ode()
    nx, nc, n = len(plant.states), law.n_state, len(plant.positions)
    nu, nd, npar = len(plant.inputs), len(plant.disturbances), len(plant.parameters)
    z, r, d, p = ca.SX.sym("z", nx + nc), ca.SX.sym("r", 3 * n), ca.SX.sym("d", nd), ca.SX.sym("p", npar)
    v = ca.SX.sym("v", nu)  # the plant input as a free variable, for B_u
    x, xc = z[:nx], z[nx:]
    m0 = ca.DM(list(law.initial_memory)) if law.n_memory else ca.DM.zeros(0, 1)
    u = law.command(x, xc, m0, r)
    ones = ca.DM.ones(nc, 1)
    xc_dot = law.derivative(x, xc, m0, r, ones)
    z_dot = ca.vertcat(f(x, u, d, p), xc_dot)
    z_dot_v = ca.vertcat(f(x, v, d, p), xc_dot)
    B_u = ca.substitute(ca.jacobian(z_dot_v, v), v, u)
    rd = ca.vertcat(r, d)
    loop = ca.Function("closed_loop", [z, r, d, p], [z_dot, u], ["z", "r", "d", "p"], ["z_dot", "u"])
    jac = ca.Function(
        "closed_loop_jacobians", [z, r, d, p],
        [ca.densify(m) for m in (z_dot, ca.jacobian(z_dot, z), ca.jacobian(z_dot, rd), ca.jacobian(u, z),
                                 ca.jacobian(u, rd), B_u)],  # dense: evaluated through NumPy buffers
        ["z", "r", "d", "p"], ["z_dot", "A", "B", "Cu", "Du", "B_u"],
    )
    return LoopFunctions(loop, jac, nx, nc, n)


@dataclass(frozen=True)
class Equilibria:
    """Equilibria of a batch of loops.

    Parameters
    ----------
    z : ndarray, shape (N, nz)
        The equilibrium states.
    residual : ndarray, shape (N,)
        ``max |z_dot| / (1 + max |z|)`` at ``z`` (1/s).
    converged : ndarray of bool, shape (N,)
        Residual below :data:`NEWTON_TOL` (a singular Jacobian or divergence leaves it False).
    iterations : int
        Newton steps taken.
    """

    z: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    iterations: int


def _reshape(block: np.ndarray, rows: int, cols: int, n: int) -> np.ndarray:
    """``(rows, cols * n)`` as returned by ``Function.map`` -> ``(n, rows, cols)``."""
    return np.asarray(block, dtype=float).reshape(rows, n, cols).transpose(1, 0, 2)


def equilibria(fns: LoopFunctions, z0: np.ndarray, r0: np.ndarray, P: np.ndarray,
               d0: np.ndarray | None = None) -> Equilibria:
    """Newton's method on ``z_dot(z, r0, d0, p) = 0`` for every row ``p`` of ``P`` at once.

    Parameters
    ----------
    fns : LoopFunctions
    z0 : ndarray, shape (nz,)
        Starting guess (the same for every plant).
    r0 : ndarray, shape (3 n,)
        Constant reference.
    P : ndarray, shape (N, n_par)
        Parameter vectors.
    d0 : ndarray, optional
        Constant disturbance (default zero).
    """
    P = np.atleast_2d(np.asarray(P, dtype=float))
    N, nz = P.shape[0], fns.n_state + fns.n_controller
    nd = fns.jacobians.size1_in(2)
    d0 = np.zeros(nd) if d0 is None else np.asarray(d0, dtype=float)
    z = np.tile(np.asarray(z0, dtype=float).reshape(1, nz), (N, 1))
    residual = np.full(N, np.inf)
    active = np.ones(N, dtype=bool)
    it = 0
    for step_count in range(1, NEWTON_ITERATIONS + 1):  # iterations, not plants
        it = step_count
        out = fns.evaluate(z, r0, d0, P)
        f, J = out[0][:, :, 0], out[1]
        residual = np.max(np.abs(f), axis=1) / (1.0 + np.max(np.abs(z), axis=1))
        active = residual > NEWTON_TOL
        if not np.any(active):
            break
        with np.errstate(all="ignore"):
            try:
                step = np.linalg.solve(J[active], f[active][..., None])[..., 0]
            except np.linalg.LinAlgError:  # some Jacobian singular: solve one by one, leave those alone
                step = np.stack([_safe_solve(Jk, fk) for Jk, fk in zip(J[active], f[active], strict=True)])
        z[active] = z[active] - step
        bad = ~np.all(np.isfinite(z), axis=1)
        z[bad] = np.nan
    finite = np.all(np.isfinite(z), axis=1)
    return Equilibria(z=z, residual=residual, converged=(residual <= NEWTON_TOL) & finite, iterations=it)


def _safe_solve(J: np.ndarray, f: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.solve(J, f)
    except np.linalg.LinAlgError:
        return np.full_like(f, np.nan)


def state_matrices(fns: LoopFunctions, z: np.ndarray, r0: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Closed-loop ``A = dz_dot/dz`` at each row of ``z`` and ``P``: shape ``(N, nz, nz)``."""
    P = np.atleast_2d(np.asarray(P, dtype=float))
    nd = fns.jacobians.size1_in(2)
    return fns.evaluate(np.nan_to_num(z), r0, np.zeros(nd), P)[1]


def linearize(plant: Any, law: Law, r0: Any, *, z0: Any = None) -> tuple[LinearSystem, LinearSystem, dict]:
    """The closed loop of ``plant`` and ``law`` linearized at its equilibrium for the reference ``r0``.

    Parameters
    ----------
    plant : Plant
        Nominal plant.
    law : Law
    r0 : array_like, shape (3 n,)
        Constant reference (positions, zero velocity and acceleration for an equilibrium).
    z0 : array_like, optional
        Newton's starting guess (default: positions at ``r0``, everything else zero).

    Returns
    -------
    closed_loop, input_loop : LinearSystem
        See :class:`~designkit.synthesis.design.Design`.
    operating_point : dict
        ``x``, ``xc``, ``r``, ``u`` (lists: the equilibrium, its reference and plant input) and the
        Newton ``residual``.

    Raises
    ------
    ValueError
        When no equilibrium is found (a singular loop Jacobian: the closed loop has a pole at 0).
    """
    fns = loop_functions(plant, law)
    nx, nc, n = fns.n_state, fns.n_controller, fns.n_joints
    r0 = np.asarray(r0, dtype=float).reshape(3 * n)
    if z0 is None:
        z0 = np.concatenate([np.zeros(nx), np.asarray(law.initial_state, dtype=float)])
        z0[list(plant.positions)] = r0[:n]
    eq = equilibria(fns, np.asarray(z0, dtype=float), r0, np.asarray(plant.parameter_vector)[None, :])
    if not bool(eq.converged[0]):
        raise ValueError(f"no equilibrium of the closed loop found (residual {eq.residual[0]:.3g})")
    z = eq.z[0]
    nd = len(plant.disturbances)
    z_dot, A, B, Cu, Du, B_u = (np.asarray(m, dtype=float) for m in
                                fns.jacobians(z, r0, np.zeros(nd), plant.parameter_vector))
    states = tuple(s.name for s in plant.states) + tuple(law.state_names)
    inputs = reference_names(n) + tuple(s.name for s in plant.disturbances)
    pos_names = tuple(plant.states[i].name for i in plant.positions)
    u_names = tuple(s.name for s in plant.inputs)
    C_pos = np.zeros((n, nx + nc))
    C_pos[np.arange(n), list(plant.positions)] = 1.0
    closed = LinearSystem(
        A=A, B=B, C=np.vstack([C_pos, Cu]), D=np.vstack([np.zeros((n, B.shape[1])), Du]),
        states=states, inputs=inputs, outputs=pos_names + u_names,
    )
    input_loop = LinearSystem(A=A, B=B_u, C=-Cu, D=np.zeros((Cu.shape[0], B_u.shape[1])), states=states,
                              inputs=u_names, outputs=tuple(f"-{u}" for u in u_names))
    u0 = np.asarray(fns.loop(z, r0, np.zeros(nd), plant.parameter_vector)[1], dtype=float).reshape(-1)
    point = {"x": z[:nx].tolist(), "xc": z[nx:].tolist(), "r": r0.tolist(), "u": u0.tolist(),
             "residual": float(eq.residual[0])}
    return closed, input_loop, point


def with_closed_loop(design: Design, law: Law, r0: Any, *, z0: Any = None, field: str = "controller",
                     hint: str = "", linearization: Linearization = EXACT) -> Design:
    """``design`` with its ``law``, ``linearization`` and the ``closed_loop``, ``input_loop`` and
    ``operating_point`` of :func:`linearize` (``z0``: Newton's starting guess, see there).

    With a ``frozen`` linearization the loop linearized is ``linearization.freeze(linearization.initial)``
    (the law with its adaptation held at the initial values), and ``law`` is stored as given.

    Raises
    ------
    SpecError
        On ``field`` (the spec key that sets the operating point), followed by ``hint``, when the
        closed loop has no equilibrium there: nothing can be linearized or certified.
    ValueError
        ``linearization`` is ``none`` (use :func:`with_law`).
    """
    from designkit.errors import SpecError

    if not linearization.linear:
        raise ValueError("a design without a linearization has no closed loop: use with_law")
    linear = law if linearization.kind == "exact" else linearization.freeze(linearization.initial)
    try:
        closed, input_loop, point = linearize(design.plant, linear, r0, z0=z0)
    except ValueError as exc:
        raise SpecError(field, f"{exc} at the operating point: the control law is not defined there or the "
                               f"closed loop has a pole at 0{hint}") from None
    return dataclasses.replace(design, closed_loop=closed, input_loop=input_loop, operating_point=point, law=law,
                               linearization=linearization)


def with_law(design: Design, law: Law, linearization: Linearization = EXACT) -> Design:
    """``design`` with its ``law`` and ``linearization`` and no linear loop (a switching law: ``none``)."""
    return dataclasses.replace(design, law=law, linearization=linearization)


@dataclass(frozen=True)
class RestState:
    """Where a run of ``plant`` under a law starts (module docstring).

    Parameters
    ----------
    xc : ndarray
        The controller's initial state.
    residual : float
        ``max |z_dot|`` there (1/s in state units): 0 when the loop starts at rest.
    at_rest : bool
        ``residual`` below :data:`REST_TOL` scaled by the state's size.
    solved : tuple of str
        The states solved for (the law's ``rest_start``).
    """

    xc: np.ndarray
    residual: float
    at_rest: bool
    solved: tuple[str, ...] = ()


REST_TOL = 1e-9
"""The loop starts at rest when ``max |z_dot| <= REST_TOL (1 + max |z|)``."""


def rest_state(plant: Any, law: Law, x0: Any, r0: Any, *, parameters: Any = None) -> RestState:
    """The controller state that starts the loop at rest with the plant state ``x0`` and reference ``r0``.

    The states in ``law.rest_start`` are found by Gauss--Newton on ``z_dot(x0, xc, r0) = 0`` (the plant
    state is not moved: the arm starts where the spec puts it), the others are ``law.initial_state``.

    Parameters
    ----------
    plant : Plant
        The simulated plant.
    law : Law
    x0 : array_like
        The plant's initial state (at rest).
    r0 : array_like, shape (3 n,)
        The reference before the motion (positions, zero velocity and acceleration).
    parameters : array_like, optional
        Plant parameter vector (default the plant's).

    Returns
    -------
    RestState
    """
    x0 = np.asarray(x0, dtype=float).ravel()
    xc = np.asarray(law.initial_state, dtype=float).copy()
    idx = list(law.rest_indices())
    fns = loop_functions(plant, law)
    nx = fns.n_state
    p = np.asarray(plant.parameter_vector if parameters is None else parameters, dtype=float)
    r0 = np.asarray(r0, dtype=float).ravel()
    d0 = np.zeros(len(plant.disturbances))

    def evaluate(xc_now: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z_dot, A = (np.asarray(m, dtype=float) for m in fns.jacobians(np.concatenate([x0, xc_now]), r0, d0, p)[:2])
        return z_dot.ravel(), A[:, [nx + i for i in idx]]

    f, J = evaluate(xc)
    for _ in range(NEWTON_ITERATIONS if idx else 0):
        step, *_ = np.linalg.lstsq(J, f, rcond=None)
        xc[idx] -= step
        f, J = evaluate(xc)
        if not np.all(np.isfinite(f)) or np.max(np.abs(step)) <= 1e-15 * (1 + np.max(np.abs(xc))):
            break
    residual = float(np.max(np.abs(f))) if f.size else 0.0
    scale = 1.0 + float(np.max(np.abs(np.concatenate([x0, xc])))) if xc.size or x0.size else 1.0
    return RestState(xc=xc, residual=residual, at_rest=bool(np.isfinite(residual) and residual <= REST_TOL * scale),
                     solved=tuple(law.rest_start))
