"""Ideal (linear, continuous, noise-free) responses of a design's closed loop via python-control.

A design's ``closed_loop`` has the reference signals (``3 n``: positions, velocities,
accelerations) and the plant's disturbances as inputs and the joint positions and plant inputs
as outputs (:mod:`designkit.synthesis.closed_loop`).  python-control is imported lazily.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.synthesis.design import Design

__all__ = ["linear_response", "linear_step"]


def linear_response(
    design: Design, time: np.ndarray, reference: np.ndarray, perturbation: np.ndarray | None = None,
    *, plant: Any | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Linear closed-loop response to sampled inputs (``control.forced_response``).

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
        Plant inputs (N*m).  python-control interpolates the inputs linearly between samples
        (first-order hold), so a step in a disturbance should fall on a sample.
    """
    import control

    loop, point = design.closed_loop, design.operating_point
    if plant is not None and plant is not design.plant:
        from designkit.families import family
        from designkit.synthesis.closed_loop import linearize

        op = design.operating_point
        loop, _, point = linearize(plant, family(design.kind).law(design, None), op["r"], z0=[*op["x"], *op["xc"]])
    n = len(design.plant.positions)
    time = np.asarray(time, float)
    ref = np.asarray(reference, float).reshape(time.size, n, 3)
    nd = len(loop.inputs) - 3 * n
    pert = np.zeros((time.size, nd)) if perturbation is None else np.asarray(perturbation, float).reshape(time.size, nd)
    r0 = np.asarray(point.get("r", np.zeros(3 * n)), dtype=float)
    u_in = np.hstack([ref.transpose(0, 2, 1).reshape(time.size, 3 * n) - r0[None, :], pert]).T
    resp = control.forced_response(loop.to_control(), T=time, U=u_in)
    y = np.atleast_2d(resp.outputs)
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
    >>> from designkit.families.pid_servo import design
    >>> d = design(LinkPlant(Km=2.0, tau=0.5), [-4, -5, -20], -3.0)
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
