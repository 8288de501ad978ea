"""A serial manipulator as a :class:`~designkit.models.plant.Plant`: any :class:`~designkit.models.robot.Robot`.

States ``x = (q, qd)`` (rad or m, rad/s or m/s per joint type), inputs ``u`` the joint torques
(N*m or N), disturbances ``d`` torques added to ``u`` (load, unmodelled forces); the ODE is
``q' = qd``, ``qd' = M(q)^-1 (u + d - C(q, qd) qd - g(q) - F(qd))`` from the model layer's forward
dynamics (``casadi.solve``, friction and rotor inertia as the robot's options say).

The robot is built *symbolic in its named parameters* once; a plant holds the numeric values,
so :meth:`RobotPlant.with_params` (robustness sweeps, model mismatch) never rebuilds the model:

* a zoo robot (:func:`zoo_plant`) exposes the parameters of its module's ``DEFAULTS`` (e.g. the
  SIMNOG arm's ``m1, m2, d1, d2, I1, I2, f1, f2, g``) with the units of its ``UNITS`` table;
* a DH or URDF chain (:func:`chain_plant`) exposes each link's mass ``m<i>`` (kg) and viscous
  friction ``f<i>`` (1-based), the data a user most often varies; every other number is fixed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import casadi as ca

from designkit import arguments
from designkit.errors import ModelError
from designkit.models.chain import numeric_value
from designkit.models.description import ChainDescription
from designkit.models.plant import Parameter, PlantBase, Signal, named, ode_function
from designkit.models.robot import Robot

__all__ = ["RobotPlant", "chain_plant", "zoo_plant"]

_NON_NEGATIVE_UNITS = frozenset({"kg", "kg*m^2", "N*m*s/rad", "N*s/m", "N*m", "m/s^2"})


@dataclass(frozen=True, eq=False)
class RobotPlant(PlantBase):
    """A serial manipulator as a plant.

    Parameters
    ----------
    robot : Robot
        The model, symbolic in exactly the parameters listed in ``parameters`` (same order as
        ``robot.symbol_names``).
    parameters : tuple of Parameter
        Named parameters with their values and units.
    source : str
        Where the robot comes from (zoo name, DH table, URDF file), for reports.
    link_masses : tuple of str or None
        For each link, the parameter holding its mass (None when it is not a parameter): where a payload goes.
    payload : (float, int) or None
        The payload this plant carries, ``(mass kg, link)``, already added to the link's mass.

    Examples
    --------
    >>> plant = zoo_plant("planar2r")
    >>> plant.n_joints, [s.name for s in plant.states]
    (2, ['q1', 'q2', 'qd1', 'qd2'])
    >>> plant.with_params(m2=4.0).parameter("m2").value
    4.0
    """

    robot: Robot
    parameters: tuple[Parameter, ...]
    source: str = ""
    link_masses: tuple[str | None, ...] = ()
    payload: tuple[float, int] | None = None

    kind = "robot"

    def __post_init__(self) -> None:
        names = tuple(p.name for p in self.parameters)
        if names != self.robot.symbol_names:
            raise ModelError("parameters", f"must list the robot's symbols {self.robot.symbol_names}, got {names}")

    # ----------------------------------------------------------------- signals

    @cached_property
    def _units(self) -> tuple[tuple[str, str, str], ...]:
        out = []
        for link in self.robot.description.links:
            out.append(("rad", "rad/s", "N*m") if link.joint == "revolute" else ("m", "m/s", "N"))
        return tuple(out)

    @property
    def states(self) -> tuple[Signal, ...]:
        """Joint positions ``q1..qn`` then velocities ``qd1..qdn``."""
        pos = tuple(Signal(f"q{i + 1}", u[0], f"joint {i + 1} position") for i, u in enumerate(self._units))
        vel = tuple(Signal(f"qd{i + 1}", u[1], f"joint {i + 1} velocity") for i, u in enumerate(self._units))
        return pos + vel

    @property
    def inputs(self) -> tuple[Signal, ...]:
        """Joint torques (forces for prismatic joints) ``u1..un``."""
        return tuple(Signal(f"u{i + 1}", u[2], f"joint {i + 1} torque") for i, u in enumerate(self._units))

    @property
    def disturbances(self) -> tuple[Signal, ...]:
        """Disturbance torques ``d1..dn`` added to the inputs."""
        return tuple(Signal(f"d{i + 1}", u[2], f"joint {i + 1} disturbance") for i, u in enumerate(self._units))

    @property
    def positions(self) -> tuple[int, ...]:
        """State indices of ``q``."""
        return tuple(range(self.robot.n))

    @property
    def velocities(self) -> tuple[int, ...]:
        """State indices of ``qd``."""
        return tuple(range(self.robot.n, 2 * self.robot.n))

    # ----------------------------------------------------------------- dynamics

    @cached_property
    def _ode(self) -> ca.Function:
        n = self.robot.n
        x, u, d = ca.SX.sym("x", 2 * n), ca.SX.sym("u", n), ca.SX.sym("d", n)
        p = ca.SX.sym("p", len(self.parameters))
        args = [x[:n], x[n:], u + d] + ([p] if self.parameters else [])
        qdd = self.robot.functions["forward_dynamics"](*args)
        return ode_function(f"{self.robot.name}_ode", x, u, d, p, ca.vertcat(x[n:], qdd))

    def ode(self) -> ca.Function:
        """``<robot>_ode: (x = (q, qd), u, d, p) -> xdot``."""
        return self._ode

    def nonsmooth(self) -> tuple[str, ...]:
        """Coulomb friction ``Fc sign(q̇)`` when the robot has it (see :meth:`PlantBase.nonsmooth`)."""
        if not self.robot.friction:
            return ()
        coulomb = [numeric_value(link.coulomb) for link in self.robot.description.links]
        joints = [j + 1 for j, c in enumerate(coulomb) if c is None or c != 0]
        if not joints:
            return ()
        peak = max((abs(c) for c in coulomb if c is not None), default=0.0)
        return (f"Coulomb friction Fc sign(q̇) on joint{'s' if len(joints) > 1 else ''} "
                f"{', '.join(map(str, joints))} (up to {peak:.3g} N·m)",)

    def equations(self) -> tuple[str, ...]:
        """The model in plain text."""
        terms = "M(q) q̈ + C(q, q̇) q̇ + g(q)"
        if self.robot.friction:
            terms += " + Fv q̇"
            coulomb = [numeric_value(link.coulomb) for link in self.robot.description.links]
            if any(c is None or c != 0 for c in coulomb):
                terms += " + Fc sign(q̇)"
        rotor = " (M includes the reflected rotor inertias)" if self.robot.motor_inertia else ""
        return (f"{terms} = u + d{rotor}", f"{self.robot.n} joints: {self.source or self.robot.name}")

    def _replace(self, values: Mapping[str, float]) -> RobotPlant:
        return dataclasses.replace(self, parameters=named(self.parameters, values))

    def with_payload(self, mass: float, link: int | None = None) -> RobotPlant:
        """The robot carrying a payload of ``mass`` (kg) concentrated at the centre of mass of ``link``
        (1-based, default the last): the link's mass parameter grows by ``mass``.

        Raises
        ------
        ModelError
            ``link`` out of range (field ``payload.link``) or a link whose mass is not a parameter.
        """
        n = self.robot.n
        link = n if link is None else int(link)
        if not 1 <= link <= n:
            raise ModelError("payload.link", f"this robot has links 1..{n}, got {link}")
        name = self.link_masses[link - 1] if len(self.link_masses) == n else None
        if name is None:
            raise ModelError("payload.link", f"link {link}'s mass is not a parameter of this robot")
        base = self.without_payload()
        carried = base.with_params(**{name: base.parameter(name).value + float(mass)})
        return dataclasses.replace(carried, payload=(float(mass), link))

    def without_payload(self) -> RobotPlant:
        """The same robot without the payload it carries (itself when it carries none)."""
        if self.payload is None:
            return self
        mass, link = self.payload
        name = self.link_masses[link - 1]
        return dataclasses.replace(self.with_params(**{name: self.parameter(name).value - mass}), payload=None)

    def with_options(self, *, friction: bool | None = None, motor_inertia: bool | None = None) -> RobotPlant:
        """The same robot and parameters with friction or rotor inertia switched (the model is rebuilt once)."""
        options = {k: v for k, v in (("friction", friction), ("motor_inertia", motor_inertia)) if v is not None}
        if all(getattr(self.robot, k) == v for k, v in options.items()):
            return self
        return dataclasses.replace(self, robot=self.robot.replace(**options))

    @property
    def joint_limits(self) -> tuple[tuple[float, float] | None, ...]:
        """Each joint's position limits ``qlim`` from the robot data (rad or m), None where absent."""
        return tuple(tuple(float(v) for v in link.qlim) if link.qlim is not None else None
                     for link in self.robot.description.links)

    def model_parameters(self) -> Any:
        """The ``p`` argument of the robot's functions (``None`` when the robot has no symbols)."""
        return self.parameter_vector if self.parameters else None


