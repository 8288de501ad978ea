"""Linear-in-parameters model ``tau = W(q, qd, qdd) P``.

Parameter vector layout (``n`` joints, 1-based names):

1. ``10 n`` inertial parameters, link by link,
   ``[m_i, mcx_i, mcy_i, mcz_i, Ixx_i, Ixy_i, Ixz_i, Iyy_i, Iyz_i, Izz_i]``: mass (kg),
   first moment ``m c`` (kg*m) and inertia tensor about the *link-frame origin* (kg*m^2),
   all in DH link frame ``i`` (see :func:`designkit.models.inertial_parameters.link_inertial_parameters`);
2. with friction: ``[fv_i, fc_i]`` per joint, viscous (N*m*s/rad) and Coulomb (N*m) coefficients;
3. with motor inertia: ``Ia_i = G_i^2 Jm_i`` per joint, the reflected rotor inertia (kg*m^2).

Names read ``"m1", "mcx1", ..., "Izz1", "m2", ..., "fv1", "fc1", ..., "Ia1", ...``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca

from designkit.models.description import ChainDescription
from designkit.models.dynamics import friction_torque
from designkit.models.inertial_parameters import INERTIAL_NAMES, inertial_parameters
from designkit.models.newton_euler import rnea

__all__ = ["inverse_dynamics", "parameter_names", "parameter_vector", "regressor"]


def parameter_names(n: int, *, friction: bool = False, motor_inertia: bool = False) -> tuple[str, ...]:
    """Names of the entries of ``P`` for ``n`` joints (see the module docstring for the layout).

    Examples
    --------
    >>> parameter_names(1, friction=True)[-3:]
    ('Izz1', 'fv1', 'fc1')
    """
    names = [f"{name}{i + 1}" for i in range(n) for name in INERTIAL_NAMES]
    if friction:
        names += [f"{name}{i + 1}" for i in range(n) for name in ("fv", "fc")]
    if motor_inertia:
        names += [f"Ia{i + 1}" for i in range(n)]
    return tuple(names)


def parameter_vector(description: ChainDescription, *, friction: bool = False,
                     motor_inertia: bool = False) -> list[Any]:
    """The parameter vector ``P`` of a description: floats, or ``SX`` where the description has symbols.

    Inertial parameters come from the centre-of-mass data by the parallel-axis
    theorem; ``Ia_i = gear_ratio_i**2 * motor_inertia_i``.
    """
    values = list(inertial_parameters(description))
    if friction:
        values += [v for link in description.links for v in (link.viscous, link.coulomb)]
    if motor_inertia:
        values += [link.gear_ratio**2 * link.motor_inertia for link in description.links]
    return values


def inverse_dynamics(
    description: ChainDescription,
    q: ca.SX,
    qd: ca.SX,
    qdd: ca.SX,
    parameters: Sequence[Any],
    *,
    friction: bool = False,
    motor_inertia: bool = False,
) -> ca.SX:
    """Joint torques for a parameter vector laid out as :func:`parameter_names` (n x 1, N*m or N).

    ``tau = RNEA(q, qd, qdd; P_inertial) + fv qd + fc sign(qd) + Ia qdd``, linear in ``P``.
    """
    n = description.n
    params = list(parameters)
    tau = rnea(description, q, qd, qdd, params[: 10 * n])
    k = 10 * n
    if friction:
        tau = tau + friction_torque(params[k: k + 2 * n: 2], params[k + 1: k + 2 * n: 2], qd)
        k += 2 * n
    if motor_inertia:
        tau = tau + ca.vertcat(*[params[k + i] * qdd[i] for i in range(n)])
    return tau


def regressor(description: ChainDescription, q: ca.SX, qd: ca.SX, qdd: ca.SX, *,
              friction: bool = False, motor_inertia: bool = False) -> ca.SX:
    """Regressor ``W(q, qd, qdd)`` with ``tau = W P`` (n x len(P)), by ``casadi.jacobian`` of the RNEA.

    The RNEA is linear in ``P`` so the Jacobian does not depend on ``P``; it may
    depend on the description's symbols (e.g. a symbolic gravity or link length).
    """
    size = len(parameter_names(description.n, friction=friction, motor_inertia=motor_inertia))
    P = ca.SX.sym("P", size)
    tau = inverse_dynamics(description, q, qd, qdd, ca.vertsplit(P),
                           friction=friction, motor_inertia=motor_inertia)
    return ca.jacobian(tau, P)
