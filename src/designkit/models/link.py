"""Simplified model of one link (course notes, section 1.2, fig. 2.2).

Each joint, with the others' coupling lumped into a disturbance ``xi``, is seen as::

    x1' = x2
    x2' = -(1/tau) x2 + (Km/tau) (u + xi)

Derivation.  Freeze the configuration ``q`` and keep only the diagonal inertia:
``D_ii(q) x1'' + f_i x1' = u + xi`` with ``f_i`` the joint viscous friction (plus any
actuator damping, e.g. back-EMF ``Kt*Ke/R`` reflected to the joint), in N*m*s/rad.
Dividing by ``f_i``::

    (D_ii/f_i) x1'' + x1' = (1/f_i) (u + xi)

so ``tau_i = D_ii(q)/f_i`` (s) and ``Km_i = 1/f_i`` (rad/s per N*m): the steady
speed per unit torque.  The notes print ``K_mi = 1/alpha_ji`` (OCR'd as
"1/i_i") -- consistent with this -- but ``tau_i = alpha_ji/D_ii``, which is
dimensionally 1/s: a misprint for ``D_ii/alpha_ji``.

Joint indices here are 0-based (``i = 0`` is the notes' link 1).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import casadi as ca
import numpy as np

from designkit.errors import ModelError
from designkit.models.chain import numeric_value
from designkit.models.plant import Parameter, PlantBase, Signal, ode_function

if TYPE_CHECKING:
    from designkit.models.robot import Robot

__all__ = ["LinkParameters", "LinkPlant", "LinkRange", "link_ode", "link_range", "simplified_link"]


_LINK_STATES = (Signal("x1", "rad", "link position"), Signal("x2", "rad/s", "link speed"))
_LINK_INPUTS = (Signal("u", "N*m", "control torque"),)
_LINK_DISTURBANCES = (Signal("xi", "N*m", "input-equivalent perturbation"),)


@functools.cache
def _link_ode() -> ca.Function:
    """The one link ODE of the code base, symbolic in ``p = (Km, tau)``."""
    x, u, d, p = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("d"), ca.SX.sym("p", 2)
    Km, tau = p[0], p[1]
    xdot = ca.vertcat(x[1], -x[1] / tau + Km / tau * (u + d))
    return ode_function("link_ode", x, u, d, p, xdot)


@dataclass(frozen=True)
class LinkPlant(PlantBase):
    """Simplified link ``x1' = x2``, ``x2' = -(1/tau) x2 + (Km/tau) (u + xi)`` (a :class:`Plant`).

    Parameters
    ----------
    Km : float
        Static gain (rad/s per N*m, or m/s per N for a prismatic joint); ``> 0``.
    tau : float
        Time constant (s); ``> 0``.

    Raises
    ------
    ModelError
        When a field is not a positive finite number (the error names the field).

    Examples
    --------
    >>> plant = LinkPlant(Km=2.0, tau=0.5)
    >>> plant.rhs([0.0, 1.0], [1.0]).tolist()   # x2' = -1/0.5 + (2/0.5) * 1
    [1.0, 2.0]
    >>> plant.with_params(tau=0.25).tau
    0.25
    """

    Km: float
    tau: float

    kind: ClassVar[str] = "link"
    states: ClassVar[tuple[Signal, ...]] = _LINK_STATES
    inputs: ClassVar[tuple[Signal, ...]] = _LINK_INPUTS
    disturbances: ClassVar[tuple[Signal, ...]] = _LINK_DISTURBANCES
    positions: ClassVar[tuple[int, ...]] = (0,)
    velocities: ClassVar[tuple[int, ...]] = (1,)
    hull_parameters: ClassVar[tuple[str, ...]] = ("Km", "tau")
    """Under a controller of fixed linear gains the closed-loop ``A`` is affine in ``(1/tau, Km/tau)``, and that
    map sends any box of ``(Km, tau)`` onto the convex hull of its corners' images (bounded by ``a = 1/tau_hi``,
    ``a = 1/tau_lo``, ``b = Km_lo a``, ``b = Km_hi a``): what holds at the corners for every matrix of their hull
    holds for the whole box."""

    def __post_init__(self) -> None:
        for name in ("Km", "tau"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
                raise ModelError(name, f"must be a number, got {value!r}")
            if not (math.isfinite(value) and value > 0):
                raise ModelError(name, f"must be positive and finite, got {value}")

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """``Km`` ((rad/s)/(N*m)) and ``tau`` (s)."""
        return (Parameter("Km", float(self.Km), "(rad/s)/(N*m)", "link gain"),
                Parameter("tau", float(self.tau), "s", "link time constant"))

    def ode(self) -> ca.Function:
        """``link_ode: (x[2], u, d = xi, p = (Km, tau)) -> xdot[2]``."""
        return _link_ode()

    def equations(self) -> tuple[str, ...]:
        """The model in plain text."""
        return ("x1' = x2", "x2' = -x2/τ + (Km/τ)(u + ξ)")

    def _replace(self, values: Mapping[str, float]) -> LinkPlant:
        return LinkPlant(Km=values.get("Km", self.Km), tau=values.get("tau", self.tau))


@dataclass(frozen=True)
class LinkParameters(LinkPlant):
    """A :class:`LinkPlant` derived from a manipulator model at one configuration.

    Parameters
    ----------
    Km, tau : float
        As in :class:`LinkPlant`: ``Km = 1/damping``, ``tau = inertia/damping``.
    inertia : float
        ``D_ii(q)`` (kg*m^2 or kg), including reflected rotor inertia when the robot has it.
    damping : float
        ``f_i``, viscous friction plus actuator damping (N*m*s/rad or N*s/m).
    """

    inertia: float = field(default=math.nan)
    damping: float = field(default=math.nan)


@dataclass(frozen=True, eq=False)
class LinkRange:
    """Range of the simplified-link parameters of one joint over a workspace box.

    ``Km`` does not depend on ``q`` (``Km_min == Km_max``); ``tau`` follows ``D_ii(q)``.

    Parameters
    ----------
    Km_min, Km_max : float
        Static gain bounds (rad/s per N*m).
    tau_min, tau_max : float
        Time-constant bounds (s).
    q_at_min, q_at_max : numpy.ndarray
        Configurations where ``D_ii`` (hence ``tau``) is smallest and largest.
    inertia_min, inertia_max : float
        The bounds of ``D_ii`` (kg*m^2).
    """

    Km_min: float
    Km_max: float
    tau_min: float
    tau_max: float
    q_at_min: np.ndarray
    q_at_max: np.ndarray
    inertia_min: float = math.nan
    inertia_max: float = math.nan


def _joint_index(robot: Robot, i: int) -> int:
    if not isinstance(i, int | np.integer) or not 0 <= i < robot.n:
        raise ModelError("i", f"must be a joint index in 0..{robot.n - 1}, got {i!r}")
    return int(i)


def _damping(robot: Robot, i: int, extra: float, p: Any) -> float:
    viscous = robot.description.links[i].viscous
    value = numeric_value(viscous)
    if value is None:
        if p is None:
            raise ModelError("p", f"symbolic robot: give values for {robot.symbol_names}")
        syms = ca.vertcat(*[s for _, s in robot.description.symbols])
        value = float(ca.Function("viscous", [syms], [viscous])(np.asarray(p, dtype=float)))
    total = value + float(extra)
    if not total > 0:
        raise ModelError(f"links[{i}].viscous",
                        f"the simplified link needs positive damping (viscous + damping), got {total}")
    return total


def simplified_link(robot: Robot, i: int, q: Any, *, damping: float = 0.0, p: Any = None) -> LinkParameters:
    """Simplified model of joint ``i`` at configuration ``q``.

    Parameters
    ----------
    robot : Robot
        The manipulator.
    i : int
        0-based joint index.
    q : array_like, shape (n,)
        Configuration (rad or m).
    damping : float
        Actuator damping added to the joint's viscous friction (N*m*s/rad).
    p : array_like, optional
        Symbol values for a symbolic robot.

    Returns
    -------
    LinkParameters
        ``Km = 1/f_i``, ``tau = D_ii(q)/f_i``.

    Examples
    --------
    >>> from designkit.models.robots import robot
    >>> link = simplified_link(robot("onelink"), 0, [0.0])
    >>> round(link.tau * link.damping / link.inertia, 12)
    1.0
    """
    i = _joint_index(robot, i)
    f = _damping(robot, i, damping, p)
    inertia = float(robot.mass_matrix(np.asarray(q, dtype=float).reshape(robot.n), p=p)[i, i])
    return LinkParameters(Km=1.0 / f, tau=inertia / f, inertia=inertia, damping=f)


def _grid(i: int, low: np.ndarray, high: np.ndarray, samples: int, max_points: int) -> np.ndarray:
    """Grid over the joints outboard of ``i`` (``D_ii`` does not depend on ``q_0..q_i``)."""
    free = list(range(i + 1, low.size))
    if not free:
        return ((low + high) / 2)[None, :]
    per_axis = max(2, min(samples, int(max_points ** (1.0 / len(free)))))
    axes = [np.linspace(low[j], high[j], per_axis) for j in free]
    mesh = np.meshgrid(*axes, indexing="ij")
    points = np.tile((low + high) / 2, (mesh[0].size, 1))
    for k, j in enumerate(free):
        points[:, j] = mesh[k].ravel()
    return points


def link_range(
    robot: Robot,
    i: int,
    q_low: Any,
    q_high: Any,
    *,
    samples: int = 7,
    damping: float = 0.0,
    max_points: int = 20000,
    p: Any = None,
) -> LinkRange:
    """Bounds of ``Km`` and ``tau`` of joint ``i`` over the box ``q_low <= q <= q_high``.

    Method: ``D_ii`` is evaluated on a grid of ``samples`` points per outboard
    joint (``D_ii`` is independent of joints ``0..i``; at most ``max_points``
    points, fewer per axis when needed), then the best grid points are polished
    by a bounded quasi-Newton search (SciPy L-BFGS-B with the exact CasADi
    gradient of ``D_ii``) for the minimum and for the maximum.

    Parameters
    ----------
    robot : Robot
        The manipulator.
    i : int
        0-based joint index.
    q_low, q_high : array_like, shape (n,)
        Workspace box (rad or m).
    samples : int
        Grid points per outboard joint.
    damping : float
        Actuator damping added to the viscous friction (N*m*s/rad).
    max_points : int
        Cap on the grid size.
    p : array_like, optional
        Symbol values for a symbolic robot.
    """
    i = _joint_index(robot, i)
    low = np.asarray(q_low, dtype=float).reshape(-1)
    high = np.asarray(q_high, dtype=float).reshape(-1)
    if low.size != robot.n or high.size != robot.n:
        raise ModelError("q_low", f"q_low and q_high need {robot.n} entries")
    if np.any(low > high):
        raise ModelError("q_high", "must be >= q_low component-wise")
    if samples < 2:
        raise ModelError("samples", f"must be at least 2, got {samples}")
    f = _damping(robot, i, damping, p)
    points = _grid(i, low, high, samples, max_points)
    values = robot.mass_matrix(points, p=p)[:, i, i]

    q = ca.SX.sym("q", robot.n)
    args = [q] if not robot.description.symbols else [q, ca.DM(np.asarray(p, dtype=float))]
    d_ii = robot.functions["mass_matrix"](*args)[i, i]
    objective = ca.Function("D_ii", [q], [d_ii, ca.gradient(d_ii, q)], ["q"], ["D_ii", "grad"])
    bounds = list(zip(low, high, strict=True))

    def polish(start: np.ndarray, sign: float) -> tuple[float, np.ndarray]:
        def fun(x: np.ndarray) -> tuple[float, np.ndarray]:
            value, grad = objective(x)
            return sign * float(value), sign * np.array(grad).reshape(-1)

        from scipy.optimize import minimize

        result = minimize(fun, start, jac=True, method="L-BFGS-B", bounds=bounds)
        best = sign * float(result.fun)
        start_value = float(objective(start)[0])
        return (best, result.x) if sign * best < sign * start_value else (start_value, start)

    d_min, q_min = polish(points[int(np.argmin(values))], 1.0)
    d_max, q_max = polish(points[int(np.argmax(values))], -1.0)
    return LinkRange(
        Km_min=1.0 / f, Km_max=1.0 / f, tau_min=d_min / f, tau_max=d_max / f,
        q_at_min=np.asarray(q_min), q_at_max=np.asarray(q_max), inertia_min=d_min, inertia_max=d_max,
    )


def link_ode(plant: LinkPlant) -> ca.Function:
    """The simplified link at ``plant``'s parameters as a named CasADi function.

    Returns
    -------
    casadi.Function
        ``"link"``: ``x`` (2: position rad, rate rad/s), ``u`` (N*m), ``xi`` (N*m)
        -> ``xdot`` (2); the plant's :meth:`LinkPlant.ode` with ``p`` fixed.
    """
    x, u, xi = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("xi")
    xdot = plant.ode()(x, u, xi, ca.DM(plant.parameter_vector))
    return ca.Function("link", [x, u, xi], [xdot], ["x", "u", "xi"], ["xdot"])
