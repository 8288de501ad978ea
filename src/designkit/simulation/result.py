"""The outcome of a closed-loop simulation, as a frozen value."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Sampled trajectories of one closed-loop simulation (SI units: s, rad, rad/s, N*m).

    Parameters
    ----------
    time : ndarray, shape (N,)
        Time instants (s).
    reference : ndarray, shape (N, 3)
        Desired position, speed and acceleration ``(xD, xD', xD'')``.
    state : ndarray, shape (N, n)
        Plant state (``x1`` position, ``x2`` speed, ...) as named by ``state_names``.
    controller_state : ndarray, shape (N, m)
        Internal state of the controller (e.g. the integral of the position error).
    u_command : ndarray, shape (N,) or (N, k)
        Control computed by the controller (before the nonlinear element).
    u_applied : ndarray
        Control reaching the plant (after nonlinear element, delay and hold).
    perturbation : ndarray
        Input-equivalent perturbation ``xi``.
    measured : ndarray, shape (N, n)
        Measurements fed to the controller (state plus noise).
    kind : str
        ``"step"`` or ``"trajectory"``.
    state_names, controller_state_names : tuple of str
        Column names.
    settings : Mapping
        Every option used (dt, integrator, nonlinearity, delay, sampling period, noise seed...),
        written into the report.
    """

    time: np.ndarray
    reference: np.ndarray
    state: np.ndarray
    controller_state: np.ndarray
    u_command: np.ndarray
    u_applied: np.ndarray
    perturbation: np.ndarray
    measured: np.ndarray
    kind: str
    state_names: tuple[str, ...] = ("x1", "x2")
    controller_state_names: tuple[str, ...] = ("x3",)
    settings: Mapping[str, Any] = field(default_factory=dict)

    @property
    def position(self) -> np.ndarray:
        """Link position ``x1`` (rad)."""
        return self.state[:, 0]

    @property
    def tracking_error(self) -> np.ndarray:
        """``x1 - xD`` (rad)."""
        return self.state[:, 0] - self.reference[:, 0]