def _parameter(name: str, value: float, unit: str, meaning: str) -> Parameter:
    return Parameter(name, float(value), unit, meaning, positive=unit not in _NON_NEGATIVE_UNITS)


def _consistent(robot: Robot, numeric: ChainDescription, method: str | None) -> Robot:
    """``robot`` with the inertias :func:`~designkit.models.physical.nearest_consistent` changes on ``numeric``."""
    if method is None:
        return robot
    from designkit.models.physical import nearest_consistent

    fixed, changes = nearest_consistent(numeric, method)
    links = list(robot.description.links)
    for change in changes:
        k = change.link - 1
        if any(numeric_value(v) is None for v in links[k].inertia):
            raise ModelError("consistent_inertia", f"link {change.link}'s inertia is a named parameter: override it "
                             "with a consistent value instead")
        links[k] = dataclasses.replace(links[k], inertia=fixed.links[k].inertia)
    description = dataclasses.replace(robot.description, links=tuple(links), source=fixed.source)
    return Robot(description, friction=robot.friction, motor_inertia=robot.motor_inertia)


CONSISTENT = ("raise", "nearest")
"""The values of ``consistent_inertia``."""


def _flags(friction: object, motor_inertia: object) -> tuple[bool, bool]:
    return arguments.flag(friction, "friction", error=ModelError), arguments.flag(motor_inertia, "motor_inertia",
                                                                                 error=ModelError)


