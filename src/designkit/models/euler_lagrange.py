"""Euler--Lagrange dynamics of a serial chain: ``M(q)``, ``V(q)``, ``g(q)``, Christoffel symbols, ``C(q, qd)``.

``M(q)`` comes from the link-origin Jacobians of :mod:`designkit.models.chain`
(kinetic energy ``0.5 qd' M qd``), ``g(q) = dV/dq`` from the potential energy, and
``C(q, qd)`` from the Christoffel symbols of ``M`` (:func:`christoffel`), so
``Mdot - 2C`` is skew-symmetric.  SI units (kg*m^2, J, N*m or N).

This route is independent of the recursive Newton--Euler of
:mod:`designkit.models.newton_euler`; the tests check that the two agree.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.models.chain import frame_transforms, joint_axes, point_jacobian
from designkit.models.description import ChainDescription
from designkit.models.exact_arithmetic import scalar
from designkit.models.inertial_parameters import inertial_parameters

__all__ = ["Lagrangian", "christoffel", "coriolis_from_christoffel", "lagrangian"]


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
        As in :func:`designkit.models.newton_euler.rnea`.
    """
    n = description.n
    params = inertial_parameters(description) if parameters is None else list(parameters)
    grav = ca.vertcat(*[ca.SX(scalar(g)) for g in (description.gravity if gravity is None else gravity)])
    frames = frame_transforms(description, q)
    axes = joint_axes(description, frames)
    mass = ca.SX.zeros(n, n)
    potential = ca.SX(0.0)
    for i, pose in enumerate(frames):
        m, hx, hy, hz, ixx, ixy, ixz, iyy, iyz, izz = (ca.SX(scalar(v)) for v in params[10 * i: 10 * i + 10])
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
