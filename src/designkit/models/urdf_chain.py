"""Geometry of a serial URDF chain and its exact conversion to modified DH.

A URDF joint is a fixed transform (``origin xyz rpy``) followed by a motion
about or along an arbitrary ``axis``; DH frames are a different choice of link
frames for the same mechanism.  :func:`to_modified_dh` finds those frames
(Craig's *modified* convention, ``T_{i-1,i} = Rx(alpha) Tx(a) Rz(theta) Tz(d)``)
from the joint axes as lines in space at ``q = 0``:

* ``z_i`` is joint ``i``'s axis, with the URDF sign, so the joint variables are
  the same (``q_DH = q_URDF``);
* ``x_i`` lies on the common normal from axis ``i`` to axis ``i+1`` (for
  intersecting axes ``z_i x z_{i+1}``; for parallel axes the normal through the
  previous frame's foot point, so ``d_i = 0``); the origin is where it meets axis ``i``;
* frame 0 coincides with frame 1 at ``q = 0``; ``base`` is its pose in the URDF
  base link, ``tool`` the pose of the tip link in frame ``n``;
* inertial data move to the DH link frames by the constant transform between
  the URDF link frame and the DH frame of the same link.

Every serial chain of revolute and prismatic joints has such a representation,
so no chain is refused for its geometry.  The result is checked: forward
kinematics of every link frame from the URDF data and from the DH parameters
must agree at three configurations (1e-9), else :class:`ModelError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from designkit.errors import ModelError
from designkit.models.description import ChainDescription, LinkDescription

__all__ = [
    "Body",
    "SerialChain",
    "UrdfJoint",
    "matrix_to_rpy",
    "merge_bodies",
    "rpy_to_matrix",
    "to_modified_dh",
    "transform",
]

_EPS = 1e-9  # m or rad: below this, axes are parallel / intersecting and lengths are zero
_SNAP = 1e-12


def rpy_to_matrix(rpy: np.ndarray | tuple[float, float, float]) -> np.ndarray:
    """URDF roll-pitch-yaw (rad) to a rotation matrix, ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def matrix_to_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """Rotation matrix to URDF roll-pitch-yaw (rad); ``roll = 0`` at the pitch = +-pi/2 singularity."""
    cp = math.hypot(R[0, 0], R[1, 0])
    pitch = math.atan2(-R[2, 0], cp)
    if cp < 1e-12:
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def transform(rotation: np.ndarray | None = None, translation: np.ndarray | None = None) -> np.ndarray:
    """4x4 homogeneous transform from a rotation matrix and a translation (m)."""
    T = np.eye(4)
    if rotation is not None:
        T[:3, :3] = rotation
    if translation is not None:
        T[:3, 3] = translation
    return T