def zoo_plant(name: str, *, overrides: Mapping[str, float] | None = None, friction: bool = True,
              motor_inertia: bool = False, consistent_inertia: str | None = None) -> RobotPlant:
    """A built-in robot (``planar2r``, ``scara``, ``puma560``, ``onelink``) as a plant.

    Parameters
    ----------
    name : str
        Zoo name (:data:`designkit.models.robots.ROBOTS`).
    overrides : mapping, optional
        Parameter values replacing the module's ``DEFAULTS``.
    friction : bool
        Joint friction (viscous and Coulomb, from the robot data) in the dynamics.
    motor_inertia : bool
        Reflected rotor inertia on the diagonal of ``M``.
    consistent_inertia : {"raise", "nearest"}, optional
        Replace the inertias that are not physically consistent as published
        (:func:`designkit.models.physical.nearest_consistent`); default: as published.

    Raises
    ------
    ModelError
        Unknown robot (field ``robot``) or parameter (field ``parameters.<name>``).
    """
    from designkit.models.robots import ROBOTS, zoo_module

    name = arguments.text(name, "robot", error=ModelError)
    friction, motor_inertia = _flags(friction, motor_inertia)
    if consistent_inertia is not None:
        consistent_inertia = arguments.choice(consistent_inertia, "consistent_inertia", CONSISTENT, error=ModelError)
    if name not in ROBOTS:
        raise ModelError("robot", f"unknown robot {name!r}; choose from {sorted(ROBOTS)}")
    module = zoo_module(name)
    if overrides is not None and not isinstance(overrides, Mapping):
        raise ModelError("overrides", f"must be a mapping of parameter names to values, got {type(overrides).__name__}")
    overrides = dict(overrides or {})
    for key in overrides:
        if key not in module.DEFAULTS:
            raise ModelError(f"parameters.{key}",
                             f"{name} has no parameter {key!r}; choose from {sorted(module.DEFAULTS)}")
    robot = ROBOTS[name](symbolic=True, friction=friction, motor_inertia=motor_inertia)
    if consistent_inertia is not None:
        robot = _consistent(robot, module.description(**overrides), consistent_inertia)
    params = tuple(_parameter(k, overrides.get(k, v), *module.UNITS[k]) for k, v in module.DEFAULTS.items())
    plant = RobotPlant(robot=robot, parameters=params, source=f"zoo robot {name}", link_masses=module.LINK_MASSES)
    try:  # validate the values through the same rule as with_params
        return plant.with_params(**overrides) if overrides else plant
    except ModelError as exc:
        raise ModelError(f"parameters.{exc.field}", exc.message) from None


