"""Task-space (end-effector) coordinates of a manipulator: what resolved-acceleration control tracks.

A :class:`TaskSpace` picks rows of the end effector's geometric Jacobian ``J(q)`` (6 x n, base
frame: rows ``x, y, z`` linear velocity, ``rx, ry, rz`` angular velocity) -- the position rows,
and the orientation rows when orientation is controlled -- leaving out the rows that are zero at
every configuration (a planar arm cannot move along ``z`` or turn about ``x``, ``y``).

Orientation error (a stated representation).  With the desired orientation ``R_D`` (held
constant) and the end effector's ``R(q)``, columns ``r_i`` and ``r_Di``::

    e_o = 1/2 sum_i r_i x r_Di = sin(theta) k

where ``R_D = Rot(k, theta) R``: the rotation from the actual to the desired orientation, as axis
times the sine of the angle (Luh, Walker and Paul's orientation error, 1980).  It equals the
angle-axis vector ``theta k`` to first order and is unique for ``|theta| < pi/2``.  The tracked
orientation coordinates are ``-e_o`` (the rotation of the actual from the desired orientation),
so that every tracked coordinate is "actual minus desired" with a desired value of zero; near
``R_D`` their rate is the angular velocity ``J_omega(q) qd``.

Functions of a task space on a robot (:func:`task_functions`, CasADi, the robot's parameters
baked in): ``tracked(q)`` (m, rad), ``jacobian(q)`` (the selected rows of ``J``), ``rate(q, qd) =
J_task qd`` and ``bias(q, qd) = (Jdot qd)_task``.  :func:`joint_path` solves the inverse kinematics
along a task-space path by continuation (Newton steps from the previous point) and reports the
conditioning of ``J_task`` along it: singular values, condition number and manipulability.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError

__all__ = [
    "AXES", "JointPath", "TaskFunctions", "TaskSpace", "check_path", "joint_path", "orientation_error",
    "task_functions",
    "task_space",
]

AXES: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")
"""Rows of the geometric Jacobian: linear velocity (m/s), then angular velocity (rad/s), base frame."""
UNITS: tuple[str, ...] = ("m", "m", "m", "rad", "rad", "rad")
ZERO_ROW = 1e-12
"""A Jacobian row below this at every sampled configuration is structurally zero."""
IK_TOLERANCE = 1e-10
"""Inverse-kinematics residual (m, rad) at which a path point is solved."""
IK_ITERATIONS = 50
REACH_TOLERANCE = 1e-6
"""A residual above this (m, rad) after the iterations: the point is out of reach."""


@dataclass(frozen=True)
class TaskSpace:
    """Which end-effector coordinates are controlled, and the orientation held.

    Parameters
    ----------
    rows : tuple of int
        Rows of the geometric Jacobian (indices into :data:`AXES`), position rows first.
    orientation_target : tuple of float
        ``R_D`` (9 numbers, row-major), the orientation held when orientation rows are controlled.
    """

    rows: tuple[int, ...]
    orientation_target: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the tracked coordinates (``x``, ``y``, ``rz``...)."""
        return tuple(AXES[i] for i in self.rows)

    @property
    def units(self) -> tuple[str, ...]:
        """Their units (m or rad)."""
        return tuple(UNITS[i] for i in self.rows)

    @property
    def position_rows(self) -> tuple[int, ...]:
        """The selected rows among ``x, y, z``."""
        return tuple(i for i in self.rows if i < 3)

    @property
    def orientation_rows(self) -> tuple[int, ...]:
        """The selected rows among ``rx, ry, rz`` (0-based in the angular part: 0, 1, 2)."""
        return tuple(i - 3 for i in self.rows if i >= 3)

    @property
    def m(self) -> int:
        """Number of task coordinates."""
        return len(self.rows)

    @property
    def R_D(self) -> np.ndarray:
        """The held orientation, 3 x 3."""
        return np.asarray(self.orientation_target, dtype=float).reshape(3, 3)

    def to_json(self) -> dict[str, Any]:
        """JSON form for designs and reports."""
        return {"coordinates": list(self.names), "units": list(self.units),
                "orientation_target": self.R_D.tolist() if self.orientation_rows else None,
                "orientation_error": "e_o = 1/2 sum_i r_i x r_Di = sin(theta) k (tracked: -e_o)"
                if self.orientation_rows else None}


def _call(robot: Any, name: str, p: Any, *args: Any) -> Any:
    f = robot.functions[name]
    extra = [ca.DM(np.asarray(p, dtype=float))] if f.n_in() > len(args) else []
    return f(*args, *extra)