@dataclass(frozen=True)
class Body:
    """Inertial data of a rigid body in some frame.

    Parameters
    ----------
    mass : float
        Mass (kg).
    com : numpy.ndarray
        Centre of mass (m), shape ``(3,)``.
    inertia : numpy.ndarray
        3x3 inertia tensor about the centre of mass (kg*m^2), frame axes.
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray

    def moved(self, T: np.ndarray) -> Body:
        """The same body expressed in a frame in which the current frame has pose ``T`` (4x4)."""
        R = T[:3, :3]
        return Body(self.mass, R @ self.com + T[:3, 3], R @ self.inertia @ R.T)


def merge_bodies(bodies: list[Body]) -> Body:
    """One body equivalent to rigidly joined bodies, all expressed in the same frame."""
    mass = sum(b.mass for b in bodies)
    first = sum((b.mass * b.com for b in bodies), np.zeros(3))
    com = first / mass if mass > 0 else np.zeros(3)
    inertia = np.zeros((3, 3))
    for b in bodies:
        r = b.com - com
        inertia += b.inertia + b.mass * (r @ r * np.eye(3) - np.outer(r, r))
    return Body(mass, com, inertia)


@dataclass(frozen=True)
class UrdfJoint:
    """A movable joint of a serial chain.

    Parameters
    ----------
    name : str
        URDF joint name.
    joint : {"revolute", "prismatic"}
        Joint type (URDF ``continuous`` is revolute without limits).
    pose : numpy.ndarray
        4x4 pose of the joint frame (= child link frame at ``q = 0``) in the base link (m).
    axis : numpy.ndarray
        Unit axis in the joint frame.
    body : Body
        Inertial data of the moved link (fixed-jointed descendants merged), joint-frame coordinates.
    qlim : tuple of 2 or None
        Joint limits (rad or m).
    viscous, coulomb : float
        URDF ``dynamics damping`` and ``friction``.
    """

    name: str
    joint: str
    pose: np.ndarray
    axis: np.ndarray
    body: Body
    qlim: tuple[float, float] | None = None
    viscous: float = 0.0
    coulomb: float = 0.0


@dataclass(frozen=True)
class SerialChain:
    """A serial URDF chain at ``q = 0``.

    Parameters
    ----------
    name : str
        Robot name.
    joints : tuple of UrdfJoint
        Movable joints, base to tip.
    tip : numpy.ndarray
        4x4 pose of the tip link (the tool frame) in the base link at ``q = 0``.
    """

    name: str
    joints: tuple[UrdfJoint, ...]
    tip: np.ndarray


def _snap(x: float) -> float:
    for exact in (0.0, 1.0, -1.0):
        if abs(x - exact) < _SNAP:
            return exact
    return float(x)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _perpendicular(z: np.ndarray, hint: np.ndarray) -> np.ndarray:
    """Unit vector perpendicular to ``z``, closest to ``hint`` (or to a base axis when ``hint`` is parallel)."""
    for candidate in (hint, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        v = candidate - (candidate @ z) * z
        if np.linalg.norm(v) > 1e-6:
            return _unit(v)
    raise AssertionError("unreachable")  # pragma: no cover


def _dh_frames(chain: SerialChain) -> list[np.ndarray]:
    """Modified-DH frames ``D_1..D_n`` at ``q = 0`` in the base link (4x4)."""
    lines = [(j.pose[:3, 3], _unit(j.pose[:3, :3] @ j.axis)) for j in chain.joints]
    n = len(lines)
    frames = []
    origin = lines[0][0]  # foot point on the current axis, where x_{i-1} meets it
    previous_x: np.ndarray | None = None
    for i in range(n):
        o, z = lines[i]
        origin = o + ((origin - o) @ z) * z  # project onto the axis (exact for i > 0 by construction)
        hint = previous_x if previous_x is not None else chain.joints[i].pose[:3, 0]
        if i == n - 1:
            x = _perpendicular(z, hint)
            foot = origin
        else:
            o2, z2 = lines[i + 1]
            c = np.cross(z, z2)
            if np.linalg.norm(c) > _EPS:  # skew or intersecting: unique common normal
                w = o - o2
                a, b, e = z @ z2, z @ w, z2 @ w
                s = (a * e - b) / (1.0 - a * a)
                t = (e - a * b) / (1.0 - a * a)
                origin, foot = o + s * z, o2 + t * z2
                gap = foot - origin
                x = _unit(gap) if np.linalg.norm(gap) > _EPS else _unit(c)
            else:  # parallel: the normal through the current foot point
                foot = o2 + ((origin - o2) @ z2) * z2
                gap = foot - origin
                x = _unit(gap) if np.linalg.norm(gap) > _EPS else _perpendicular(z, hint)
        frames.append(transform(np.column_stack([x, np.cross(z, x), z]), origin))
        previous_x, origin = x, foot
    return frames


def _dh_parameters(T: np.ndarray) -> tuple[float, float, float, float]:
    """``(alpha, a, theta, d)`` with ``T = Rx(alpha) Tx(a) Rz(theta) Tz(d)``; raise if ``T`` has another form."""
    R, p = T[:3, :3], T[:3, 3]
    alpha = math.atan2(-R[1, 2], R[2, 2])
    theta = math.atan2(-R[0, 1], R[0, 0])
    a = p[0]
    d = p[2] * math.cos(alpha) - p[1] * math.sin(alpha)
    if np.abs(_modified(alpha, a, theta, d) - T).max() > 1e-9:
        raise ModelError("internal error: URDF to DH conversion produced a non-DH transform")
    return tuple(_snap(v) for v in (alpha, a, theta, d))  # type: ignore[return-value]


def _modified(alpha: float, a: float, theta: float, d: float) -> np.ndarray:
    ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    return np.array([
        [ct, -st, 0.0, a],
        [st * ca, ct * ca, -sa, -sa * d],
        [st * sa, ct * sa, ca, ca * d],
        [0.0, 0.0, 0.0, 1.0],
    ])


def _motion(joint: UrdfJoint, q: float) -> np.ndarray:
    if joint.joint == "prismatic":
        return transform(None, joint.axis * q)
    k = joint.axis
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return transform(np.eye(3) + math.sin(q) * K + (1.0 - math.cos(q)) * K @ K)


def _check(chain: SerialChain, description: ChainDescription, frames: list[np.ndarray]) -> None:
    """Compare link-frame forward kinematics of the URDF data and the DH description."""
    rng = np.random.default_rng(0)
    for q in rng.uniform(-2.0, 2.0, (3, len(chain.joints))):
        urdf = np.eye(4)
        previous = np.eye(4)
        dh = np.array(description.base, dtype=float)
        for i, (joint, link) in enumerate(zip(chain.joints, description.links, strict=True)):
            urdf = urdf @ np.linalg.solve(previous, joint.pose) @ _motion(joint, q[i])
            previous = joint.pose
            theta = q[i] + link.offset if link.joint == "revolute" else link.theta
            d = q[i] + link.offset if link.joint == "prismatic" else link.d
            dh = dh @ _modified(link.alpha, link.a, theta, d)
            expected = urdf @ np.linalg.solve(joint.pose, frames[i])
            if np.abs(expected - dh).max() > 1e-9:
                raise ModelError(f"internal error: DH frame of joint {joint.name!r} does not match the URDF")


def to_modified_dh(chain: SerialChain, *, gravity: tuple[float, float, float]) -> ChainDescription:
    """Modified-DH description of a serial URDF chain (see the module docstring).

    Parameters
    ----------
    chain : SerialChain
        Joints, inertial data and tip pose at ``q = 0``.
    gravity : tuple of 3
        Gravitational acceleration in the URDF base link (m/s^2).

    Returns
    -------
    ChainDescription
        ``convention="modified"``, with ``base`` and ``tool`` transforms; joint
        variables equal the URDF ones.
    """
    if not chain.joints:
        raise ModelError(f"URDF robot {chain.name!r} has no movable joint between base and tip")
    frames = _dh_frames(chain)
    links = []
    previous = frames[0]  # frame 0 coincides with frame 1 at q = 0
    for joint, frame in zip(chain.joints, frames, strict=True):
        alpha, a, theta, d = _dh_parameters(np.linalg.solve(previous, frame))
        body = joint.body.moved(np.linalg.solve(frame, joint.pose))
        I = body.inertia
        common = dict(
            a=a, alpha=alpha, mass=float(body.mass), com=tuple(_snap(c) for c in body.com),
            inertia=tuple(_snap(v) for v in (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])),
            viscous=joint.viscous, coulomb=joint.coulomb, qlim=joint.qlim, name=joint.name,
        )
        if joint.joint == "revolute":
            links.append(LinkDescription(joint="revolute", d=d, offset=theta, **common))
        else:
            links.append(LinkDescription(joint="prismatic", theta=theta, offset=d, **common))
        previous = frame

    def rows(T: np.ndarray) -> tuple[tuple[float, ...], ...]:
        return tuple(tuple(_snap(v) for v in row) for row in T)

    description = ChainDescription(
        name=chain.name, links=tuple(links), convention="modified", gravity=tuple(float(g) for g in gravity),
        base=rows(frames[0]), tool=rows(np.linalg.solve(frames[-1], chain.tip)), source="URDF",
    )
    _check(chain, description, frames)
    return description
