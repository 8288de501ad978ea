"""Integration schemes and the CasADi ``mapaccum`` runner.

* :func:`rk4`: one classical Runge-Kutta 4 step of ``s' = rhs(s, a)`` on CasADi expressions, with
  the time-varying arguments at the step's start, middle and end;
* :func:`variable_step`: one step of CasADi's variable-step BDF integrator (CVODES) on the same
  right-hand side, the time-varying arguments interpolated quadratically through the same three
  values (third-order accurate in the reference, whatever steps CVODES takes inside), for stiff
  plants such as the elastic joint;
* :func:`plant_step`: one RK4 step of a plant's ODE with its inputs held (tests, benchmarks).

:func:`run_steps` evaluates a one-step Function ``(z, w) -> (z_next, record)`` over ``N`` steps
without a Python loop per step: one ``Function.mapaccum`` over ``chunk`` steps, evaluated chunk
after chunk through CasADi's zero-copy buffer interface; only the per-step records are kept.
A step that raises (CVODES giving up on a diverging or too stiff loop) can end the run instead
of the program: the records from that step on are NaN and the failure is reported.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import casadi as ca
import numpy as np

DIVERGED = 1e150
"""A CVODES step starting from a state or held value beyond this magnitude returns NaN (a diverged loop)."""


def rk4(rhs: Callable[[Any, Any], Any], s: Any, dt: float, stages: Sequence[Any]) -> Any:
    """One classical Runge-Kutta 4 step of ``s' = rhs(s, a)``.

    Parameters
    ----------
    rhs : callable
        ``(s, a) -> s_dot`` on CasADi expressions (or NumPy arrays).
    s : casadi.SX or ndarray
        State at the step's start.
    dt : float
        Step (s).
    stages : sequence of 3
        Time-varying arguments ``a`` at the step's start, middle and end (``t``, ``t + dt/2``,
        ``t + dt``).

    Returns
    -------
    casadi.SX or ndarray
        State at ``t + dt`` (local error ``O(dt^5)`` for a smooth right-hand side).
    """
    a0, am, a1 = stages
    k1 = rhs(s, a0)
    k2 = rhs(s + 0.5 * dt * k1, am)
    k3 = rhs(s + 0.5 * dt * k2, am)
    k4 = rhs(s + dt * k3, a1)
    return s + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def plant_step(plant: Any, dt: float) -> ca.Function:
    """``plant_rk4: (x, u, d) -> x_next``: one RK4 step of ``plant``'s ODE (nominal parameters), inputs held."""
    ode = plant.ode_at()
    x, u, d = (ca.SX.sym(k, ode.size1_in(i)) for i, k in enumerate(("x", "u", "d")))
    x_next = rk4(lambda s, a: ode(s, u, d), x, dt, (None, None, None))
    return ca.Function("plant_rk4", [x, u, d], [x_next], ["x", "u", "d"], ["x_next"])


def variable_step(rhs: ca.Function, s: ca.MX, dt: float, stages: Sequence[ca.MX], held: ca.MX,
                  *, rtol: float, atol: float) -> ca.MX:
    """One CVODES step of ``s' = rhs(s, a(t), held)`` over ``[0, dt]``, as an expression of ``s`` and ``held``.

    Parameters
    ----------
    rhs : casadi.Function
        ``(s, a, h) -> s_dot``: ``a`` the time-varying argument (the reference), ``h`` everything
        held over the step.
    s : casadi.MX
        State at the step's start.
    dt : float
        Step (s).
    stages : sequence of 3 MX
        ``a`` at ``0, dt/2, dt``; inside the step ``a`` is the quadratic through them.
    held : casadi.MX
        The held values.
    rtol, atol : float
        CVODES tolerances.

    Returns
    -------
    casadi.MX
        State at ``t + dt``; NaN when the state or the held values at the step's start are not
        finite or sum beyond :data:`DIVERGED` in magnitude (a diverged loop: CVODES is not called,
        so it cannot fail on an overflowing right-hand side, and the NaN marks the run as diverged).
    """
    a0, am, a1 = stages
    na, nh = rhs.size1_in(1), rhs.size1_in(2)
    tau, xs = ca.SX.sym("tau"), ca.SX.sym("s", rhs.size1_in(0))
    A0, Am, A1, H = ca.SX.sym("a0", na), ca.SX.sym("am", na), ca.SX.sym("a1", na), ca.SX.sym("h", nh)
    h = 0.5 * dt
    a_t = ((tau - h) * (tau - 2 * h) / (2 * h * h)) * A0 - (tau * (tau - 2 * h) / (h * h)) * Am \
        + (tau * (tau - h) / (2 * h * h)) * A1
    dae = {"x": xs, "p": ca.vertcat(A0, Am, A1, H), "t": tau, "ode": rhs(xs, a_t, H)}
    opts = {"reltol": rtol, "abstol": atol, "max_num_steps": 100_000}
    opts.update(show_eval_warnings=False, disable_internal_warnings=True)
    integrator = ca.integrator("cvodes_step", "cvodes", dae, 0.0, dt, opts)
    start = ca.vertcat(s, held)
    finite = ca.sum1(ca.fabs(start)) < DIVERGED  # False for NaN and inf (a sum propagates NaN; fmax drops it)
    nan = ca.DM(np.full(rhs.size1_in(0), np.nan))
    return ca.if_else(finite, integrator(x0=s, p=ca.vertcat(a0, am, a1, held))["xf"], nan, True)


