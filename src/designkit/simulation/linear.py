"""Ideal (linear, continuous, noise-free) responses of a design's closed loop.

A design's ``closed_loop`` has the reference signals (``3 n``: positions, velocities,
accelerations) and the plant's disturbances as inputs and the joint positions and plant inputs
as outputs (:mod:`designkit.synthesis.closed_loop`).

The response to sampled inputs is exact for inputs interpolated linearly between the samples
(first-order hold), as python-control's ``forced_response`` computes it (the tests compare the
two): over a step ``h`` with ``u(t_k + s) = u_k + (u_{k+1} - u_k) s / h``,

    x_{k+1} = Phi x_k + Gamma0 u_k + Gamma1 u_{k+1},

read off one matrix exponential (Van Loan's block form)::

    expm([[A h, B h, 0], [0, 0, I], [0, 0, 0]]) = [[Phi, G, Gamma1], [0, I, I], [0, 0, I]],

with ``G = int_0^h e^{A s} ds B`` the zero-order-hold input matrix, ``Gamma1 = (1/h) int_0^h
e^{A (h - s)} B s ds`` the ramp's share and ``Gamma0 = G - Gamma1``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.synthesis.design import Design

__all__ = ["forced_response", "linear_response", "linear_step"]


def forced_response(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, time: np.ndarray,
                    inputs: np.ndarray, x0: np.ndarray | None = None, *, held: Any = None) -> np.ndarray:
    """Outputs of ``x' = A x + B u, y = C x + D u`` from ``x0`` (zero by default) for inputs sampled at
    ``time`` and interpolated linearly between the samples (module docstring), or held (zero-order hold:
    ``u(t_k + s) = u_k``, so ``Gamma0 = G``, ``Gamma1 = 0``) for the inputs ``held`` marks.

    Parameters
    ----------
    A, B, C, D : ndarray
        State-space matrices (``B`` shape ``(n, m)``, ``C`` shape ``(p, n)``).
    time : ndarray, shape (N,)
        Increasing, evenly spaced instants (s).
    inputs : ndarray, shape (m, N)
        Input samples.
    x0 : ndarray, shape (n,), optional
        Initial state.
    held : array_like of bool, shape (m,), optional
        Inputs held over each interval (as the simulator holds a disturbance or a piecewise-constant
        reference) instead of interpolated.

    Returns
    -------
    ndarray, shape (p, N)
        Output samples.
    """
    import scipy.linalg

    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C, D))
    t = np.asarray(time, dtype=float)
    U = np.asarray(inputs, dtype=float).reshape(B.shape[1], t.size)
    n, m = B.shape
    X = np.zeros((t.size, n))
    X[0] = 0.0 if x0 is None else np.asarray(x0, dtype=float)
    if t.size > 1:
        h = float(t[1] - t[0])
        if not h > 0 or not np.allclose(np.diff(t), h, rtol=1e-9, atol=0.0):
            raise ValueError("time must be increasing and evenly spaced")
        M = np.zeros((n + 2 * m, n + 2 * m))
        M[:n, :n], M[:n, n:n + m], M[n:n + m, n + m:] = A * h, B * h, np.eye(m)
        E = scipy.linalg.expm(M)
        Phi, Gamma1 = E[:n, :n], E[:n, n + m:].copy()
        Gamma0 = E[:n, n:n + m] - Gamma1
        if held is not None:
            mask = np.asarray(held, dtype=bool).reshape(m)
            Gamma0[:, mask] += Gamma1[:, mask]
            Gamma1[:, mask] = 0.0
        W = U[:, :-1].T @ Gamma0.T + U[:, 1:].T @ Gamma1.T  # the input's share of each step
        PhiT, x = Phi.T, X[0]
        for k in range(t.size - 1):
            x = x @ PhiT + W[k]
            X[k + 1] = x
    return C @ X.T + D @ U


def linear_response(
    design: Design, time: np.ndarray, reference: np.ndarray, perturbation: np.ndarray | None = None,
    *, plant: Any | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Linear closed-loop response to sampled inputs (:func:`forced_response`).

    Parameters
    ----------
    design : Design
        The controller.
    time : ndarray, shape (N,)
        Increasing, evenly spaced instants (s).
    reference : ndarray, shape (N, n, 3) (or (N, 3) for one joint)
        ``(xD, xD', xD'')`` per joint (rad, rad/s, rad/s^2), about the operating point's reference.
    perturbation : ndarray, shape (N, nd) or (N,), optional
        The disturbances (N*m); zero by default.
    plant : Plant, optional
        True plant (default ``design.plant``): the design's law linearized on it.

    Returns
    -------
    positions : ndarray, shape (N, n)
        Joint positions (rad).
    u : ndarray, shape (N, nu)
        Plant inputs (N*m).  The inputs are interpolated linearly between samples (first-order
        hold), so a step in a disturbance should fall on a sample.
    """
    loop, point = design.closed_loop, design.operating_point
    if loop is None:
        raise ValueError(f"this {design.kind} design has no linear closed loop ({design.linearization.reason})")
    if plant is not None and plant is not design.plant:
        from designkit.synthesis.closed_loop import linearize

        op = design.operating_point
        loop, _, point = linearize(plant, design.linear_law, op["r"], z0=[*op["x"], *op["xc"]])
    n = len(design.plant.positions)
    time = np.asarray(time, float)
    ref = np.asarray(reference, float).reshape(time.size, n, 3)
    nd = len(loop.inputs) - 3 * n
    pert = np.zeros((time.size, nd)) if perturbation is None else np.asarray(perturbation, float).reshape(time.size, nd)
    r0 = np.asarray(point.get("r", np.zeros(3 * n)), dtype=float)
    u_in = np.hstack([ref.transpose(0, 2, 1).reshape(time.size, 3 * n) - r0[None, :], pert]).T
    y = np.atleast_2d(forced_response(loop.A, loop.B, loop.C, loop.D, time, u_in))
    x0 = np.asarray(point.get("x", np.zeros(len(design.plant.states))), dtype=float)
    positions = y[:n].T + x0[list(design.plant.positions)][None, :]
    u0 = np.asarray(point.get("u", np.zeros(y.shape[0] - n)), dtype=float)
    return positions, y[n:].T + u0[None, :]