def task_space(robot: Any, p: Any, q0: Any, orientation: bool, *, samples: int = 8, seed: int = 0) -> TaskSpace:
    """The task space of ``robot``: position rows (and orientation rows), without the structurally zero ones.

    Parameters
    ----------
    robot : Robot
        The manipulator.
    p : array_like or None
        Its parameter values (``None`` when it has no symbols).
    q0 : array_like, shape (n,)
        The initial configuration (rad, m): its end-effector orientation is the one held.
    orientation : bool
        Control the orientation too.
    samples, seed : int
        Random configurations at which a Jacobian row must vanish to be left out.
    """
    n = robot.n
    rng = np.random.default_rng(seed)
    rows_norm = np.zeros(6)
    for q in [np.asarray(q0, dtype=float), *rng.uniform(-np.pi, np.pi, size=(samples, n))]:
        J = np.asarray(_call(robot, "jacobian", p, ca.DM(q)))
        rows_norm = np.maximum(rows_norm, np.max(np.abs(J), axis=1))
    wanted = range(6) if orientation else range(3)
    rows = tuple(i for i in wanted if rows_norm[i] > ZERO_ROW)
    T = np.asarray(_call(robot, "fkine", p, ca.DM(np.asarray(q0, dtype=float))))
    return TaskSpace(rows, tuple(T[:3, :3].ravel().tolist()))


def orientation_error(R: Any, R_D: Any) -> Any:
    """``e_o = 1/2 sum_i R[:, i] x R_D[:, i]`` (works on NumPy arrays and CasADi expressions)."""
    if isinstance(R, np.ndarray) and isinstance(R_D, np.ndarray):
        return 0.5 * sum(np.cross(R[:, i], R_D[:, i]) for i in range(3))
    return 0.5 * sum(ca.cross(R[:, i], ca.DM(R_D)[:, i] if isinstance(R_D, np.ndarray) else R_D[:, i])
                     for i in range(3))


@dataclass(frozen=True)
class TaskFunctions:
    """CasADi functions of a task space on one robot (parameters baked in).

    ``tracked: q -> (m,)`` actual task coordinates (m; rad for ``-e_o``); ``jacobian: q -> (m, n)``;
    ``rate: (q, qd) -> J_task qd``; ``bias: (q, qd) -> (Jdot qd)_task``; ``tracked_jacobian: q ->
    d tracked/dq`` (equals ``jacobian`` on the held orientation).
    """

    tracked: ca.Function
    jacobian: ca.Function
    rate: ca.Function
    bias: ca.Function
    tracked_jacobian: ca.Function


def task_functions(robot: Any, p: Any, space: TaskSpace) -> TaskFunctions:
    """The :class:`TaskFunctions` of ``space`` on ``robot`` with parameters ``p``."""
    n = robot.n
    q, qd = ca.SX.sym("q", n), ca.SX.sym("qd", n)
    T = _call(robot, "fkine", p, q)
    rows = list(space.rows)
    parts = [T[i, 3] for i in space.position_rows]
    if space.orientation_rows:
        e_o = orientation_error(T[:3, :3], space.R_D)
        parts += [-e_o[i] for i in space.orientation_rows]
    tracked = ca.vertcat(*parts)
    J = _call(robot, "jacobian", p, q)[rows, :]
    bias = _call(robot, "jacobian_dot_qd", p, q, qd)[rows]
    return TaskFunctions(
        tracked=ca.Function("task_tracked", [q], [tracked], ["q"], ["x"]),
        jacobian=ca.Function("task_jacobian", [q], [J], ["q"], ["J"]),
        rate=ca.Function("task_rate", [q, qd], [J @ qd], ["q", "qd"], ["xd"]),
        bias=ca.Function("task_bias", [q, qd], [bias], ["q", "qd"], ["Jdot_qd"]),
        tracked_jacobian=ca.Function("task_tracked_jacobian", [q], [ca.jacobian(tracked, q)], ["q"], ["dx_dq"]),
    )


@dataclass(frozen=True)
class JointPath:
    """The joint motion that tracks a task-space path exactly, and the conditioning of ``J_task`` along it.

    Attributes
    ----------
    time : ndarray (N,)
        Instants (s).
    q, qd : ndarray (N, n)
        Joint positions (rad, m) and velocities (``J_task^+ xD'``; rad/s, m/s).
    sigma : ndarray (N, min(m, n))
        Singular values of ``J_task`` (descending).
    condition : ndarray (N,)
        ``sigma_max / sigma_min`` (inf where singular).
    manipulability : ndarray (N,)
        Yoshikawa's ``sqrt(det(J J^T))`` = the product of the singular values.
    residual : ndarray (N,)
        Inverse-kinematics residual ``|tracked(q) - xD|`` (m, rad); after the first point out of
        reach the path is not solved (``inf``).
    """

    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    sigma: np.ndarray
    condition: np.ndarray
    manipulability: np.ndarray
    residual: np.ndarray

    @property
    def worst(self) -> int:
        """Index of the worst-conditioned instant."""
        return int(np.argmax(self.condition))


