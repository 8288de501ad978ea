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
        Desired position, velocity and acceleration of each of the ``n`` tracked coordinates: the
        joints, or the task coordinates of a task-space controller (``tracked``).
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
    tracked : ndarray, shape (N, m), optional
        The tracked task coordinates (m, rad) of a task-space controller; ``None``: the joints are tracked.
    tracked_names, tracked_units : tuple of str
        Their names (``x``, ``y``, ``rz``) and units.
    signals : Mapping
        The law's recorded signals (:attr:`designkit.synthesis.law.Law.signals`): name -> array ``(N,)``,
        with ``signal_units`` name -> unit.
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
    tracked: np.ndarray | None = None
    tracked_names: tuple[str, ...] = ()
    tracked_units: tuple[str, ...] = ()
    signals: Mapping[str, np.ndarray] = field(default_factory=dict)
    signal_units: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n_t = np.size(self.time)
        for name in ("time", "reference", "state", "controller_state", "u_command", "u_applied", "perturbation",
                     "measured"):
            arr = _owned(getattr(self, name))
            if name in ("u_command", "u_applied", "perturbation", "controller_state") and arr.ndim == 1:
                arr = arr.reshape(n_t, -1)
            if name == "reference" and arr.ndim == 2:
                arr = arr.reshape(n_t, -1, 3)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if self.tracked is not None:
            arr = _owned(self.tracked).reshape(n_t, -1)
            arr.setflags(write=False)
            object.__setattr__(self, "tracked", arr)
        object.__setattr__(self, "settings", freeze(dict(self.settings)))
        object.__setattr__(self, "signals", freeze({k: np.asarray(v, dtype=float).reshape(n_t)
                                                    for k, v in self.signals.items()}))
        object.__setattr__(self, "signal_units", freeze(dict(self.signal_units)))

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
        """Desired positions of the tracked coordinates ``(N, n)`` (rad; m for task positions)."""
        return self.reference[:, :, 0]

    @property
    def task_space(self) -> bool:
        """Whether task coordinates (not the joints) are tracked."""
        return self.tracked is not None

    @property
    def tracked_positions(self) -> np.ndarray:
        """The tracked coordinates ``(N, n)``: the joint positions, or the task coordinates."""
        return self.tracked if self.tracked is not None else self.joint_positions

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        """Names of the tracked coordinates (state names of the joints, or ``x``, ``y``, ...)."""
        return self.tracked_names if self.tracked is not None else tuple(self.state_names[i] for i in self.positions)

    @property
    def coordinate_units(self) -> tuple[str, ...]:
        """Their units."""
        return self.tracked_units if self.tracked is not None else ("rad",) * len(self.positions)

    @property
    def tracking_errors(self) -> np.ndarray:
        """Actual minus desired of every tracked coordinate, ``(N, n)`` (rad; m for task positions)."""
        return self.tracked_positions - self.desired

    @property
    def position(self) -> np.ndarray:
        """Position of the first joint (rad), shape ``(N,)``."""
        return self.state[:, self.positions[0]]

    @property
    def tracking_error(self) -> np.ndarray:
        """``x1 - xD`` of the first joint (rad), shape ``(N,)``."""
        return self.tracking_errors[:, 0]

    @property
    def diverged_at(self) -> float | None:
        """The first instant (s) at which the run stops being finite -- a plant state, a controller state or a
        command not finite or beyond :data:`~designkit.simulation.integrate.DIVERGED` in magnitude -- or None
        for a run that stays finite throughout."""
        from designkit.simulation.integrate import DIVERGED

        rows = [np.asarray(a, dtype=float).reshape(np.size(self.time), -1)
                for a in (self.state, self.controller_state, self.u_command)]
        data = np.hstack(rows)
        with np.errstate(invalid="ignore"):
            bad = ~np.all(np.isfinite(data) & (np.abs(data) < DIVERGED), axis=1)
        first = np.flatnonzero(bad)
        return float(self.time[first[0]]) if first.size else None


def _owned(value: Any) -> np.ndarray:
    """``value`` as a float array the result may keep: a read-only float array is taken as it is (the simulator
    hands over views of its own records, marked read-only), anything else is copied."""
    if isinstance(value, np.ndarray) and value.dtype == np.float64 and not value.flags.writeable:
        return value
    return np.array(value, dtype=float)
