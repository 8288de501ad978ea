"""The outcome of a closed-loop simulation, as a frozen value."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.synthesis.design import freeze

__all__ = ["SimulationResult"]


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Sampled trajectories of one closed-loop simulation (SI units: s, rad, rad/s, N*m).

    Every array is read-only; rows are the instants ``time``.

    Parameters
    ----------
    time : ndarray, shape (N,)
        Time instants (s).
    reference : ndarray, shape (N, n, 3)
        Desired position, velocity and acceleration of each of the ``n`` joints.
    state : ndarray, shape (N, nx)
        Plant state, columns named by ``state_names``.
    controller_state : ndarray, shape (N, nc)
        Continuous controller state (e.g. the integrals of the position errors).
    u_command : ndarray, shape (N, nu)
        Controls computed by the controller (before the nonlinear element).
    u_applied : ndarray, shape (N, nu)
        Controls reaching the plant (after nonlinear element, delay and hold).
    perturbation : ndarray, shape (N, nd)
        The plant's disturbances (input-equivalent perturbation ``xi``, load torques).
    measured : ndarray, shape (N, nx)
        Measurements fed to the controller (state plus noise).
    kind : str
        ``"step"`` or ``"trajectory"``.
    positions, velocities : tuple of int
        Columns of ``state`` holding the joint positions and velocities.
    state_names, controller_state_names, input_names, disturbance_names : tuple of str
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
    positions: tuple[int, ...] = (0,)
    velocities: tuple[int, ...] = (1,)
    state_names: tuple[str, ...] = ("x1", "x2")
    controller_state_names: tuple[str, ...] = ("x3",)
    input_names: tuple[str, ...] = ("u",)
    disturbance_names: tuple[str, ...] = ("xi",)
    settings: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n_t = np.size(self.time)
        for name in ("time", "reference", "state", "controller_state", "u_command", "u_applied", "perturbation",
                     "measured"):
            arr = np.array(getattr(self, name), dtype=float)
            if name in ("u_command", "u_applied", "perturbation", "controller_state") and arr.ndim == 1:
                arr = arr.reshape(n_t, -1)
            if name == "reference" and arr.ndim == 2:
                arr = arr.reshape(n_t, -1, 3)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "settings", freeze(dict(self.settings)))

    @property
    def n_joints(self) -> int:
        """Number of joints."""
        return len(self.positions)

    @property
    def joint_positions(self) -> np.ndarray:
        """Joint positions ``(N, n)`` (rad)."""
        return self.state[:, list(self.positions)]

    @property
    def desired(self) -> np.ndarray:
        """Desired joint positions ``(N, n)`` (rad)."""
        return self.reference[:, :, 0]

    @property
    def tracking_errors(self) -> np.ndarray:
        """``q - qD`` per joint, ``(N, n)`` (rad)."""
        return self.joint_positions - self.desired

    @property
    def position(self) -> np.ndarray:
        """Position of the first joint (rad), shape ``(N,)``."""
        return self.state[:, self.positions[0]]

    @property
    def tracking_error(self) -> np.ndarray:
        """``x1 - xD`` of the first joint (rad), shape ``(N,)``."""
        return self.tracking_errors[:, 0]