def chain_plant(description: ChainDescription, *, friction: bool = True, motor_inertia: bool = False,
                source: str = "", consistent_inertia: str | None = None) -> RobotPlant:
    """A DH or URDF chain as a plant whose link masses ``m<i>`` and viscous frictions ``f<i>`` are parameters.

    Parameters
    ----------
    description : ChainDescription
        Numeric chain description (SI units).
    friction, motor_inertia : bool
        As in :func:`zoo_plant`.
    source : str
        Where the description comes from, for reports.
    consistent_inertia : {"raise", "nearest"}, optional
        As in :func:`zoo_plant`.
    """
    arguments.instance(description, "description", ChainDescription, "a ChainDescription", error=ModelError)
    friction, motor_inertia = _flags(friction, motor_inertia)
    source = arguments.text(source, "source", error=ModelError)
    if consistent_inertia is not None:
        consistent_inertia = arguments.choice(consistent_inertia, "consistent_inertia", CONSISTENT, error=ModelError)
        from designkit.models.physical import nearest_consistent

        description, _ = nearest_consistent(description, consistent_inertia)
    links, params = [], []
    for i, link in enumerate(description.links, start=1):
        mass, viscous = numeric_value(link.mass), numeric_value(link.viscous)
        if mass is None or viscous is None:
            raise ModelError(f"links[{i - 1}]", "a chain plant needs a numeric description")
        m, f = ca.SX.sym(f"m{i}"), ca.SX.sym(f"f{i}")
        links.append(dataclasses.replace(link, mass=m, viscous=f))
        joint_unit = "N*m*s/rad" if link.joint == "revolute" else "N*s/m"
        params += [(f"m{i}", m, _parameter(f"m{i}", mass, "kg", f"link {i} mass")),
                   (f"f{i}", f, _parameter(f"f{i}", viscous, joint_unit, f"joint {i} viscous friction"))]
    symbolic = dataclasses.replace(description, links=tuple(links), symbols=tuple((n, s) for n, s, _ in params))
    robot = Robot(symbolic, friction=friction, motor_inertia=motor_inertia)
    return RobotPlant(robot=robot, parameters=tuple(p for _, _, p in params), source=source or description.name,
                      link_masses=tuple(f"m{i}" for i in range(1, len(links) + 1)))