def linear_step(design: Design, duration: float, n: int = 501, *, amplitude: Any = 1.0) -> tuple[np.ndarray, ...]:
    """Ideal response to a position step ``xD = amplitude`` (rad, per joint) over ``duration`` (s), ``n`` samples.

    For a tracking design the step enters ``xD`` only (``xD' = xD'' = 0``): the response of the
    PID feedback part to a position step, without feedforward.

    Returns
    -------
    t : ndarray, shape (n,)
        Time (s).
    positions : ndarray, shape (n, joints)
        Positions (rad).
    u : ndarray, shape (n, inputs)
        Controls (N*m).

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> from designkit.synthesis.servo_loop import servo_design
    >>> d = servo_design(LinkPlant(Km=2.0, tau=0.5), [-4, -5, -20], -3.0, kind="servo")
    >>> t, x1, u = linear_step(d, 5.0)
    >>> round(float(x1[-1, 0]), 4), round(float(u[0, 0]), 4)
    (1.0, 33.3333)
    """
    joints = len(design.plant.positions)
    t = np.linspace(0.0, float(duration), int(n))
    r0 = np.asarray(design.operating_point.get("r", np.zeros(3 * joints)), dtype=float)
    ref = np.zeros((t.size, joints, 3))
    ref[:, :, 0] = r0[:joints] + np.broadcast_to(np.asarray(amplitude, float), (joints,))
    positions, u = linear_response(design, t, ref)
    return t, positions, u
