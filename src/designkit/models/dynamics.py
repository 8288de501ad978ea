"""Rigid-body dynamics of a serial chain: the joint-space model and where each term is built.

Model (SI units: N*m or N, kg*m^2, rad/s)::

    tau = M(q) qdd + C(q, qd) qd + g(q) + diag(Ia) qdd + Fv qd + Fc sign(qd)

Two independent routes build the rigid-body part, each in its own module:

* :mod:`designkit.models.newton_euler` -- :func:`rnea`, recursive Newton--Euler
  written *linear in the inertial parameters* of
  :mod:`designkit.models.inertial_parameters` (:func:`link_inertial_parameters`),
  so ``casadi.jacobian(tau, P)`` is the regressor.
* :mod:`designkit.models.euler_lagrange` -- :func:`lagrangian` (``M(q)`` from the
  link-origin Jacobians, ``g(q) = dV/dq``), :func:`christoffel` and
  :func:`coriolis_from_christoffel`, so ``Mdot - 2C`` is skew-symmetric.

This module adds the joint friction (:func:`friction_torque`) and the forward
dynamics (:func:`forward_dynamics`), and re-exports the names above so that
``from designkit.models import dynamics`` reaches the whole model.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca

from designkit.models.euler_lagrange import Lagrangian, christoffel, coriolis_from_christoffel, lagrangian
from designkit.models.exact_arithmetic import add, mul, scalar
from designkit.models.inertial_parameters import INERTIAL_NAMES, inertial_parameters, link_inertial_parameters
from designkit.models.newton_euler import rnea

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


def friction_torque(viscous: Sequence[Any], coulomb: Sequence[Any], qd: ca.SX) -> ca.SX:
    """Joint friction ``Fv qd + Fc sign(qd)`` (N*m or N), ``sign(0) = 0``."""
    return ca.vertcat(*[add(mul(scalar(fv), qd[i]), mul(scalar(fc), ca.sign(qd[i])))
                        for i, (fv, fc) in enumerate(zip(viscous, coulomb, strict=True))])


def forward_dynamics(mass_matrix: ca.SX, bias: ca.SX, tau: ca.SX) -> ca.SX:
    """Joint accelerations ``qdd = M^{-1} (tau - bias)`` by ``casadi.solve`` (no explicit inverse)."""
    return ca.solve(mass_matrix, tau - bias)