def joint_path(functions: TaskFunctions, q0: Any, time: np.ndarray, targets: np.ndarray, rates: np.ndarray
               ) -> JointPath:
    """Inverse kinematics along a sampled task path by continuation.

    Each point starts from the previous solution (``q0`` for the first) and takes Newton steps
    ``dq = J^+ (xD - tracked(q))`` with ``J = d tracked/dq`` (least squares by SVD, so a
    singular point is passed, not divided by zero) until the residual is below
    :data:`IK_TOLERANCE` or :data:`IK_ITERATIONS` steps are taken.

    Parameters
    ----------
    functions : TaskFunctions
        The task space on the robot.
    q0 : array_like, shape (n,)
        Initial configuration (rad, m).
    time : ndarray (N,)
        Instants (s).
    targets, rates : ndarray (N, m)
        Desired task coordinates and their rates along the path.

    Returns
    -------
    JointPath
        ``residual`` above :data:`REACH_TOLERANCE` marks points out of reach (the caller decides).
    """
    q = np.asarray(q0, dtype=float).copy()
    N = time.size
    Q = np.empty((N, q.size))
    residual = np.empty(N)
    tracked, dtracked = functions.tracked, functions.tracked_jacobian
    for k in range(N):
        err = targets[k] - np.asarray(tracked(q)).ravel()
        for _ in range(IK_ITERATIONS):
            if np.max(np.abs(err)) < IK_TOLERANCE:
                break
            J = np.asarray(dtracked(q))
            q = q + np.linalg.lstsq(J, err, rcond=1e-12)[0]
            err = targets[k] - np.asarray(tracked(q)).ravel()
        Q[k] = q
        residual[k] = float(np.linalg.norm(err))
        if residual[k] > REACH_TOLERANCE:  # out of reach: the rest of the path is not solved
            Q[k + 1:] = q
            residual[k + 1:] = np.inf
            break
    J_all = np.asarray(functions.jacobian.map(N)(Q.T)).reshape(-1, N, order="F")
    m = targets.shape[1]
    Js = np.stack([J_all[:, k].reshape(m, -1, order="F") for k in range(N)])
    sigma = np.linalg.svd(Js, compute_uv=False)
    with np.errstate(divide="ignore"):
        condition = np.where(sigma[:, -1] > 0, sigma[:, 0] / sigma[:, -1], np.inf)
    Qd = np.stack([np.linalg.lstsq(Js[k], rates[k], rcond=1e-12)[0] for k in range(N)])
    return JointPath(time, Q, Qd, sigma, condition, np.prod(sigma, axis=1), residual)


def check_path(path: JointPath, key: str, limits: Any, velocity_limits: Any = None, *,
               reach_key: str | None = None) -> None:
    """Refuse a path out of reach, or whose joint motion leaves the joint or velocity limits.

    Raises
    ------
    ModelError
        Path ``key`` (``reach_key`` for a point out of reach, default ``key``) with the instant and
        the numbers.
    """
    far = np.flatnonzero(path.residual > REACH_TOLERANCE)
    if far.size:
        k = int(far[0])
        raise ModelError(reach_key or key, f"out of reach: at t = {path.time[k]:.4g} s the closest the end "
                                           f"effector gets to the path is {path.residual[k]:.3g} (m, rad)")
    for j, lim in enumerate(limits):
        if lim is None:
            continue
        bad = np.flatnonzero((path.q[:, j] < lim[0] - 1e-9) | (path.q[:, j] > lim[1] + 1e-9))
        if bad.size:
            k = int(bad[0])
            raise ModelError(key, f"the joint motion leaves joint {j + 1}'s limits [{lim[0]:.4g}, {lim[1]:.4g}] "
                                  f"at t = {path.time[k]:.4g} s (q{j + 1} = {path.q[k, j]:.4g})")
    if velocity_limits is not None:
        bound = np.broadcast_to(np.asarray(velocity_limits, dtype=float), (path.q.shape[1],))
        peak = np.max(np.abs(path.qd), axis=0)
        j = int(np.argmax(peak / bound))
        if peak[j] > bound[j] * (1 + 1e-9):
            k = int(np.argmax(np.abs(path.qd[:, j])))
            raise ModelError(key, f"joint {j + 1} needs {peak[j]:.4g} rad/s at t = {path.time[k]:.4g} s, above "
                                  f"plant.limits.velocity {bound[j]:g}")
