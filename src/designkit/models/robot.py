"""A manipulator model: named CasADi functions plus NumPy-in/NumPy-out methods.

:class:`Robot` is built from a :class:`~designkit.models.description.ChainDescription`
(:func:`robot_from_dh`).  Its ``functions`` table
(:class:`~designkit.models.functions.FunctionTable`) holds one named
``casadi.Function`` per quantity -- ``fkine``, ``jacobian``, ``inverse_dynamics``,
``mass_matrix``, ``coriolis_matrix``, ``gravity_torque``, ``forward_dynamics``,
``regressor``, ... (the full list with inputs and outputs is in
:mod:`designkit.models.functions`) -- built on first use and cached.

When the description holds CasADi symbols (``description.symbols``), every
function takes one more, last, input ``"p"``: the symbols stacked in the order
of ``description.symbols``; the NumPy methods then need ``p=``.

Every NumPy method accepts one state (shape ``(n,)``) or a batch (shape ``(N, n)``) and returns
results stacked along a leading axis of length ``N``.  Units are SI (m, rad, kg, s, N, N*m).
The plain call is the fast path, with identical results on every route:

* one state given as float64 arrays (``p`` too, for a symbolic robot) goes through
  :mod:`designkit.models.one_state`: the function compiled to C on its own (loaded from the cache
  at the first call, else built at the ``one_state.COMPILE_CALLS``-th call) and called through a
  native binding that reads the arrays in place (:mod:`designkit.models.native`), else through
  CasADi's buffers; :meth:`Robot.one_state` tells which route runs and why;
* batches, and single states given otherwise (lists, other dtypes), go through
  :mod:`designkit.models.batch`: NumPy arrays handed to CasADi's buffer interface (no
  ``casadi.DM`` conversions) and the function's compiled block when a C compiler is present --
  built once for a batch of at least ``batch.COMPILE_MIN_STATES`` states, cached on disk, loaded
  from the cache by every later robot with the same function; interpreted otherwise.
  :meth:`Robot.evaluator` tells which path runs and why.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit import arguments
from designkit.errors import ModelError
from designkit.models import chain, regressor
from designkit.models.batch import Evaluator, evaluate, evaluator_for, shape_output
from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.functions import FUNCTION_SPECS, Expressions, FunctionTable
from designkit.models.one_state import OneState, OneStateTable

__all__ = ["Energy", "FunctionTable", "Robot", "robot_from_dh"]

_JOINTS = ("revolute", "prismatic")
_CONVENTIONS = ("standard", "modified")
_KINDS = {name: spec.kinds[0] for name, spec in FUNCTION_SPECS.items()}


@dataclass(frozen=True)
class Energy:
    """Kinetic and potential energy (J), floats or arrays of shape ``(N,)`` for a batch."""

    kinetic: Any
    potential: Any

    @property
    def total(self) -> Any:
        """``kinetic + potential`` (J)."""
        return self.kinetic + self.potential


def _validate(description: ChainDescription) -> None:
    """Check the structure of a description; raise :class:`ModelError` naming the field."""
    if not description.links:
        raise ModelError("links", "a chain needs at least one link")
    if description.convention not in _CONVENTIONS:
        raise ModelError("convention", f"must be one of {_CONVENTIONS}, got {description.convention!r}")
    if len(description.gravity) != 3:
        raise ModelError("gravity", f"must have 3 components, got {len(description.gravity)}")
    for key in ("base", "tool"):
        matrix = getattr(description, key)
        if len(matrix) != 4 or any(len(row) != 4 for row in matrix):
            raise ModelError(key, "must be a 4x4 homogeneous transform")
    for i, link in enumerate(description.links):
        if link.joint not in _JOINTS:
            raise ModelError(f"links[{i}].joint", f"must be one of {_JOINTS}, got {link.joint!r}")
        if len(link.com) != 3 or len(link.inertia) != 6:
            raise ModelError(f"links[{i}]", "com needs 3 and inertia 6 components")
        for key in ("mass", "motor_inertia", "viscous", "coulomb"):
            value = chain.numeric_value(getattr(link, key))
            if value is not None and value < 0:
                raise ModelError(f"links[{i}].{key}", f"must be non-negative, got {value}")
    for name, sym in description.symbols:
        if not (isinstance(sym, ca.SX) and sym.is_symbolic()):
            raise ModelError(f"symbols.{name}", "must be a scalar casadi.SX symbol")


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
        Named ``casadi.Function`` objects, see :mod:`designkit.models.functions`.
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
    _evaluators: dict[str, Evaluator] = field(init=False, repr=False, default_factory=dict)
    _one_state: OneStateTable = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        _validate(self.description)
        expressions = Expressions(self.description, self.friction, self.motor_inertia)
        object.__setattr__(self, "functions", FunctionTable(expressions))
        names = regressor.parameter_names(self.n, friction=self.friction, motor_inertia=self.motor_inertia)
        object.__setattr__(self, "parameter_names", names)
        values = [chain.numeric_value(v) for v in expressions.parameters]
        numeric = None if any(v is None for v in values) else np.array(values, dtype=float)
        object.__setattr__(self, "parameters", numeric)
        object.__setattr__(self, "_one_state", OneStateTable(self.functions, 1 if self.symbol_names else 0, _KINDS))

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

    # ---------------------------------------------------------------- evaluation

    def _call(self, name: str, args: Sequence[tuple[str, Any]], p: Any) -> Any:
        outputs, batch = evaluate(self.functions[name], args, p, symbol_names=self.symbol_names,
                                  evaluators=self._evaluators)
        return shape_output(outputs[0], FUNCTION_SPECS[name].kinds[0], batch)

    def evaluator(self, name: str) -> Evaluator:
        """The :class:`~designkit.models.batch.Evaluator` behind the NumPy methods of function ``name``.

        Its ``compiled`` and ``why`` say whether calls run compiled C or the interpreter, and why;
        ``evaluator(name).compile()`` compiles ahead of time (else the policy of
        :mod:`designkit.models.batch` applies).
        """
        return evaluator_for(self.functions[name], self._evaluators, 1 if self.symbol_names else 0)

    def one_state(self, name: str) -> OneState:
        """The :class:`~designkit.models.one_state.OneState` behind one-state calls of function ``name``.

        One state given as float64 arrays of shape ``(size,)`` (and ``p`` as a float64 array for a symbolic
        robot) runs through it; its ``compiled`` and ``why`` say whether that is compiled C, and
        ``one_state(name).compile()`` compiles ahead of time (else the policy of
        :mod:`designkit.models.one_state` applies).
        """
        self.functions[name]  # NameNotFoundError for an unknown name
        return self._one_state.state(name)

    # ---------------------------------------------------------------- kinematics

    def fkine(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Tool pose in the base frame: ``(4, 4)`` or ``(N, 4, 4)``."""
        out = self._one_state["fkine"](q, p)
        return self._call("fkine", [("q", q)], p) if out is None else out

    def fkine_all(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Poses of DH frames ``1..n``: ``(n, 4, 4)`` or ``(N, n, 4, 4)``."""
        out = self._one_state["fkine_all"](q, p)
        if out is None:
            out = self._call("fkine_all", [("q", q)], p)
        if out.ndim == 2:
            return out.reshape(4, self.n, 4).transpose(1, 0, 2)
        return out.reshape(out.shape[0], 4, self.n, 4).transpose(0, 2, 1, 3)

    def jacobian(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Geometric Jacobian of the tool origin, base frame, rows ``[v; omega]``: ``(6, n)`` or ``(N, 6, n)``."""
        out = self._one_state["jacobian"](q, p)
        return self._call("jacobian", [("q", q)], p) if out is None else out

    def jacobian_dot_qd(self, q: Any, qd: Any, *, p: Any = None) -> np.ndarray:
        """``Jdot qd`` (m/s^2, rad/s^2): ``(6,)`` or ``(N, 6)``."""
        out = self._one_state["jacobian_dot_qd"](q, qd, p)
        return self._call("jacobian_dot_qd", [("q", q), ("qd", qd)], p) if out is None else out

    def analytic_jacobian(self, q: Any, representation: str = "rpy", *, p: Any = None) -> np.ndarray:
        """Analytic Jacobian of ``[p; phi]`` for ``representation`` in ``chain.REPRESENTATIONS``."""
        chain.representation(representation)
        name = f"analytic_jacobian_{representation}"
        out = self._one_state[name](q, p)
        return self._call(name, [("q", q)], p) if out is None else out

    # ---------------------------------------------------------------- dynamics

    def inverse_dynamics(self, q: Any, qd: Any, qdd: Any, *, p: Any = None) -> np.ndarray:
        """Joint torques (N*m or N) by recursive Newton--Euler: ``(n,)`` or ``(N, n)``."""
        out = self._one_state["inverse_dynamics"](q, qd, qdd, p)
        return self._call("inverse_dynamics", [("q", q), ("qd", qd), ("qdd", qdd)], p) if out is None else out

    def mass_matrix(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Joint-space inertia matrix ``M(q)``: ``(n, n)`` or ``(N, n, n)``."""
        out = self._one_state["mass_matrix"](q, p)
        return self._call("mass_matrix", [("q", q)], p) if out is None else out

    def christoffel(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Christoffel symbols ``G[i, j, k]``: ``(n, n, n)`` or ``(N, n, n, n)``."""
        out = self._one_state["christoffel"](q, p)
        if out is None:
            out = self._call("christoffel", [("q", q)], p)
        return out.reshape(*out.shape[:-1], self.n, self.n)

    def coriolis_matrix(self, q: Any, qd: Any, *, p: Any = None) -> np.ndarray:
        """Coriolis matrix ``C(q, qd)`` (Christoffel form, ``Mdot - 2C`` skew): ``(n, n)`` or ``(N, n, n)``."""
        out = self._one_state["coriolis_matrix"](q, qd, p)
        return self._call("coriolis_matrix", [("q", q), ("qd", qd)], p) if out is None else out

    def gravity_torque(self, q: Any, *, p: Any = None) -> np.ndarray:
        """Gravity torque ``g(q) = dV/dq``: ``(n,)`` or ``(N, n)``."""
        out = self._one_state["gravity_torque"](q, p)
        return self._call("gravity_torque", [("q", q)], p) if out is None else out

    def friction_torque(self, qd: Any, *, p: Any = None) -> np.ndarray:
        """Joint friction torque (zero when the robot was built without friction)."""
        out = self._one_state["friction_torque"](qd, p)
        return self._call("friction_torque", [("qd", qd)], p) if out is None else out

    def forward_dynamics(self, q: Any, qd: Any, tau: Any, *, p: Any = None) -> np.ndarray:
        """Joint accelerations for applied torques: ``(n,)`` or ``(N, n)``."""
        out = self._one_state["forward_dynamics"](q, qd, tau, p)
        return self._call("forward_dynamics", [("q", q), ("qd", qd), ("tau", tau)], p) if out is None else out

    def regressor(self, q: Any, qd: Any, qdd: Any, *, p: Any = None) -> np.ndarray:
        """Regressor ``W`` with ``tau = W @ P``: ``(n, len(P))`` or ``(N, n, len(P))``."""
        out = self._one_state["regressor"](q, qd, qdd, p)
        return self._call("regressor", [("q", q), ("qd", qd), ("qdd", qdd)], p) if out is None else out

    def parameter_values(self, p: Any = None) -> np.ndarray:
        """Numeric parameter vector ``P`` (for a symbolic robot, at symbol values ``p``)."""
        return self._call("parameters", [], p).reshape(-1)

    def energy(self, q: Any, qd: Any, *, p: Any = None) -> Energy:
        """Kinetic ``0.5 qd' M qd`` and potential energy (J); arrays of shape ``(N,)`` for a batch."""
        kinetic = self._one_state["kinetic_energy"](q, qd, p)
        if kinetic is None:
            kinetic = self._call("kinetic_energy", [("q", q), ("qd", qd)], p)
        potential = self._one_state["potential_energy"](q, p)
        if potential is None:
            potential = self._call("potential_energy", [("q", q)], p)
        return Energy(kinetic, potential)

    def replace(self, **changes: Any) -> Robot:
        """A new robot with other options (``friction``, ``motor_inertia``) or description."""
        fields = {"description": self.description, "friction": self.friction, "motor_inertia": self.motor_inertia}
        unknown = set(changes) - set(fields)
        if unknown:
            raise ModelError(sorted(unknown)[0], f"unknown option; choose from {sorted(fields)}")
        return Robot(**{**fields, **changes})


def _link(value: Any, index: int) -> LinkDescription:
    if isinstance(value, LinkDescription):
        return value
    if isinstance(value, Mapping):
        try:
            return LinkDescription(**value)
        except TypeError as exc:
            raise ModelError(f"links[{index}]", str(exc)) from None
    raise ModelError(f"links[{index}]", f"must be a LinkDescription or a mapping, got {type(value).__name__}")


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
    ModelError
        For an invalid description (the message names the field).

    Examples
    --------
    >>> import math
    >>> arm = robot_from_dh(name="pendulum", links=[{"a": 1.0, "mass": 2.0, "com": (-0.5, 0, 0)}],
    ...                     gravity=(0.0, -9.81, 0.0))
    >>> round(float(arm.gravity_torque([0.0])[0]), 3)
    9.81
    """
    friction = arguments.flag(friction, "friction", error=ModelError)
    motor_inertia = arguments.flag(motor_inertia, "motor_inertia", error=ModelError)
    if description is None:
        links = fields.pop("links", None)
        if links is None:
            raise ModelError("links", "give a description or its links")
        fields.setdefault("name", "robot")
        try:
            description = ChainDescription(links=tuple(_link(v, i) for i, v in enumerate(links)), **fields)
        except TypeError as exc:
            raise ModelError("description", str(exc)) from None
    elif fields:
        try:
            description = dataclasses.replace(description, **fields)
        except TypeError as exc:
            raise ModelError("description", str(exc)) from None
    arguments.instance(description, "description", ChainDescription, "a ChainDescription", error=ModelError)
    return Robot(description, friction=friction, motor_inertia=motor_inertia)
