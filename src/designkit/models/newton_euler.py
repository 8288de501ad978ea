"""Recursive Newton--Euler inverse dynamics, linear in the inertial parameters (CasADi ``SX``).

:func:`rnea` computes ``M(q) qdd + C(q, qd) qd + g(q)`` of a serial chain (SI units:
N*m or N) from the 10 inertial parameters per link of
:mod:`designkit.models.inertial_parameters`, about each link's DH-frame origin.
The recursion is written *linear in those parameters*, so
``casadi.jacobian(tau, P)`` is the regressor (:mod:`designkit.models.regressor`).

It runs in *joint frames* (origin on the joint axis, ``z`` along it; for the
standard convention these are the frames of the equivalent modified-DH chain);
the parameters are moved there by a fixed, linear change of reference point.

Numeric parameters stay Python floats until they meet a symbol
(:mod:`designkit.models.exact_arithmetic`), so exact zeros vanish and CasADi
folds constants (the PUMA 560 inverse dynamics compile to well under 730
instructions).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.models.chain import trig
from designkit.models.description import ChainDescription
from designkit.models.exact_arithmetic import (
    Mat,
    Vec,
    add,
    cross,
    dot,
    matmul,
    mul,
    rot,
    rot_t,
    rz,
    rz_t,
    scalar,
    sub,
    vadd,
    vscale,
)
from designkit.models.inertial_parameters import inertial_parameters

__all__ = ["rnea"]


@dataclass(frozen=True)
class _Body:
    """Inertial parameters of one link about a point, in some frame."""

    m: Any
    h: Vec  # first moment m*c (kg*m)
    inertia: Mat  # 3x3 inertia tensor about the point (kg*m^2)

    @staticmethod
    def from_vector(p: Sequence[Any]) -> _Body:
        m, hx, hy, hz, ixx, ixy, ixz, iyy, iyz, izz = p
        return _Body(m, [hx, hy, hz], [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])

    def moved(self, R: Mat, r: Vec) -> _Body:
        """Express in a frame rotated by ``R`` (new <- old) about a point ``r`` away from the old origin.

        ``r`` is the old reference point relative to the new one, in new coordinates.
        ``I_B = R I_A R' + m (r.r E - r r') + 2 (r.h) E - r h' - h r'`` with ``h = R h_A``.
        """
        h = rot(R, self.h)
        inertia = matmul(matmul(R, self.inertia), [list(row) for row in zip(*R, strict=True)])
        rr, rh = dot(r, r), dot(r, h)
        out = [[0.0] * 3 for _ in range(3)]
        for a in range(3):
            for b in range(3):
                shift = sub(mul(-1.0, add(mul(r[a], h[b]), mul(h[a], r[b]))), mul(self.m, mul(r[a], r[b])))
                if a == b:
                    shift = add(shift, add(mul(self.m, rr), mul(2.0, rh)))
                out[a][b] = add(inertia[a][b], shift)
        return _Body(self.m, vadd(h, vscale(self.m, r)), out)


@dataclass(frozen=True)
class _Joint:
    """Joint ``i`` seen from joint frame ``i-1``: fixed ``(R, p)`` then a motion about/along ``z``."""

    revolute: bool
    R: Mat
    p: Vec


def _compose(a: tuple[Mat, Vec], b: tuple[Mat, Vec]) -> tuple[Mat, Vec]:
    Ra, pa = a
    Rb, pb = b
    return matmul(Ra, Rb), vadd(pa, rot(Ra, pb))


def _rot_x(angle: Any) -> tuple[Mat, Vec]:
    c, s = trig(angle)
    return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]], [0.0, 0.0, 0.0]


def _rot_z(angle: Any) -> tuple[Mat, Vec]:
    c, s = trig(angle)
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], [0.0, 0.0, 0.0]


def _trans(x: Any, y: Any, z: Any) -> tuple[Mat, Vec]:
    return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [scalar(x), scalar(y), scalar(z)]


_IDENTITY = _trans(0.0, 0.0, 0.0)


def _joint_frames(description: ChainDescription) -> tuple[list[_Joint], list[tuple[Mat, Vec]]]:
    """Split each DH transform into ``fixed part @ motion(q)`` with the motion about/along local ``z``.

    Returns the joints and, for each link, the transform from the joint frame to
    the DH link frame (identity for the modified convention).
    """
    base = description.base
    before: tuple[Mat, Vec] = ([[scalar(base[r][c]) for c in range(3)] for r in range(3)],
                               [scalar(base[r][3]) for r in range(3)])
    joints: list[_Joint] = []
    to_link: list[tuple[Mat, Vec]] = []
    modified = description.convention == "modified"
    for link in description.links:
        fixed = _compose(before, _compose(_rot_x(link.alpha), _trans(link.a, 0.0, 0.0))) if modified else before
        revolute = link.joint == "revolute"
        if revolute:
            fixed = _compose(fixed, _compose(_trans(0.0, 0.0, link.d), _rot_z(link.offset)))
        else:
            fixed = _compose(fixed, _compose(_rot_z(link.theta), _trans(0.0, 0.0, link.offset)))
        joints.append(_Joint(revolute, *fixed))
        after = _IDENTITY if modified else _compose(_trans(link.a, 0.0, 0.0), _rot_x(link.alpha))
        to_link.append(after)
        before = after
    return joints, to_link


def rnea(
    description: ChainDescription,
    q: ca.SX,
    qd: ca.SX,
    qdd: ca.SX,
    parameters: Sequence[Any] | None = None,
    gravity: Sequence[Any] | None = None,
) -> ca.SX:
    """Rigid-body inverse dynamics ``M(q) qdd + C(q, qd) qd + g(q)`` by recursive Newton--Euler.

    Parameters
    ----------
    description : ChainDescription
        Kinematics (and, when ``parameters`` is None, inertial data).
    q, qd, qdd : casadi.SX
        Joint positions, rates and accelerations, ``n x 1`` (rad, rad/s, rad/s^2 or m, m/s, m/s^2).
    parameters : sequence of 10 n scalars, optional
        Inertial parameters per link, see
        :data:`~designkit.models.inertial_parameters.INERTIAL_NAMES`; numbers or ``SX``.
        Defaults to :func:`~designkit.models.inertial_parameters.inertial_parameters` of the description.
    gravity : sequence of 3, optional
        Gravitational acceleration in the base frame (m/s^2); defaults to the description's.

    Returns
    -------
    casadi.SX
        Joint torques/forces, ``n x 1`` (N*m or N); friction and motor inertia excluded.
    """
    n = description.n
    params = inertial_parameters(description) if parameters is None else list(parameters)
    grav = description.gravity if gravity is None else gravity
    joints, to_link = _joint_frames(description)
    bodies = [
        _Body.from_vector([scalar(v) for v in params[10 * i: 10 * i + 10]]).moved(*to_link[i])
        for i in range(n)
    ]

    w: Vec = [0.0, 0.0, 0.0]
    wd: Vec = [0.0, 0.0, 0.0]
    acc: Vec = [mul(-1.0, scalar(g)) for g in grav]
    trigs: list[tuple[Any, Any]] = []
    offsets: list[Vec] = []
    forces: list[Vec] = []
    moments: list[Vec] = []
    for i, (joint, body) in enumerate(zip(joints, bodies, strict=True)):
        if joint.revolute:
            c, s = ca.cos(q[i]), ca.sin(q[i])
            trigs.append((c, s))
            u = vadd(acc, cross(wd, joint.p), cross(w, cross(w, joint.p)))
            acc = rz_t(c, s, rot_t(joint.R, u))
            w_in = rz_t(c, s, rot_t(joint.R, w))
            wd = vadd(rz_t(c, s, rot_t(joint.R, wd)), [mul(qd[i], w_in[1]), mul(-qd[i], w_in[0]), qdd[i]])
            w = [w_in[0], w_in[1], add(w_in[2], qd[i])]
            offsets.append(joint.p)
        else:
            trigs.append((1.0, 0.0))
            w = rot_t(joint.R, w)
            wd = rot_t(joint.R, wd)
            r = vadd(rot_t(joint.R, joint.p), [0.0, 0.0, q[i]])
            coriolis = cross(w, [0.0, 0.0, mul(2.0, qd[i])])
            acc = vadd(rot_t(joint.R, acc), cross(wd, r), cross(w, cross(w, r)), coriolis, [0.0, 0.0, qdd[i]])
            offsets.append(vadd(joint.p, rot(joint.R, [0.0, 0.0, q[i]])))
        h, inertia = body.h, body.inertia
        forces.append(vadd(vscale(body.m, acc), cross(wd, h), cross(w, cross(w, h))))
        moments.append(vadd(rot(inertia, wd), cross(w, rot(inertia, w)), cross(h, acc)))

    tau: list[Any] = [0.0] * n
    force: Vec = [0.0, 0.0, 0.0]
    moment: Vec = [0.0, 0.0, 0.0]
    for i in reversed(range(n)):
        if i + 1 < n:
            nxt = joints[i + 1]
            c, s = trigs[i + 1]
            f_child = rot(nxt.R, rz(c, s, force))
            moment = vadd(rot(nxt.R, rz(c, s, moment)), cross(offsets[i + 1], f_child))
            force = f_child
        force = vadd(forces[i], force)
        moment = vadd(moments[i], moment)
        tau[i] = moment[2] if joints[i].revolute else force[2]
    return ca.vertcat(*[ca.SX(t) for t in tau]) if n else ca.SX.zeros(0, 1)
