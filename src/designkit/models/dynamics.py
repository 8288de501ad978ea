"""Rigid-body dynamics of a serial chain: Newton--Euler and Euler--Lagrange, as CasADi ``SX`` builders.

Model (SI units: N*m or N, kg*m^2, rad/s)::

    tau = M(q) qdd + C(q, qd) qd + g(q) + diag(Ia) qdd + Fv qd + Fc sign(qd)

Two independent routes build it:

* :func:`rnea` -- recursive Newton--Euler, written *linear in the inertial
  parameters*: each link contributes ``[m, m*cx, m*cy, m*cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]``
  about its own DH-frame origin (:func:`link_inertial_parameters`), so
  ``casadi.jacobian(tau, P)`` is the regressor.  The recursion runs in *joint frames*
  (origin on the joint axis, ``z`` along it; for the standard convention these
  are the frames of the equivalent modified-DH chain); the parameters are moved
  there by a fixed, linear change of reference point.
* :func:`lagrangian` -- Euler--Lagrange: ``M(q)`` from the link-origin Jacobians
  of :mod:`designkit.models.chain` (kinetic energy ``0.5 qd' M qd``), ``g(q) = dV/dq``
  from the potential energy, and ``C(q, qd)`` from the Christoffel symbols of ``M``
  (:func:`christoffel`), so ``Mdot - 2C`` is skew-symmetric.

Numeric parameters stay Python floats until they meet a symbol, so exact zeros
vanish and CasADi folds constants (the PUMA 560 inverse dynamics compile to
well under 730 instructions).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.models.chain import frame_transforms, joint_axes, numeric_value, point_jacobian, trig
from designkit.models.description import ChainDescription, LinkDescription

Vec = list  # three scalars (float or casadi.SX)
Mat = list  # 3x3 nested list of scalars

__all__ = [
    "INERTIAL_NAMES",
    "Lagrangian",
    "christoffel",
    "coriolis_from_christoffel",
    "forward_dynamics",
    "friction_torque",
    "inertial_parameters",
    "lagrangian",
    "link_inertial_parameters",
    "rnea",
]

INERTIAL_NAMES: tuple[str, ...] = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz")
"""Names of the 10 inertial parameters of one link (about its DH-frame origin, link frame)."""


# --------------------------------------------------------------------------------------------
# Scalar and 3-vector arithmetic that keeps numeric zeros and ones exact
# --------------------------------------------------------------------------------------------


def _is(x: Any, value: float) -> bool:
    return isinstance(x, int | float) and x == value


def _mul(a: Any, b: Any) -> Any:
    if _is(a, 0.0) or _is(b, 0.0):
        return 0.0
    if _is(a, 1.0):
        return b
    if _is(b, 1.0):
        return a
    if _is(a, -1.0):
        return -b
    if _is(b, -1.0):
        return -a
    return a * b


def _add(a: Any, b: Any) -> Any:
    if _is(a, 0.0):
        return b
    if _is(b, 0.0):
        return a
    return a + b


def _sub(a: Any, b: Any) -> Any:
    if _is(b, 0.0):
        return a
    if _is(a, 0.0):
        return -b
    return a - b


def _sum(*terms: Any) -> Any:
    total: Any = 0.0
    for t in terms:
        total = _add(total, t)
    return total


def _vadd(*vectors: Vec) -> Vec:
    return [_sum(*(v[k] for v in vectors)) for k in range(3)]


def _vscale(s: Any, v: Vec) -> Vec:
    return [_mul(s, x) for x in v]


def _cross(a: Vec, b: Vec) -> Vec:
    return [
        _sub(_mul(a[1], b[2]), _mul(a[2], b[1])),
        _sub(_mul(a[2], b[0]), _mul(a[0], b[2])),
        _sub(_mul(a[0], b[1]), _mul(a[1], b[0])),
    ]


def _dot(a: Vec, b: Vec) -> Any:
    return _sum(*(_mul(x, y) for x, y in zip(a, b, strict=True)))


def _rot(R: Mat, v: Vec) -> Vec:
    """``R @ v``."""
    return [_sum(*(_mul(R[r][c], v[c]) for c in range(3))) for r in range(3)]


def _rot_t(R: Mat, v: Vec) -> Vec:
    """``R.T @ v``."""
    return [_sum(*(_mul(R[r][c], v[r]) for r in range(3))) for c in range(3)]


def _matmul(A: Mat, B: Mat) -> Mat:
    return [[_sum(*(_mul(A[r][k], B[k][c]) for k in range(3))) for c in range(3)] for r in range(3)]


def _rz_t(c: Any, s: Any, v: Vec) -> Vec:
    """``Rz(theta).T @ v`` from ``c = cos(theta)``, ``s = sin(theta)``."""
    return [_add(_mul(c, v[0]), _mul(s, v[1])), _sub(_mul(c, v[1]), _mul(s, v[0])), v[2]]


def _rz(c: Any, s: Any, v: Vec) -> Vec:
    """``Rz(theta) @ v``."""
    return [_sub(_mul(c, v[0]), _mul(s, v[1])), _add(_mul(s, v[0]), _mul(c, v[1])), v[2]]


def _scalar(x: Any) -> Any:
    value = numeric_value(x)
    return value if value is not None else x


# --------------------------------------------------------------------------------------------
# Inertial parameters
# --------------------------------------------------------------------------------------------


def link_inertial_parameters(link: LinkDescription) -> tuple[Any, ...]:
    """The 10 inertial parameters of a link about its DH-frame origin.

    Parallel-axis theorem: ``I_o = I_c + m (|c|^2 E - c c')``, where ``I_c`` is the
    inertia tensor about the centre of mass ``c`` (tensor entries, so the
    off-diagonal ``Ixy`` is ``-sum m x y``).

    Parameters
    ----------
    link : LinkDescription
        Mass (kg), centre of mass (m) and inertia about it (kg*m^2), link frame.

    Returns
    -------
    tuple
        ``(m, m cx, m cy, m cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)`` (kg, kg*m, kg*m^2).
    """
    m = _scalar(link.mass)
    cx, cy, cz = (_scalar(c) for c in link.com)
    ixx, iyy, izz, ixy, ixz, iyz = (_scalar(v) for v in link.inertia)
    return (
        m,
        _mul(m, cx),
        _mul(m, cy),
        _mul(m, cz),
        _add(ixx, _mul(m, _add(_mul(cy, cy), _mul(cz, cz)))),
        _sub(ixy, _mul(m, _mul(cx, cy))),
        _sub(ixz, _mul(m, _mul(cx, cz))),
        _add(iyy, _mul(m, _add(_mul(cx, cx), _mul(cz, cz)))),
        _sub(iyz, _mul(m, _mul(cy, cz))),
        _add(izz, _mul(m, _add(_mul(cx, cx), _mul(cy, cy)))),
    )


def inertial_parameters(description: ChainDescription) -> list[Any]:
    """Concatenated inertial parameters of every link (length ``10 n``), see :func:`link_inertial_parameters`."""
    return [p for link in description.links for p in link_inertial_parameters(link)]


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
        h = _rot(R, self.h)
        inertia = _matmul(_matmul(R, self.inertia), [list(row) for row in zip(*R, strict=True)])
        rr, rh = _dot(r, r), _dot(r, h)
        out = [[0.0] * 3 for _ in range(3)]
        for a in range(3):
            for b in range(3):
                shift = _sub(_mul(-1.0, _add(_mul(r[a], h[b]), _mul(h[a], r[b]))), _mul(self.m, _mul(r[a], r[b])))
                if a == b:
                    shift = _add(shift, _add(_mul(self.m, rr), _mul(2.0, rh)))
                out[a][b] = _add(inertia[a][b], shift)
        return _Body(self.m, _vadd(h, _vscale(self.m, r)), out)


# --------------------------------------------------------------------------------------------
# Recursive Newton--Euler in joint frames
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Joint:
    """Joint ``i`` seen from joint frame ``i-1``: fixed ``(R, p)`` then a motion about/along ``z``."""

    revolute: bool
    R: Mat
    p: Vec


def _compose(a: tuple[Mat, Vec], b: tuple[Mat, Vec]) -> tuple[Mat, Vec]:
    Ra, pa = a
    Rb, pb = b
    return _matmul(Ra, Rb), _vadd(pa, _rot(Ra, pb))


def _rot_x(angle: Any) -> tuple[Mat, Vec]:
    c, s = trig(angle)
    return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]], [0.0, 0.0, 0.0]


def _rot_z(angle: Any) -> tuple[Mat, Vec]:
    c, s = trig(angle)
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], [0.0, 0.0, 0.0]


def _trans(x: Any, y: Any, z: Any) -> tuple[Mat, Vec]:
    return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [_scalar(x), _scalar(y), _scalar(z)]


_IDENTITY = _trans(0.0, 0.0, 0.0)


def _joint_frames(description: ChainDescription) -> tuple[list[_Joint], list[tuple[Mat, Vec]]]:
    """Split each DH transform into ``fixed part @ motion(q)`` with the motion about/along local ``z``.

    Returns the joints and, for each link, the transform from the joint frame to
    the DH link frame (identity for the modified convention).
    """
    base = description.base
    before: tuple[Mat, Vec] = ([[_scalar(base[r][c]) for c in range(3)] for r in range(3)],
                               [_scalar(base[r][3]) for r in range(3)])
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
        Inertial parameters per link, see :data:`INERTIAL_NAMES`; numbers or ``SX``.
        Defaults to :func:`inertial_parameters` of the description.
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
        _Body.from_vector([_scalar(v) for v in params[10 * i: 10 * i + 10]]).moved(*to_link[i])
        for i in range(n)
    ]

    w: Vec = [0.0, 0.0, 0.0]
    wd: Vec = [0.0, 0.0, 0.0]
    acc: Vec = [_mul(-1.0, _scalar(g)) for g in grav]
    trigs: list[tuple[Any, Any]] = []
    offsets: list[Vec] = []
    forces: list[Vec] = []
    moments: list[Vec] = []
    for i, (joint, body) in enumerate(zip(joints, bodies, strict=True)):
        if joint.revolute:
            c, s = ca.cos(q[i]), ca.sin(q[i])
            trigs.append((c, s))
            u = _vadd(acc, _cross(wd, joint.p), _cross(w, _cross(w, joint.p)))
            acc = _rz_t(c, s, _rot_t(joint.R, u))
            w_in = _rz_t(c, s, _rot_t(joint.R, w))
            wd = _vadd(_rz_t(c, s, _rot_t(joint.R, wd)), [_mul(qd[i], w_in[1]), _mul(-qd[i], w_in[0]), qdd[i]])
            w = [w_in[0], w_in[1], _add(w_in[2], qd[i])]
            offsets.append(joint.p)
        else:
            trigs.append((1.0, 0.0))
            w = _rot_t(joint.R, w)
            wd = _rot_t(joint.R, wd)
            r = _vadd(_rot_t(joint.R, joint.p), [0.0, 0.0, q[i]])
            coriolis = _cross(w, [0.0, 0.0, _mul(2.0, qd[i])])
            acc = _vadd(_rot_t(joint.R, acc), _cross(wd, r), _cross(w, _cross(w, r)), coriolis, [0.0, 0.0, qdd[i]])
            offsets.append(_vadd(joint.p, _rot(joint.R, [0.0, 0.0, q[i]])))
        h, inertia = body.h, body.inertia
        forces.append(_vadd(_vscale(body.m, acc), _cross(wd, h), _cross(w, _cross(w, h))))
        moments.append(_vadd(_rot(inertia, wd), _cross(w, _rot(inertia, w)), _cross(h, acc)))

    tau: list[Any] = [0.0] * n
    force: Vec = [0.0, 0.0, 0.0]
    moment: Vec = [0.0, 0.0, 0.0]
    for i in reversed(range(n)):
        if i + 1 < n:
            nxt = joints[i + 1]
            c, s = trigs[i + 1]
            f_child = _rot(nxt.R, _rz(c, s, force))
            moment = _vadd(_rot(nxt.R, _rz(c, s, moment)), _cross(offsets[i + 1], f_child))
            force = f_child
        force = _vadd(forces[i], force)
        moment = _vadd(moments[i], moment)
        tau[i] = moment[2] if joints[i].revolute else force[2]
    return ca.vertcat(*[ca.SX(t) for t in tau]) if n else ca.SX.zeros(0, 1)


# --------------------------------------------------------------------------------------------
# Euler--Lagrange
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Lagrangian:
    """Euler--Lagrange terms of a chain, ``SX`` in ``q`` (and parameters).

    Parameters
    ----------
    mass_matrix : casadi.SX
        ``M(q)``, n x n (kg*m^2, kg, kg*m): kinetic energy ``0.5 qd' M qd``.
    potential : casadi.SX
        Potential energy ``V(q)`` (J), zero at the base-frame origin.
    gravity_torque : casadi.SX
        ``g(q) = dV/dq``, n x 1 (N*m or N).
    """

    mass_matrix: ca.SX
    potential: ca.SX
    gravity_torque: ca.SX


def _skew(v: ca.SX) -> ca.SX:
    return ca.vertcat(
        ca.horzcat(0, -v[2], v[1]),
        ca.horzcat(v[2], 0, -v[0]),
        ca.horzcat(-v[1], v[0], 0),
    )


def lagrangian(
    description: ChainDescription,
    q: ca.SX,
    parameters: Sequence[Any] | None = None,
    gravity: Sequence[Any] | None = None,
) -> Lagrangian:
    """Mass matrix, potential energy and gravity torque from link Jacobians (Euler--Lagrange).

    Link ``i`` with origin velocity ``v = Jv_i qd`` and angular velocity
    ``w = Jw_i qd`` (base frame) has kinetic energy
    ``0.5 m v.v + v.(w x R h) + 0.5 w' R I_o R' w`` (``h = m c``, ``I_o`` about the
    link origin), hence
    ``M = sum_i m Jv'Jv - Jv'[Rh]x Jw - Jw'[Rh]x' Jv + Jw' R I_o R' Jw``.
    Potential energy ``V = -sum_i g.(m p_i + R_i h_i)``.

    Parameters
    ----------
    description : ChainDescription
        The chain.
    q : casadi.SX
        Joint coordinates, ``n x 1``.
    parameters, gravity
        As in :func:`rnea`.
    """
    n = description.n
    params = inertial_parameters(description) if parameters is None else list(parameters)
    grav = ca.vertcat(*[ca.SX(_scalar(g)) for g in (description.gravity if gravity is None else gravity)])
    frames = frame_transforms(description, q)
    axes = joint_axes(description, frames)
    mass = ca.SX.zeros(n, n)
    potential = ca.SX(0.0)
    for i, pose in enumerate(frames):
        m, hx, hy, hz, ixx, ixy, ixz, iyy, iyz, izz = (ca.SX(_scalar(v)) for v in params[10 * i: 10 * i + 10])
        R, p = pose[0:3, 0:3], pose[0:3, 3]
        h = ca.mtimes(R, ca.vertcat(hx, hy, hz))
        inertia = ca.mtimes([R, ca.vertcat(ca.horzcat(ixx, ixy, ixz), ca.horzcat(ixy, iyy, iyz),
                                           ca.horzcat(ixz, iyz, izz)), R.T])
        jac = point_jacobian(description, axes, p, i)
        jv, jw = jac[0:3, :], jac[3:6, :]
        cross = -ca.mtimes([jv.T, _skew(h), jw])
        mass += m * ca.mtimes(jv.T, jv) + cross + cross.T + ca.mtimes([jw.T, inertia, jw])
        potential -= ca.dot(grav, m * p + h)
    mass = ca.triu(mass) + ca.triu(mass, False).T  # exactly symmetric: one expression per pair
    return Lagrangian(mass, potential, ca.gradient(potential, q))


def christoffel(mass_matrix: ca.SX, q: ca.SX) -> ca.SX:
    """Christoffel symbols of the first kind of ``M(q)``.

    ``G_ijk = 0.5 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i)``, so that
    ``sum_jk G_ijk qd_j qd_k`` is the Coriolis/centripetal torque of joint ``i``.
    (The course notes' ``D_ijk`` with ``D_ijk = G_ijk``.)

    Returns
    -------
    casadi.SX
        ``n x n^2`` matrix, entry ``[i, j*n + k]`` is ``G_ijk``.
    """
    n = mass_matrix.shape[0]
    dm = ca.jacobian(ca.vec(mass_matrix), q)  # row i + j*n is dM_ij/dq

    def d(i: int, j: int, k: int) -> ca.SX:
        return dm[i + j * n, k]

    rows = [ca.horzcat(*[0.5 * (d(i, j, k) + d(i, k, j) - d(j, k, i)) for j in range(n) for k in range(n)])
            for i in range(n)]
    return ca.vertcat(*rows) if n else ca.SX.zeros(0, 0)


def coriolis_from_christoffel(symbols: ca.SX, qd: ca.SX) -> ca.SX:
    """Coriolis matrix ``C_ij = sum_k G_ijk qd_k`` from :func:`christoffel` output (n x n)."""
    n = symbols.shape[0]
    return ca.horzcat(*[ca.mtimes(symbols[:, j * n:(j + 1) * n], qd) for j in range(n)]) if n else symbols


def friction_torque(viscous: Sequence[Any], coulomb: Sequence[Any], qd: ca.SX) -> ca.SX:
    """Joint friction ``Fv qd + Fc sign(qd)`` (N*m or N), ``sign(0) = 0``."""
    return ca.vertcat(*[_add(_mul(_scalar(fv), qd[i]), _mul(_scalar(fc), ca.sign(qd[i])))
                        for i, (fv, fc) in enumerate(zip(viscous, coulomb, strict=True))])


def forward_dynamics(mass_matrix: ca.SX, bias: ca.SX, tau: ca.SX) -> ca.SX:
    """Joint accelerations ``qdd = M^{-1} (tau - bias)`` by ``casadi.solve`` (no explicit inverse)."""
    return ca.solve(mass_matrix, tau - bias)
