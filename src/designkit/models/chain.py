"""Kinematics of a serial chain as CasADi ``SX`` expression builders.

Every function here takes a :class:`~designkit.models.description.ChainDescription`
and symbolic joint coordinates and returns ``casadi.SX`` expressions; nothing is
evaluated numerically.  :mod:`designkit.models.robot` wraps them into named
``casadi.Function`` objects.

Conventions (SI units: m, rad):

* ``T_0i`` is the pose of DH frame ``i`` (the frame attached to link ``i``) in the
  *base frame*, which is the frame the ``ChainDescription.base`` transform starts
  from; ``T_0i = base @ T_01 @ ... @ T_{i-1,i}``.  The tool pose is ``T_0n @ tool``.
* Geometric Jacobians are expressed in the base frame, rows ``[v; omega]``, where
  ``v`` is the linear velocity of the chosen point (by default the tool-frame origin).
* Angles of ``cos``/``sin`` of *numeric* twist angles are snapped to exact 0 and
  +-1 (``cos(pi/2)`` is ``0``, not ``6e-17``) so that CasADi folds the constants.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.errors import ModelError
from designkit.models.description import ChainDescription, LinkDescription

_SNAP = 1e-14

__all__ = [
    "REPRESENTATIONS",
    "Representation",
    "analytic_jacobian",
    "as_sx_matrix",
    "dh_transform",
    "frame_transforms",
    "geometric_jacobian",
    "jacobian_dot_qd",
    "joint_axes",
    "link_transform",
    "numeric_value",
    "point_jacobian",
    "representation",
    "tool_pose",
    "trig",
]


def numeric_value(x: Any) -> float | None:
    """Return ``x`` as a float if it is a numeric constant, else ``None``.

    Parameters
    ----------
    x : float, int or casadi.SX
        A scalar, possibly symbolic.

    Returns
    -------
    float or None
        The value, or ``None`` when ``x`` depends on a symbol.
    """
    if isinstance(x, int | float):
        return float(x)
    if isinstance(x, ca.SX | ca.DM) and x.numel() == 1 and x.is_constant():
        return float(ca.DM(x))
    return None


def _snap(value: float) -> float:
    """Round ``value`` to exactly 0, 1 or -1 when it is within ``1e-14`` of one of them."""
    for exact in (0.0, 1.0, -1.0):
        if abs(value - exact) < _SNAP:
            return exact
    return value


def trig(angle: Any) -> tuple[Any, Any]:
    """Cosine and sine of an angle, exact 0/+-1 for numeric multiples of pi/2.

    Parameters
    ----------
    angle : float or casadi.SX
        Angle (rad).

    Returns
    -------
    tuple
        ``(cos(angle), sin(angle))`` as floats for a numeric angle, else ``SX``.
    """
    value = numeric_value(angle)
    if value is not None:
        return _snap(math.cos(value)), _snap(math.sin(value))
    return ca.cos(angle), ca.sin(angle)


def as_sx_matrix(rows: Sequence[Sequence[Any]]) -> ca.SX:
    """Build an ``SX`` matrix from nested rows of floats and ``SX`` scalars."""
    return ca.vertcat(*[ca.horzcat(*[ca.SX(v) if not isinstance(v, ca.SX) else v for v in row])
                        for row in rows])


def dh_transform(a: Any, alpha: Any, d: Any, theta: Any, convention: str = "standard") -> ca.SX:
    """Homogeneous transform between consecutive DH frames.

    Parameters
    ----------
    a, alpha, d, theta : float or casadi.SX
        DH link length (m), twist (rad), offset (m) and joint angle (rad).
    convention : {"standard", "modified"}
        ``"standard"``: ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``;
        ``"modified"``: ``Rx(alpha) Tx(a) Rz(theta) Tz(d)``.

    Returns
    -------
    casadi.SX
        4x4 transform ``T_{i-1,i}``.
    """
    ct, st = trig(theta)
    ca_, sa = trig(alpha)
    if convention == "standard":
        rows = [
            [ct, -st * ca_, st * sa, a * ct],
            [st, ct * ca_, -ct * sa, a * st],
            [0.0, sa, ca_, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    elif convention == "modified":
        rows = [
            [ct, -st, 0.0, a],
            [st * ca_, ct * ca_, -sa, -sa * d],
            [st * sa, ct * sa, ca_, ca_ * d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    else:
        raise ModelError("convention", f"must be 'standard' or 'modified', got {convention!r}")
    return as_sx_matrix(rows)


def link_transform(link: LinkDescription, q: Any, convention: str = "standard") -> ca.SX:
    """Transform ``T_{i-1,i}`` of one link for joint coordinate ``q``.

    Revolute joints use ``theta = q + offset``; prismatic joints ``d = q + offset``.
    """
    if link.joint == "revolute":
        return dh_transform(link.a, link.alpha, link.d, q + link.offset, convention)
    if link.joint == "prismatic":
        return dh_transform(link.a, link.alpha, q + link.offset, link.theta, convention)
    raise ModelError("joint", f"must be 'revolute' or 'prismatic', got {link.joint!r}")


def frame_transforms(description: ChainDescription, q: ca.SX) -> list[ca.SX]:
    """Poses ``T_0i`` of every DH link frame ``i = 1..n`` in the base frame.

    Parameters
    ----------
    description : ChainDescription
        The chain.
    q : casadi.SX
        Joint coordinates, ``n x 1`` (rad or m).

    Returns
    -------
    list of casadi.SX
        ``n`` 4x4 transforms, the base transform included.
    """
    pose = as_sx_matrix(description.base)
    frames = []
    for i, link in enumerate(description.links):
        pose = ca.mtimes(pose, link_transform(link, q[i], description.convention))
        frames.append(pose)
    return frames


def tool_pose(description: ChainDescription, q: ca.SX, frames: Sequence[ca.SX] | None = None) -> ca.SX:
    """Pose of the tool frame in the base frame, ``T_0n @ tool`` (4x4)."""
    frames = frame_transforms(description, q) if frames is None else frames
    last = frames[-1] if frames else as_sx_matrix(description.base)
    return ca.mtimes(last, as_sx_matrix(description.tool))


def joint_axes(description: ChainDescription, frames: Sequence[ca.SX]) -> list[tuple[ca.SX, ca.SX]]:
    """Axis direction and a point on the axis of every joint, in the base frame.

    Standard DH: joint ``i`` moves along/about ``z_{i-1}`` through the origin of
    frame ``i-1`` (frame 0 is the base transform).  Modified DH: ``z_i`` through
    the origin of frame ``i``.

    Returns
    -------
    list of (casadi.SX, casadi.SX)
        ``(z, o)`` pairs, each a 3x1 vector.
    """
    modified = description.convention == "modified"
    anchors = list(frames) if modified else [as_sx_matrix(description.base), *frames[:-1]]
    return [(pose[0:3, 2], pose[0:3, 3]) for pose in anchors]


def point_jacobian(description: ChainDescription, axes: Sequence[tuple[ca.SX, ca.SX]], point: ca.SX,
                   last_joint: int) -> ca.SX:
    """Geometric Jacobian (6 x n, rows ``[v; omega]``) of a point carried by link ``last_joint``.

    Parameters
    ----------
    description : ChainDescription
        The chain.
    axes : list of (z, o)
        Joint axes from :func:`joint_axes`.
    point : casadi.SX
        3x1 position of the point in the base frame (m).
    last_joint : int
        0-based index of the link carrying the point; joints after it do not move it.
    """
    n = description.n
    columns = []
    for j in range(n):
        if j > last_joint:
            columns.append(ca.SX.zeros(6, 1))
            continue
        z, o = axes[j]
        if description.links[j].joint == "revolute":
            columns.append(ca.vertcat(ca.cross(z, point - o), z))
        else:
            columns.append(ca.vertcat(z, ca.SX.zeros(3, 1)))
    return ca.horzcat(*columns) if columns else ca.SX.zeros(6, 0)


def geometric_jacobian(description: ChainDescription, q: ca.SX) -> ca.SX:
    """Geometric Jacobian of the tool frame, base frame, rows ``[v; omega]`` (6 x n).

    ``v`` is the velocity of the tool-frame origin (m/s per joint rate) and
    ``omega`` the angular velocity of the tool frame (rad/s per joint rate).
    """
    frames = frame_transforms(description, q)
    tool = tool_pose(description, q, frames)
    return point_jacobian(description, joint_axes(description, frames), tool[0:3, 3], description.n - 1)


def jacobian_dot_qd(jacobian: ca.SX, q: ca.SX, qd: ca.SX) -> ca.SX:
    """Exact ``Jdot(q, qd) @ qd`` by forward-mode differentiation.

    ``d/dt (J(q) qd)`` at constant ``qd`` is ``sum_k dJ/dq_k qd_k qd``, which is
    ``casadi.jtimes(J qd, q, qd)``.

    Parameters
    ----------
    jacobian : casadi.SX
        ``J(q)``, 6 x n.
    q, qd : casadi.SX
        Joint coordinates and rates, the symbols ``J`` depends on.

    Returns
    -------
    casadi.SX
        6x1 vector (m/s^2 and rad/s^2).
    """
    return ca.jtimes(ca.mtimes(jacobian, qd), q, qd)


# --------------------------------------------------------------------------------------------
# Orientation representations for the analytic Jacobian
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Representation:
    """A minimal orientation representation ``phi`` (3 angles, rad).

    Parameters
    ----------
    name : str
        Registry key.
    angles : callable
        ``R (3x3 SX) -> phi (3x1 SX)``, the angles of a rotation matrix.
    inverse_rate : callable
        ``phi -> E^{-1}(phi)`` where ``omega = E(phi) phi_dot`` (omega in the base frame).
    rate : callable
        ``phi -> E(phi)``.
    singular : str
        Where ``E`` is singular.
    """

    name: str
    angles: Callable[[Any], Any]
    inverse_rate: Callable[[Any], Any]
    rate: Callable[[Any], Any]
    singular: str


def _rpy_angles(R: Any) -> ca.SX:
    """ZYX roll-pitch-yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``, returns ``[roll, pitch, yaw]``."""
    roll = ca.atan2(R[2, 1], R[2, 2])
    pitch = ca.atan2(-R[2, 0], ca.sqrt(R[0, 0] ** 2 + R[1, 0] ** 2))
    yaw = ca.atan2(R[1, 0], R[0, 0])
    return ca.vertcat(roll, pitch, yaw)


def _rpy_rate(phi: Any) -> ca.SX:
    cp, sp = ca.cos(phi[1]), ca.sin(phi[1])
    cy, sy = ca.cos(phi[2]), ca.sin(phi[2])
    return ca.vertcat(ca.horzcat(cy * cp, -sy, 0), ca.horzcat(sy * cp, cy, 0), ca.horzcat(-sp, 0, 1))


def _rpy_inverse_rate(phi: Any) -> ca.SX:
    cp, sp = ca.cos(phi[1]), ca.sin(phi[1])
    cy, sy = ca.cos(phi[2]), ca.sin(phi[2])
    return ca.vertcat(
        ca.horzcat(cy / cp, sy / cp, 0),
        ca.horzcat(-sy, cy, 0),
        ca.horzcat(cy * sp / cp, sy * sp / cp, 1),
    )


def _zyz_angles(R: Any) -> ca.SX:
    """ZYZ Euler: ``R = Rz(phi) Ry(theta) Rz(psi)`` with ``theta`` in ``[0, pi]``; returns ``[phi, theta, psi]``."""
    phi = ca.atan2(R[1, 2], R[0, 2])
    theta = ca.atan2(ca.sqrt(R[0, 2] ** 2 + R[1, 2] ** 2), R[2, 2])
    psi = ca.atan2(R[2, 1], -R[2, 0])
    return ca.vertcat(phi, theta, psi)


def _zyz_rate(phi: Any) -> ca.SX:
    ca_, sa = ca.cos(phi[0]), ca.sin(phi[0])
    cb, sb = ca.cos(phi[1]), ca.sin(phi[1])
    return ca.vertcat(ca.horzcat(0, -sa, ca_ * sb), ca.horzcat(0, ca_, sa * sb), ca.horzcat(1, 0, cb))


def _zyz_inverse_rate(phi: Any) -> ca.SX:
    ca_, sa = ca.cos(phi[0]), ca.sin(phi[0])
    cb, sb = ca.cos(phi[1]), ca.sin(phi[1])
    return ca.vertcat(
        ca.horzcat(-ca_ * cb / sb, -sa * cb / sb, 1),
        ca.horzcat(-sa, ca_, 0),
        ca.horzcat(ca_ / sb, sa / sb, 0),
    )


REPRESENTATIONS: dict[str, Representation] = {
    "rpy": Representation("rpy", _rpy_angles, _rpy_inverse_rate, _rpy_rate, "pitch = +-pi/2"),
    "zyz": Representation("zyz", _zyz_angles, _zyz_inverse_rate, _zyz_rate, "theta = 0 or pi"),
}
"""Orientation representations by name: ``"rpy"`` (ZYX roll-pitch-yaw) and ``"zyz"`` Euler angles."""


def representation(name: str) -> Representation:
    """Look up an orientation representation, raising :class:`ModelError` for an unknown name."""
    try:
        return REPRESENTATIONS[name]
    except KeyError:
        raise ModelError("representation", f"must be one of {sorted(REPRESENTATIONS)}, got {name!r}") from None


def analytic_jacobian(description: ChainDescription, q: ca.SX, name: str = "rpy") -> tuple[ca.SX, ca.SX]:
    """Analytic Jacobian of the tool pose ``x = [p; phi]`` for an orientation representation.

    ``J_a = blkdiag(I, E(phi)^{-1}) J`` with ``omega = E(phi) phi_dot``.

    Parameters
    ----------
    description : ChainDescription
        The chain.
    q : casadi.SX
        Joint coordinates, ``n x 1``.
    name : {"rpy", "zyz"}
        Orientation representation (see :data:`REPRESENTATIONS`).

    Returns
    -------
    (casadi.SX, casadi.SX)
        ``J_a`` (6 x n; m and rad per joint unit) and the pose vector ``[p; phi]`` (6x1).
    """
    rep = representation(name)
    frames = frame_transforms(description, q)
    tool = tool_pose(description, q, frames)
    jac = point_jacobian(description, joint_axes(description, frames), tool[0:3, 3], description.n - 1)
    phi = rep.angles(tool[0:3, 0:3])
    analytic = ca.vertcat(jac[0:3, :], ca.mtimes(rep.inverse_rate(phi), jac[3:6, :]))
    return analytic, ca.vertcat(tool[0:3, 3], phi)
