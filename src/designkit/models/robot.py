"""A manipulator model: named CasADi functions plus NumPy-in/NumPy-out methods.

:class:`Robot` is built from a :class:`~designkit.models.description.ChainDescription`
(:func:`robot_from_dh`).  Its ``functions`` table holds one named
``casadi.Function`` per quantity, built on first use and cached:

==================== ========================== =======================================
name                 inputs                     outputs (shape)
==================== ========================== =======================================
fkine                q                          T (4x4), tool pose in the base frame
fkine_all            q                          T_all (4 x 4n), ``[T_01, ..., T_0n]``
jacobian             q                          J (6 x n), rows ``[v; omega]``, base frame
jacobian_dot_qd      q, qd                      Jdot_qd (6)
analytic_jacobian    q                          Ja (6 x n), x (6): ``[p; rpy]``
analytic_jacobian_R  q                          same for representation R (rpy, zyz)
inverse_dynamics     q, qd, qdd                 tau (n), Newton--Euler (+ friction, rotors)
mass_matrix          q                          M (n x n), Euler--Lagrange (+ rotors)
christoffel          q                          Gamma (n x n^2), ``[i, j*n+k] = G_ijk``
coriolis_matrix      q, qd                      C (n x n), ``C_ij = sum_k G_ijk qd_k``
gravity_torque       q                          g (n)
friction_torque      qd                         tau_f (n), zero when friction is off
forward_dynamics     q, qd, tau                 qdd (n)
regressor            q, qd, qdd                 W (n x len(P)), ``tau = W P``
parameters           (none)                     P (len(P))
kinetic_energy       q, qd                      T (1)
potential_energy     q                          V (1)
==================== ========================== =======================================

When the description holds CasADi symbols (``description.symbols``), every
function takes one more, last, input ``"p"``: the symbols stacked in the order
of ``description.symbols``; the NumPy methods then need ``p=``.

Every NumPy method accepts one state (shape ``(n,)``) or a batch (shape ``(N, n)``,
evaluated with ``casadi.Function.map``) and returns results stacked along a
leading axis of length ``N``.  Units are SI (m, rad, kg, s, N, N*m).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError, SpecError
from designkit.models import chain, dynamics, regressor
from designkit.models.description import ChainDescription, LinkDescription

__all__ = ["Energy", "FunctionTable", "Robot", "robot_from_dh"]

_JOINTS = ("revolute", "prismatic")
_CONVENTIONS = ("standard", "modified")
_MAX_MAPS = 64


@dataclass(frozen=True)
class Energy:
    """Kinetic and potential energy (J), floats or arrays of shape ``(N,)`` for a batch."""

    kinetic: Any
    potential: Any

    @property
    def total(self) -> Any:
        """``kinetic + potential`` (J)."""
        return self.kinetic + self.potential


class _Expressions:
    """Symbols and lazily built ``SX`` expressions shared by the functions of one robot."""

    def __init__(self, description: ChainDescription, friction: bool, motor_inertia: bool) -> None:
        n = description.n
        self.description = description
        self.friction = friction
        self.motor_inertia = motor_inertia
        self.q = ca.SX.sym("q", n)
        self.qd = ca.SX.sym("qd", n)
        self.qdd = ca.SX.sym("qdd", n)
        self.tau = ca.SX.sym("tau", n)
        symbols = [sym for _, sym in description.symbols]
        self.p = ca.vertcat(*symbols) if symbols else None

    @cached_property
    def parameters(self) -> list[Any]:
        return regressor.parameter_vector(self.description, friction=self.friction,
                                          motor_inertia=self.motor_inertia)

    @cached_property
    def frames(self) -> list[ca.SX]:
        return chain.frame_transforms(self.description, self.q)

    @cached_property
    def tool(self) -> ca.SX:
        return chain.tool_pose(self.description, self.q, self.frames)

    @cached_property
    def jacobian(self) -> ca.SX:
        axes = chain.joint_axes(self.description, self.frames)
        return chain.point_jacobian(self.description, axes, self.tool[0:3, 3], self.description.n - 1)

    @cached_property
    def lagrangian(self) -> dynamics.Lagrangian:
        terms = dynamics.lagrangian(self.description, self.q, self.parameters[: 10 * self.description.n])
        # merge the subexpressions the link sums built separately, before differentiating M
        return dataclasses.replace(terms, mass_matrix=ca.cse(terms.mass_matrix))

    @cached_property
    def rotor_inertia(self) -> ca.SX:
        n = self.description.n
        if not self.motor_inertia:
            return ca.SX.zeros(n, n)
        start = len(self.parameters) - n
        return ca.diag(ca.vertcat(*[ca.SX(v) for v in self.parameters[start:]]))

    @cached_property
    def mass_matrix(self) -> ca.SX:
        return self.lagrangian.mass_matrix + self.rotor_inertia

    @cached_property
    def christoffel(self) -> ca.SX:
        return dynamics.christoffel(self.lagrangian.mass_matrix, self.q)

    def inverse_dynamics(self, qdd: Any) -> ca.SX:
        return regressor.inverse_dynamics(self.description, self.q, self.qd, qdd, self.parameters,
                                          friction=self.friction, motor_inertia=self.motor_inertia)

    @cached_property
    def friction_torque(self) -> ca.SX:
        links = self.description.links
        if not self.friction:
            return ca.SX.zeros(len(links), 1)
        return dynamics.friction_torque([lk.viscous for lk in links], [lk.coulomb for lk in links], self.qd)


# name -> (input names, output names, output kinds, builder(expressions) -> list of output SX);
# a kind is "scalar" (1x1 -> float), "vector" (k x 1 -> (k,)) or "matrix" (kept 2-D).
_Spec = tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...], Callable[[_Expressions], list[Any]]]


def _analytic(name: str) -> _Spec:
    def build(e: _Expressions) -> list[Any]:
        ja, x = chain.analytic_jacobian(e.description, e.q, name)
        return [ja, x]

    return ("q",), ("Ja", "x"), ("matrix", "vector"), build


_M, _V, _S = ("matrix",), ("vector",), ("scalar",)

_SPECS: dict[str, _Spec] = {
    "fkine": (("q",), ("T",), _M, lambda e: [e.tool]),
    "fkine_all": (("q",), ("T_all",), _M, lambda e: [ca.horzcat(*e.frames)]),
    "jacobian": (("q",), ("J",), _M, lambda e: [e.jacobian]),
    "jacobian_dot_qd": (("q", "qd"), ("Jdot_qd",), _V,
                        lambda e: [chain.jacobian_dot_qd(e.jacobian, e.q, e.qd)]),
    "analytic_jacobian": _analytic("rpy"),
    **{f"analytic_jacobian_{name}": _analytic(name) for name in chain.REPRESENTATIONS},
    "inverse_dynamics": (("q", "qd", "qdd"), ("tau",), _V, lambda e: [e.inverse_dynamics(e.qdd)]),
    "mass_matrix": (("q",), ("M",), _M, lambda e: [e.mass_matrix]),
    "christoffel": (("q",), ("Gamma",), _M, lambda e: [e.christoffel]),
    "coriolis_matrix": (("q", "qd"), ("C",), _M,
                        lambda e: [dynamics.coriolis_from_christoffel(e.christoffel, e.qd)]),
    "gravity_torque": (("q",), ("g",), _V, lambda e: [e.lagrangian.gravity_torque]),
    "friction_torque": (("qd",), ("tau_f",), _V, lambda e: [e.friction_torque]),
    "forward_dynamics": (("q", "qd", "tau"), ("qdd",), _V, lambda e: [
        dynamics.forward_dynamics(e.mass_matrix, e.inverse_dynamics(ca.SX.zeros(e.description.n)), e.tau)]),
    "regressor": (("q", "qd", "qdd"), ("W",), _M, lambda e: [regressor.regressor(
        e.description, e.q, e.qd, e.qdd, friction=e.friction, motor_inertia=e.motor_inertia)]),
    "parameters": ((), ("P",), _V, lambda e: [ca.vertcat(*[ca.SX(v) for v in e.parameters])]),
    "kinetic_energy": (("q", "qd"), ("T",), _S, lambda e: [0.5 * ca.bilin(e.mass_matrix, e.qd, e.qd)]),
    "potential_energy": (("q",), ("V",), _S, lambda e: [e.lagrangian.potential]),
}


class FunctionTable(Mapping[str, ca.Function]):
    """Read-only mapping name -> named ``casadi.Function``, each built on first access and cached."""

    def __init__(self, expressions: _Expressions) -> None:
        self._expressions = expressions
        self._cache: dict[str, ca.Function] = {}

    def __getitem__(self, name: str) -> ca.Function:
        if name not in self._cache:
            try:
                in_names, out_names, _, build = _SPECS[name]
            except KeyError:
                raise KeyError(f"no function {name!r}; available: {sorted(_SPECS)}") from None
            e = self._expressions
            inputs = [getattr(e, arg) for arg in in_names]
            names = list(in_names)
            if e.p is not None:
                inputs.append(e.p)
                names.append("p")
            self._cache[name] = ca.Function(name, inputs, build(e), names, list(out_names))
        return self._cache[name]

    def __contains__(self, name: object) -> bool:
        return name in _SPECS

    def __iter__(self) -> Iterator[str]:
        return iter(_SPECS)

    def __len__(self) -> int:
        return len(_SPECS)


def _validate(description: ChainDescription) -> None:
    """Check the structure of a description; raise :class:`SpecError` naming the field."""
    if not description.links:
        raise SpecError("links", "a chain needs at least one link")
    if description.convention not in _CONVENTIONS:
        raise SpecError("convention", f"must be one of {_CONVENTIONS}, got {description.convention!r}")
    if len(description.gravity) != 3:
        raise SpecError("gravity", f"must have 3 components, got {len(description.gravity)}")
    for key in ("base", "tool"):
        matrix = getattr(description, key)
        if len(matrix) != 4 or any(len(row) != 4 for row in matrix):
            raise SpecError(key, "must be a 4x4 homogeneous transform")
    for i, link in enumerate(description.links):
        if link.joint not in _JOINTS:
            raise SpecError(f"links[{i}].joint", f"must be one of {_JOINTS}, got {link.joint!r}")
        if len(link.com) != 3 or len(link.inertia) != 6:
            raise SpecError(f"links[{i}]", "com needs 3 and inertia 6 components")
        for key in ("mass", "motor_inertia", "viscous", "coulomb"):
            value = chain.numeric_value(getattr(link, key))
            if value is not None and value < 0:
                raise SpecError(f"links[{i}].{key}", f"must be non-negative, got {value}")
    for name, sym in description.symbols:
        if not (isinstance(sym, ca.SX) and sym.is_symbolic()):
            raise SpecError(f"symbols.{name}", "must be a scalar casadi.SX symbol")


@dataclass(frozen=True, eq=False)
class Robot:
    """A serial manipulator with symbolic kinematics and dynamics.

    Parameters
    ----------
    description : ChainDescription
        Kinematic and inertial data (SI units).
    friction : bool, default False
        Add joint friction ``fv qd + fc sign(qd)`` to the inverse and forward
        dynamics and the regressor (parameters ``fv_i, fc_i``).
    motor_inertia : bool, default False
        Add the reflected rotor inertia ``Ia_i = gear_ratio_i^2 motor_inertia_i`` to
        ``M_ii`` (parameters ``Ia_i``).

    Attributes
    ----------
    functions : FunctionTable
        Named ``casadi.Function`` objects, see the module docstring.
    parameter_names : tuple of str
        Names of the entries of ``P`` (:func:`designkit.models.regressor.parameter_names`).
    parameters : numpy.ndarray or None
        Numeric ``P``; ``None`` when the description is symbolic (use :meth:`parameter_values`).

    Examples
    --------
    >>> from designkit.models.robots import robot
    >>> arm = robot("planar2r")
    >>> arm.inverse_dynamics([0.0, 0.0], [0.0, 0.0], [0.0, 0.0]).shape
    (2,)
    """

    description: ChainDescription
    friction: bool = False
    motor_inertia: bool = False
    functions: FunctionTable = field(init=False, repr=False)
    parameter_names: tuple[str, ...] = field(init=False, repr=False)
    parameters: np.ndarray | None = field(init=False, repr=False)
    _maps: dict[tuple[str, int], ca.Function] = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self) -> None:
        _validate(self.description)
        expressions = _Expressions(self.description, self.friction, self.motor_inertia)
        object.__setattr__(self, "functions", FunctionTable(expressions))
        names = regressor.parameter_names(self.n, friction=self.friction, motor_inertia=self.motor_inertia)
        object.__setattr__(self, "parameter_names", names)
        values = [chain.numeric_value(v) for v in expressions.parameters]
        numeric = None if any(v is None for v in values) else np.array(values, dtype=float)
        object.__setattr__(self, "parameters", numeric)

    @property
    def name(self) -> str:
        """Robot name."""
        return self.description.name

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.description.n

    @property
    def symbol_names(self) -> tuple[str, ...]:
        """Names of the symbolic parameters, the order of the ``p`` input."""
        return tuple(name for name, _ in self.description.symbols)

    # ---------------------------------------------------------------- evaluation machinery

    def _evaluate(self, name: str, args: Sequence[tuple[str, Any]], p: Any) -> tuple[list[np.ndarray], int | None]:
        function = self.functions[name]
        arrays: list[np.ndarray] = []
        batch: int | None = None
        for index, (label, value) in enumerate(args):
            size = function.size1_in(index)
            array = np.asarray(value, dtype=float)
            if array.ndim == 1 and array.shape[0] == size:
                arrays.append(array.reshape(size, 1))
            elif array.ndim == 2 and array.shape[1] == size:
                if batch is not None and array.shape[0] != batch:
                    raise SpecError(label, f"batch of {array.shape[0]} rows, other inputs have {batch}")
                batch = array.shape[0]
                arrays.append(array.T)
            else:
                raise SpecError(label, f"expected shape ({size},) or (N, {size}), got {array.shape}")
        if self.description.symbols:
            if p is None:
                raise SpecError("p", f"symbolic robot: give values for {self.symbol_names}")
            p_array = np.asarray(p, dtype=float).reshape(-1)
            if p_array.shape[0] != len(self.description.symbols):
                raise SpecError("p", f"expected {len(self.description.symbols)} values, got {p_array.shape[0]}")
            arrays.append(p_array.reshape(-1, 1))
        elif p is not None:
            raise SpecError("p", "this robot has no symbolic parameters")
        if batch is None:
            outputs = function.call([ca.DM(a) for a in arrays])
            return [np.array(out) for out in outputs], None
        key = (name, batch)
        if key not in self._maps:
            if len(self._maps) >= _MAX_MAPS:  # a memo, not a store: forget old batch sizes
                self._maps.clear()
            self._maps[key] = function.map(batch)
        outputs = self._maps[key].call([ca.DM(a) for a in arrays])
        shaped = []
        for index, out in enumerate(outputs):
            rows, cols = function.size_out(index)
            shaped.append(np.array(out).reshape(rows, batch, cols).transpose(1, 0, 2))
        return shaped, batch

    @staticmethod
    def _shape(value: np.ndarray, kind: str, batch: int | None) -> Any:
        """Squeeze ``vector`` results to 1-D and ``scalar`` results to floats (or ``(N,)``)."""
        if kind == "scalar":
            return float(value[0, 0]) if batch is None else value[:, 0, 0]
        if kind == "vector":
            return value[..., 0]
        return value

    def _call(self, name: str, args: Sequence[tuple[str, Any]], p: Any) -> Any:
        outputs, batch = self._evaluate(name, args, p)
        return self._shape(outputs[0], _SPECS[name][2][0], batch)

    # ---------------------------------------------------------------- kinematics

    def fkine(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Tool pose in the base frame: ``(4, 4)`` or ``(N, 4, 4)``."""
        return self._call("fkine", [("q", q)], p)

    def fkine_all(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Poses of DH frames ``1..n``: ``(n, 4, 4)`` or ``(N, n, 4, 4)``."""
        out = self._call("fkine_all", [("q", q)], p)
        if out.ndim == 2:
            return out.reshape(4, self.n, 4).transpose(1, 0, 2)
        return out.reshape(out.shape[0], 4, self.n, 4).transpose(0, 2, 1, 3)

    def jacobian(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Geometric Jacobian of the tool origin, base frame, rows ``[v; omega]``: ``(6, n)`` or ``(N, 6, n)``."""
        return self._call("jacobian", [("q", q)], p)

    def jacobian_dot_qd(self, q: Any, qd: Any, *, p: Any = None) -> np.ndarray:
        """``Jdot qd`` (m/s^2, rad/s^2): ``(6,)`` or ``(N, 6)``."""
        return self._call("jacobian_dot_qd", [("q", q), ("qd", qd)], p)

    def analytic_jacobian(self, q: Any, representation: str = "rpy", *, p: Any = None) -> np.ndarray:
        """Analytic Jacobian of ``[p; phi]`` for ``representation`` in ``chain.REPRESENTATIONS``."""
        chain.representation(representation)
        return self._call(f"analytic_jacobian_{representation}", [("q", q)], p)

    # ---------------------------------------------------------------- dynamics

    def inverse_dynamics(self, q: Any, qd: Any, qdd: Any, *, p: Any = None) -> np.ndarray:
        """Joint torques (N*m or N) by recursive Newton--Euler: ``(n,)`` or ``(N, n)``."""
        return self._call("inverse_dynamics", [("q", q), ("qd", qd), ("qdd", qdd)], p)

    def mass_matrix(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Joint-space inertia matrix ``M(q)``: ``(n, n)`` or ``(N, n, n)``."""
        return self._call("mass_matrix", [("q", q)], p)

    def christoffel(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Christoffel symbols ``G[i, j, k]``: ``(n, n, n)`` or ``(N, n, n, n)``."""
        out = self._call("christoffel", [("q", q)], p)
        return out.reshape(*out.shape[:-1], self.n, self.n)

    def coriolis_matrix(self, q: Any, qd: Any, *, p: Any = None) -> np.ndarray:
        """Coriolis matrix ``C(q, qd)`` (Christoffel form, ``Mdot - 2C`` skew): ``(n, n)`` or ``(N, n, n)``."""
        return self._call("coriolis_matrix", [("q", q), ("qd", qd)], p)

    def gravity_torque(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Gravity torque ``g(q) = dV/dq``: ``(n,)`` or ``(N, n)``."""
        return self._call("gravity_torque", [("q", q)], p)

    def friction_torque(self, qd: Any, *, p: Any = None) -> np.ndarray:
        """Joint friction torque (zero when the robot was built without friction)."""
        return self._call("friction_torque", [("qd", qd)], p)

    def forward_dynamics(self, q: Any, qd: Any, tau: Any, *, p: Any = None) -> np.ndarray:
        """Joint accelerations for applied torques: ``(n,)`` or ``(N, n)``."""
        return self._call("forward_dynamics", [("q", q), ("qd", qd), ("tau", tau)], p)

    def regressor(self, q: Any, qd: Any, qdd: Any, *, p: Any = None) -> np.ndarray:
        """Regressor ``W`` with ``tau = W @ P``: ``(n, len(P))`` or ``(N, n, len(P))``."""
        return self._call("regressor", [("q", q), ("qd", qd), ("qdd", qdd)], p)

    def parameter_values(self, p: Any = None) -> np.ndarray:
        """Numeric parameter vector ``P`` (for a symbolic robot, at symbol values ``p``)."""
        return self._call("parameters", [], p).reshape(-1)

    def energy(self, q: Any, qd: Any, *, p: Any = None) -> Energy:
        """Kinetic ``0.5 qd' M qd`` and potential energy (J); arrays of shape ``(N,)`` for a batch."""
        kinetic = self._call("kinetic_energy", [("q", q), ("qd", qd)], p)
        potential = self._call("potential_energy", [("q", q)], p)
        return Energy(kinetic, potential)

    def replace(self, **changes: Any) -> Robot:
        """A new robot with other options (``friction``, ``motor_inertia``) or description."""
        fields = {"description": self.description, "friction": self.friction, "motor_inertia": self.motor_inertia}
        unknown = set(changes) - set(fields)
        if unknown:
            raise SpecError(sorted(unknown)[0], f"unknown option; choose from {sorted(fields)}")
        return Robot(**{**fields, **changes})


def _link(value: Any, index: int) -> LinkDescription:
    if isinstance(value, LinkDescription):
        return value
    if isinstance(value, Mapping):
        try:
            return LinkDescription(**value)
        except TypeError as exc:
            raise SpecError(f"links[{index}]", str(exc)) from None
    raise SpecError(f"links[{index}]", f"must be a LinkDescription or a mapping, got {type(value).__name__}")


def robot_from_dh(
    description: ChainDescription | None = None,
    *,
    friction: bool = False,
    motor_inertia: bool = False,
    **fields: Any,
) -> Robot:
    """Build a :class:`Robot` from a description, or from ``ChainDescription`` fields.

    Parameters
    ----------
    description : ChainDescription, optional
        The chain.  When omitted, ``fields`` are the keyword arguments of
        ``ChainDescription`` (``name``, ``links``, ``convention``, ``gravity``, ...);
        ``links`` may hold mappings of ``LinkDescription`` fields.
    friction, motor_inertia : bool
        Model options, see :class:`Robot`.

    Returns
    -------
    Robot

    Raises
    ------
    SpecError
        For an invalid description (the message names the field).

    Examples
    --------
    >>> import math
    >>> arm = robot_from_dh(name="pendulum", links=[{"a": 1.0, "mass": 2.0, "com": (-0.5, 0, 0)}],
    ...                     gravity=(0.0, -9.81, 0.0))
    >>> round(float(arm.gravity_torque([0.0])[0]), 3)
    9.81
    """
    if description is None:
        links = fields.pop("links", None)
        if links is None:
            raise SpecError("links", "give a description or its links")
        fields.setdefault("name", "robot")
        try:
            description = ChainDescription(links=tuple(_link(v, i) for i, v in enumerate(links)), **fields)
        except TypeError as exc:
            raise SpecError("description", str(exc)) from None
    elif fields:
        try:
            description = dataclasses.replace(description, **fields)
        except TypeError as exc:
            raise SpecError("description", str(exc)) from None
    if not isinstance(description, ChainDescription):
        raise ModelError(f"expected a ChainDescription, got {type(description).__name__}")
    return Robot(description, friction=friction, motor_inertia=motor_inertia)
