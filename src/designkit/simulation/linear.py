"""Ideal (linear, continuous, noise-free) responses of a design's closed loop via python-control.

The closed loops of :mod:`designkit.synthesis.pid` have the inputs ``xD`` (and, for tracking,
``xDd``, ``xDdd``) and ``xi``, and the outputs ``(x1, u)``.  python-control is imported lazily.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.synthesis.design import Design
from designkit.synthesis.registry import family

_COLUMNS = {"xD": 0, "xDd": 1, "xDdd": 2}


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
    reference : ndarray, shape (N, 3)
        ``(xD, xD', xD'')`` (rad, rad/s, rad/s^2); columns the loop has no input for are ignored.
    perturbation : ndarray, shape (N,), optional
        ``xi`` (N*m); zero by default.
    plant : optional
        True plant (default ``design.plant``).

    Returns
    -------
    x1, u : ndarray, shape (N,)
        Position (rad) and control (N*m).  python-control interpolates the inputs linearly
        between samples (first-order hold), so a step in ``xi`` should fall on a sample.
    """
    import control

    loop = design.closed_loop if plant is None else family(design.kind).closed_loop(design, plant)
    time = np.asarray(time, float)
    reference = np.asarray(reference, float)
    xi = np.zeros_like(time) if perturbation is None else np.asarray(perturbation, float)
    u_in = np.vstack([xi if name == "xi" else reference[:, _COLUMNS[name]] for name in loop.inputs])
    resp = control.forced_response(loop.to_control(), T=time, U=u_in)
    y = np.atleast_2d(resp.outputs)
    return y[loop.outputs.index("x1")], y[loop.outputs.index("u")]


def linear_step(design: Design, duration: float, n: int = 501, *, amplitude: float = 1.0) -> tuple[np.ndarray, ...]:
    """Ideal response to a position step ``xD = amplitude`` (rad) over ``duration`` (s), ``n`` samples.

    For a tracking design the step enters ``xD`` only (``xD' = xD'' = 0``): the response of the
    PID feedback part to a position step, without feedforward.

    Returns
    -------
    t, x1, u : ndarray, shape (n,)
        Time (s), position (rad), control (N*m).

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> from designkit.synthesis.pid import design_servo
    >>> design = design_servo(LinkPlant(Km=2.0, tau=0.5), [-4, -5, -20], -3.0)
    >>> t, x1, u = linear_step(design, 5.0)
    >>> round(float(x1[-1]), 4), round(float(u[0]), 4)
    (1.0, 33.3333)
    """
    t = np.linspace(0.0, float(duration), int(n))
    ref = np.zeros((t.size, 3))
    ref[:, 0] = amplitude
    x1, u = linear_response(design, t, ref)
    return t, x1, u
