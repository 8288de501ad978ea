"""One link driven through an elastic transmission (the notes' ROBEL simulator, appendix B, fig. 5.x).

Physical model (motor angle ``theta_m``, link angle ``theta_l``, spring between
``R1 theta_m`` and ``R2 theta_l``)::

    J1 theta_m'' + B1 theta_m' = Ku u - R1 KR (R1 theta_m - R2 theta_l)
    J2 theta_l'' + B2 theta_l' = R2 KR (R1 theta_m - R2 theta_l) - mgl sin(theta_l) + w

``u`` is the drive input, ``w`` a disturbance torque on the link, and the
optional gravity term takes ``theta_l`` from the downward vertical.  In the
spring-side coordinates ``x = [R1 theta_m, R1 theta_m', R2 theta_l, R2 theta_l']``
used by ROBEL, with ``tau1 = J1/B1``, ``tau2 = J2/B2`` and ``Km = R1 Ku / B1``::

    x1' = x2
    x2' = -x2/tau1 - (KR R1^2/J1)(x1 - x3) + (Km/tau1) u
    x3' = x4
    x4' = -x4/tau2 + (KR R2^2/J2)(x1 - x3) - (R2 mgl/J2) sin(x3/R2) + (R2/J2) w

This is the ``(A, B)`` that the notes' fig. 5.3 gains ``l_i = -A_i' C / (B' C)``
imply (``l1 = (tau1/Km)(KR R1^2/J1 - c4 KR R2^2/J2)``, ..., checked in the tests).
With ``R1 = 1/N``, ``R2 = 1`` it is the usual gear-reduced elastic joint.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from designkit.errors import ModelError
from designkit.models.plant import Parameter, PlantBase, Signal, ode_function

__all__ = ["ElasticJointPlant", "ElasticLinkParameters", "elastic_ode", "elastic_state_space", "rigid_approximation"]


@dataclass(frozen=True)
class ElasticLinkParameters:
    """Parameters of the elastic link, in the notes' (ROBEL) names.

    Parameters
    ----------
    J1 : float
        Motor (rotor) inertia (kg*m^2).
    tau1 : float
        Motor mechanical time constant ``J1/B1`` (s).
    Km : float
        Motor static gain in spring-side coordinates, ``R1 Ku / B1`` (rad/s per input unit).
    KR : float
        Transmission stiffness (N*m/rad).
    R1, R2 : float
        Transmission ratios on the motor and link sides (dimensionless).
    J2 : float
        Link inertia about its joint (kg*m^2).
    tau2 : float
        Link time constant ``J2/B2`` (s); ``math.inf`` for a frictionless link.
    mgl : float
        Gravity torque amplitude ``m g l`` of the link (N*m), 0 to ignore gravity.
    """

    J1: float
    tau1: float
    Km: float
    KR: float
    R1: float
    R2: float
    J2: float
    tau2: float
    mgl: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, int | float) or isinstance(value, bool) or math.isnan(value):
                raise ModelError(f.name, f"must be a number, got {value!r}")
            if f.name == "mgl":
                if value < 0 or math.isinf(value):
                    raise ModelError(f.name, f"must be finite and non-negative, got {value}")
            elif f.name == "tau2":
                if value <= 0:
                    raise ModelError(f.name, f"must be positive (math.inf for no link friction), got {value}")
            elif not (value > 0 and math.isfinite(value)):
                raise ModelError(f.name, f"must be positive and finite, got {value}")

    @property
    def B1(self) -> float:
        """Motor viscous friction ``J1/tau1`` (N*m*s/rad)."""
        return self.J1 / self.tau1

    @property
    def B2(self) -> float:
        """Link viscous friction ``J2/tau2`` (N*m*s/rad)."""
        return self.J2 / self.tau2

    @property
    def Ku(self) -> float:
        """Motor torque per input unit ``Km B1 / R1`` (N*m per input unit)."""
        return self.Km * self.B1 / self.R1


def elastic_state_space(params: ElasticLinkParameters) -> tuple[np.ndarray, np.ndarray]:
    """Linear model ``x' = A x + B u`` in spring-side coordinates (gravity linearised at ``x = 0``).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``A`` (4x4, 1/s and 1/s^2) and ``B`` (4x1).
    """
    k1 = params.KR * params.R1**2 / params.J1
    k2 = params.KR * params.R2**2 / params.J2
    grav = params.mgl / params.J2
    A = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-k1, -1.0 / params.tau1, k1, 0.0],
        [0.0, 0.0, 0.0, 1.0],
        [k2, 0.0, -k2 - grav, -1.0 / params.tau2],
    ])
    B = np.array([[0.0], [params.Km / params.tau1], [0.0], [0.0]])
    return A, B


def rigid_approximation(params: ElasticLinkParameters) -> tuple[float, float]:
    """The rigid link ``x'' = -x'/tau + (Km/tau) u`` the joint becomes with an infinitely stiff transmission.

    With ``x1 = x3 = x`` (``theta_m = x/R1``, ``theta_l = x/R2``) the spring torque ``T = KR (x1 - x3)`` is
    eliminated between the two equations of motion (the motor's divided by ``R1``, the link's by ``R2``, added)::

        (J1/R1^2 + J2/R2^2) x'' + (B1/R1^2 + B2/R2^2) x' = (Ku/R1) u + w/R2 - (mgl/R2) sin(x/R2)

    so ``tau = Jeq/Beq`` and ``Km = (Ku/R1)/Beq = Km_motor (B1/R1^2)/Beq`` (``Ku/R1 = Km_motor B1/R1^2``), with
    ``Jeq = J1/R1^2 + J2/R2^2`` (kg*m^2) and ``Beq = B1/R1^2 + B2/R2^2`` (N*m*s/rad).

    Returns
    -------
    (float, float)
        ``Km`` (spring-side rad/s per input unit) and ``tau`` (s) of the rigid link (gravity ignored).
    """
    j_eq = params.J1 / params.R1**2 + params.J2 / params.R2**2
    b_motor = params.B1 / params.R1**2
    b_eq = b_motor + params.B2 / params.R2**2
    return params.Km * b_motor / b_eq, j_eq / b_eq


_PARAMETER_INFO: dict[str, tuple[str, str]] = {
    "J1": ("kg*m^2", "motor (rotor) inertia"),
    "tau1": ("s", "motor time constant J1/B1"),
    "Km": ("(rad/s)/V", "motor static gain R1 Ku/B1"),
    "KR": ("N*m/rad", "transmission stiffness"),
    "R1": ("1", "motor-side transmission ratio"),
    "R2": ("1", "link-side transmission ratio"),
    "J2": ("kg*m^2", "link inertia"),
    "tau2": ("s", "link time constant J2/B2"),
    "mgl": ("N*m", "gravity torque amplitude"),
}


@functools.cache
def _elastic_ode() -> ca.Function:
    """The elastic-joint ODE, symbolic in ``p = (J1, tau1, Km, KR, R1, R2, J2, tau2, mgl)``."""
    x, u, w = ca.SX.sym("x", 4), ca.SX.sym("u"), ca.SX.sym("d")
    p = ca.SX.sym("p", len(_PARAMETER_INFO))
    J1, tau1, Km, KR, R1, R2, J2, tau2, mgl = ca.vertsplit(p)
    stretch = x[0] - x[2]
    xdot = ca.vertcat(
        x[1],
        -x[1] / tau1 - KR * R1**2 / J1 * stretch + Km / tau1 * u,
        x[3],
        -x[3] / tau2 + KR * R2**2 / J2 * stretch - R2 * mgl / J2 * ca.sin(x[2] / R2) + R2 / J2 * w,
    )
    return ode_function("elastic_joint_ode", x, u, w, p, xdot)


def elastic_ode(params: ElasticLinkParameters) -> ca.Function:
    """Nonlinear elastic-link dynamics at ``params`` as a named CasADi function.

    Returns
    -------
    casadi.Function
        ``"elastic_link"``: ``x`` (4, spring-side coordinates, rad and rad/s), ``u`` (input),
        ``w`` (link disturbance torque, N*m) -> ``xdot`` (4); :meth:`ElasticJointPlant.ode` with
        the parameters fixed.
    """
    plant = ElasticJointPlant(params)
    x, u, w = ca.SX.sym("x", 4), ca.SX.sym("u"), ca.SX.sym("w")
    xdot = plant.ode()(x, u, w, ca.DM(plant.parameter_vector))
    return ca.Function("elastic_link", [x, u, w], [xdot], ["x", "u", "w"], ["xdot"])


@dataclass(frozen=True)
class ElasticJointPlant(PlantBase):
    """The ROBEL elastic joint as a :class:`~designkit.models.plant.Plant` (4 states, spring-side coordinates).

    States ``x1 = R1 theta_m`` (rad), ``x2`` its rate, ``x3 = R2 theta_l`` (rad, the controlled
    link position), ``x4`` its rate; input ``u``; disturbance ``w`` (N*m on the link).

    Parameters
    ----------
    params : ElasticLinkParameters
        Physical parameters (see :class:`ElasticLinkParameters`).

    Examples
    --------
    >>> from designkit.models.robots.elastic_link import DEFAULTS
    >>> plant = ElasticJointPlant(DEFAULTS)
    >>> plant.positions, plant.velocities, len(plant.parameters)
    ((2,), (3,), 9)
    """

    params: ElasticLinkParameters

    kind: ClassVar[str] = "elastic_joint"
    states: ClassVar[tuple[Signal, ...]] = (
        Signal("x1", "rad", "motor angle R1 theta_m"), Signal("x2", "rad/s", "motor speed"),
        Signal("x3", "rad", "link angle R2 theta_l"), Signal("x4", "rad/s", "link speed"),
    )
    inputs: ClassVar[tuple[Signal, ...]] = (Signal("u", "V", "drive input voltage (motor torque Ku u, N*m)"),)
    disturbances: ClassVar[tuple[Signal, ...]] = (Signal("w", "N*m", "disturbance torque on the link"),)
    positions: ClassVar[tuple[int, ...]] = (2,)
    velocities: ClassVar[tuple[int, ...]] = (3,)

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """The nine physical parameters with units (``mgl`` may be 0)."""
        return tuple(Parameter(name, float(getattr(self.params, name)), unit, meaning, positive=name != "mgl")
                     for name, (unit, meaning) in _PARAMETER_INFO.items())

    def ode(self) -> ca.Function:
        """``elastic_joint_ode: (x[4], u, d = w, p[9]) -> xdot[4]``."""
        return _elastic_ode()

    def rest_state(self, q: Any) -> np.ndarray:
        """At rest with the link at ``q`` (spring-side rad) and the spring unstretched (``x1 = x3 = q``)."""
        arr = np.asarray(q, dtype=float).reshape(-1)
        if arr.size != 1:
            raise ModelError("q", f"needs 1 entry, got {arr.size}")
        return np.array([arr[0], 0.0, arr[0], 0.0])

    def equations(self) -> tuple[str, ...]:
        """The model in plain text."""
        return (
            "x1' = x2,   x2' = -x2/τ1 - (KR R1²/J1)(x1 - x3) + (Km/τ1) u",
            "x3' = x4,   x4' = -x4/τ2 + (KR R2²/J2)(x1 - x3) - (R2 mgl/J2) sin(x3/R2) + (R2/J2) w",
        )

    def _replace(self, values: Mapping[str, float]) -> ElasticJointPlant:
        return ElasticJointPlant(dataclasses.replace(self.params, **values))