def flat_inputs(inputs: np.ndarray, m: int) -> np.ndarray:
    """The columns of ``inputs`` ``(nw, N)`` padded to whole chunks of ``m`` steps (the last column repeated; the
    extra steps are discarded) and laid out step after step, as :func:`run_steps` hands them to ``mapaccum``."""
    nw, n = inputs.shape
    n_chunks = -(-n // m)
    padded = np.concatenate([inputs, np.repeat(inputs[:, -1:], n_chunks * m - n, axis=1)], axis=1)
    return np.ascontiguousarray(padded.T).ravel()  # column-major: each chunk is contiguous


def run_steps(step: ca.Function, z0: np.ndarray, inputs: np.ndarray, *, chunk: int = 200,
              accumulated: ca.Function | None = None, failure: dict[str, Any] | None = None,
              flat: np.ndarray | None = None) -> np.ndarray:
    """Run ``step: (z, w) -> (z_next, record)`` over the columns of ``inputs``.

    ``step.mapaccum(chunk)`` is built once and evaluated chunk after chunk through CasADi's
    zero-copy buffer interface, the last state of a chunk starting the next; there is no Python
    loop per step.  (Measured with CasADi 3.8: building one ``mapaccum`` over all the steps costs
    5 ms for 4,000 steps but 0.1 s for 10,000 and 2.5 s for 100,000, while evaluating costs well
    under 1 us per step; chunks keep the construction cost constant and the memory bounded by
    the records, not by the augmented state, which holds the delay line.)

    Parameters
    ----------
    step : casadi.Function
        One integration step; ``z`` the augmented state, ``w`` the per-step inputs.
    z0 : ndarray, shape (nz,)
        Augmented state at ``t = 0``.
    inputs : ndarray, shape (nw, N)
        Per-step inputs, one column per step.
    chunk : int
        Steps per ``mapaccum`` evaluation.
    accumulated : casadi.Function, optional
        A ready ``mapaccum`` of ``step`` (e.g. compiled to C); its number of steps replaces ``chunk``.
    flat : ndarray, optional
        ``flat_inputs(inputs, m)`` computed before (a simulator's own inputs, run again), ``m`` the steps per
        evaluation.
    failure : dict, optional
        When given, a chunk whose evaluation raises (e.g. ``CV_TOO_MUCH_WORK`` from CVODES) is
        re-run step by step; the records from the failing step on are NaN, and ``failure`` receives
        ``step`` (its index) and ``error`` (the solver's last message line).  Without it the error
        propagates.

    Returns
    -------
    ndarray, shape (nrec, N)
        The ``record`` output of every step (the augmented state itself is not kept).
    """
    nw, n = inputs.shape
    nz, nrec = step.size1_in(0), step.size1_out(1)
    m = accumulated.size2_in(1) if accumulated is not None else max(1, min(chunk, n))
    n_chunks = -(-n // m)
    w_flat = flat_inputs(inputs, m) if flat is None else flat
    records = np.empty((n_chunks, m * nrec))
    acc = accumulated if accumulated is not None else step.mapaccum(f"{step.name()}_acc", m)
    buf, evaluate = acc.buffer()
    z = np.array(z0, dtype=float)
    z_out = np.empty(nz * m)
    for j in range(n_chunks):
        buf.set_arg(0, memoryview(z))
        buf.set_arg(1, memoryview(w_flat[j * m * nw:(j + 1) * m * nw]))
        buf.set_res(0, memoryview(z_out))
        buf.set_res(1, memoryview(records[j]))
        try:
            evaluate()
        except RuntimeError as exc:
            if failure is None:
                raise
            block = w_flat[j * m * nw:(j + 1) * m * nw].reshape(m, nw).T
            k, z = _step_by_step(step, z, block, records[j].reshape(m, nrec))
            if k == m:  # every step of the chunk went through on its own
                continue
            records[j].reshape(m, nrec)[k:] = np.nan
            records[j + 1:] = np.nan
            lines = [line.strip() for line in str(exc).strip().splitlines() if line.strip()]
            failure.update(step=j * m + k, error=lines[-1] if lines else type(exc).__name__)
            break
        z = z_out[-nz:].copy()
    return records.reshape(n_chunks * m, nrec)[:n].T


def _step_by_step(step: ca.Function, z: np.ndarray, inputs: np.ndarray, out: np.ndarray) -> tuple[int, np.ndarray]:
    """Run ``step`` over the columns of ``inputs`` from ``z``, writing each record into the rows of ``out``;
    return the number of steps done before one raised (all of them if none did) and the state reached."""
    for k in range(inputs.shape[1]):
        try:
            z_next, record = step(z, inputs[:, k])
        except RuntimeError:
            return k, z
        out[k] = np.asarray(record, dtype=float).ravel()
        z = np.asarray(z_next, dtype=float).ravel()
    return inputs.shape[1], z
