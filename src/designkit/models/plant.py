"""The plant protocol: one interface for every model a controller is designed for and simulated on.

A plant is a frozen value with

* named **states** ``x``, **inputs** ``u`` (what the controller commands), **disturbances** ``d``
  (what enters unmeasured: load torques, the notes' input-equivalent perturbation ``xi``) and
  **parameters** ``p`` (physical constants with nominal values), each a :class:`Signal` or
  :class:`Parameter` with its unit;
* one CasADi ODE ``ode: (x, u, d, p) -> xdot``, the only place its dynamics are written;
* which states are the joint **positions** and **velocities** (the controlled outputs and their
  rates), so that references, requirements and figures can be laid out per joint;
* :meth:`~PlantBase.linearize` (Jacobians of the ODE at an operating point, as a
  :class:`~designkit.models.linear_system.LinearSystem`) and :meth:`~PlantBase.with_params`
  (the same plant with other parameter values, for robustness sweeps and model mismatch).

Implementations: :class:`~designkit.models.link.LinkPlant` (the notes' simplified link),
:class:`~designkit.models.robot_plant.RobotPlant` (any serial :class:`~designkit.models.robot.Robot`)
and :class:`~designkit.models.elastic.ElasticJointPlant` (the ROBEL elastic joint).  Because the
parameters are an input of the ODE, one symbolic model serves every parameter value: a
robustness sweep maps the same CasADi function over many ``p``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import casadi as ca
import numpy as np

from designkit.errors import ModelError
from designkit.models.linear_system import LinearSystem

__all__ = ["Parameter", "Plant", "PlantBase", "Signal", "named", "ode_function", "signals"]


@dataclass(frozen=True)
class Signal:
    """A named signal of a plant.

    Parameters
    ----------
    name : str
        Identifier (``"x1"``, ``"q2"``, ``"u1"``).
    unit : str
        SI unit (``"rad"``, ``"rad/s"``, ``"N*m"``).
    meaning : str
        What it is, in a few words.
    """

    name: str
    unit: str
    meaning: str = ""


@dataclass(frozen=True)
class Parameter:
    """A named physical parameter with its nominal value.

    Parameters
    ----------
    name : str
        Identifier, as used in ``with_params`` and in a spec's ``uncertainty``.
    value : float
        Value (``unit``).
    unit : str
        SI unit.
    meaning : str
        What it is.
    positive : bool
        Whether the model needs it strictly positive (``with_params`` refuses other values).
    """

    name: str
    value: float
    unit: str
    meaning: str = ""
    positive: bool = True


@runtime_checkable
class Plant(Protocol):
    """What the pipeline needs from a plant (see the module docstring)."""

    @property
    def kind(self) -> str: ...  # noqa: D102

    @property
    def states(self) -> tuple[Signal, ...]: ...  # noqa: D102

    @property
    def inputs(self) -> tuple[Signal, ...]: ...  # noqa: D102

    @property
    def disturbances(self) -> tuple[Signal, ...]: ...  # noqa: D102

    @property
    def parameters(self) -> tuple[Parameter, ...]: ...  # noqa: D102

    @property
    def positions(self) -> tuple[int, ...]: ...  # noqa: D102

    @property
    def velocities(self) -> tuple[int, ...]: ...  # noqa: D102

    def ode(self) -> ca.Function: ...  # noqa: D102

    def linearize(self, x0: Any, u0: Any, d0: Any = None) -> LinearSystem: ...  # noqa: D102

    def with_params(self, **values: float) -> Plant: ...  # noqa: D102

    def equations(self) -> tuple[str, ...]: ...  # noqa: D102


def ode_function(name: str, x: ca.SX, u: ca.SX, d: ca.SX, p: ca.SX, xdot: ca.SX) -> ca.Function:
    """The named ODE ``name: (x, u, d, p) -> xdot`` every plant returns from ``ode()``."""
    return ca.Function(name, [x, u, d, p], [xdot], ["x", "u", "d", "p"], ["xdot"])


class PlantBase(ABC):
    """Shared implementation of the :class:`Plant` protocol.

    Subclasses provide ``kind``, the signal tuples, ``parameters``, ``positions``,
    ``velocities``, ``ode()``, ``equations()`` and ``_replace(values)`` (a new plant with the
    given parameter values, already validated by :meth:`with_params`).
    """

    kind: str

    # ----------------------------------------------------------------- sizes and lookups

    @property
    def n_states(self) -> int:
        """Number of states."""
        return len(self.states)  # type: ignore[attr-defined]

    @property
    def n_inputs(self) -> int:
        """Number of inputs."""
        return len(self.inputs)  # type: ignore[attr-defined]

    @property
    def n_disturbances(self) -> int:
        """Number of disturbances."""
        return len(self.disturbances)  # type: ignore[attr-defined]

    @property
    def n_joints(self) -> int:
        """Number of controlled joints (position states)."""
        return len(self.positions)  # type: ignore[attr-defined]

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the parameters, in the order of the ``p`` input of :meth:`ode`."""
        return tuple(par.name for par in self.parameters)  # type: ignore[attr-defined]

    @property
    def parameter_vector(self) -> np.ndarray:
        """Nominal parameter values in the order of the ``p`` input (read-only)."""
        out = np.array([par.value for par in self.parameters], dtype=float)  # type: ignore[attr-defined]
        out.setflags(write=False)
        return out

    def parameter(self, name: str) -> Parameter:
        """The parameter called ``name``; :class:`ModelError` naming it otherwise."""
        for par in self.parameters:  # type: ignore[attr-defined]
            if par.name == name:
                return par
        raise ModelError(name, f"unknown parameter; this {self.kind} plant has {list(self.parameter_names)}")

    def nonsmooth(self) -> tuple[str, ...]:
        """The plant's terms that are not differentiable at rest, in words (``()``: a smooth plant).

        A linearization at rest leaves them out (CasADi's derivative of ``sign`` is zero), so a small-signal
        comparison of the simulated loop with its linearization does not apply to a plant that has any.
        """
        return ()

    def rest_state(self, q: Any) -> np.ndarray:
        """The state at rest with the joints at positions ``q`` (every other state zero)."""
        x = np.zeros(self.n_states)
        x[list(self.positions)] = _vector(q, self.n_joints, "q")  # type: ignore[attr-defined]
        return x

    # ----------------------------------------------------------------- derived functions

    def ode_at(self, p: Any = None) -> ca.Function:
        """``(x, u, d) -> xdot`` with the parameters fixed (nominal values by default)."""
        f = self.ode()  # type: ignore[attr-defined]
        pv = self.parameter_vector if p is None else np.asarray(p, dtype=float)
        x, u, d = (ca.SX.sym(k, f.size1_in(i)) for i, k in enumerate(("x", "u", "d")))
        return ca.Function(f"{f.name()}_nominal", [x, u, d], [f(x, u, d, ca.DM(pv))], ["x", "u", "d"], ["xdot"])

    def rhs(self, x: Any, u: Any, d: Any = None, p: Any = None) -> np.ndarray:
        """``xdot`` at one point, as a NumPy vector (nominal parameters by default)."""
        d = np.zeros(self.n_disturbances) if d is None else d
        p = self.parameter_vector if p is None else p
        return np.asarray(self.ode()(x, u, d, p), dtype=float).reshape(-1)  # type: ignore[attr-defined]

    def linearize(self, x0: Any, u0: Any, d0: Any = None) -> LinearSystem:
        """Jacobians of the ODE at ``(x0, u0, d0)`` with the nominal parameters.

        Returns
        -------
        LinearSystem
            ``dx' = A dx + B [du; dd]``, outputs the states (``C = I``, ``D = 0``); the inputs are
            the plant's inputs followed by its disturbances.  ``A`` in 1/s (per state unit).
        """
        f = self.ode()  # type: ignore[attr-defined]
        x, u, d = (ca.SX.sym(k, f.size1_in(i)) for i, k in enumerate(("x", "u", "d")))
        xdot = f(x, u, d, ca.DM(self.parameter_vector))
        jac = ca.Function("plant_jacobians", [x, u, d], [ca.jacobian(xdot, x), ca.jacobian(xdot, ca.vertcat(u, d))])
        d0 = np.zeros(self.n_disturbances) if d0 is None else d0
        A, B = (np.asarray(m, dtype=float) for m in jac(_vector(x0, self.n_states, "x0"),
                                                       _vector(u0, self.n_inputs, "u0"),
                                                       _vector(d0, self.n_disturbances, "d0")))
        names = tuple(s.name for s in self.states)  # type: ignore[attr-defined]
        ins = tuple(s.name for s in (*self.inputs, *self.disturbances))  # type: ignore[attr-defined]
        return LinearSystem(A=A, B=B, C=np.eye(self.n_states), D=np.zeros((self.n_states, len(ins))),
                            states=names, inputs=ins, outputs=names)

    def with_params(self, **values: float) -> Any:
        """The same plant with other parameter values (unknown names or invalid values: :class:`ModelError`)."""
        checked: dict[str, float] = {}
        for name, value in values.items():
            par = self.parameter(name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
                raise ModelError(name, f"must be a number, got {value!r}")
            value = float(value)
            if not math.isfinite(value) or (par.positive and value <= 0) or (not par.positive and value < 0):
                need = "positive and finite" if par.positive else "non-negative and finite"
                raise ModelError(name, f"must be {need}, got {value:g}")
            checked[name] = value
        return self._replace(checked) if checked else self

    @abstractmethod
    def _replace(self, values: Mapping[str, float]) -> Any:
        """A new plant of the same kind with ``values`` (validated names and numbers) replaced."""


def _vector(value: Any, size: int, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.size != size:
        raise ModelError(name, f"needs {size} entries, got {arr.size}")
    return arr


def signals(prefix: str, count: int, unit: str, meaning: str, *, start: int = 1) -> tuple[Signal, ...]:
    """``count`` signals ``prefix1 .. prefixN`` with one unit (per-joint signals of an n-joint plant)."""
    return tuple(Signal(f"{prefix}{k}", unit, f"{meaning} {k}".strip()) for k in range(start, start + count))


def named(values: Sequence[Parameter], overrides: Mapping[str, float]) -> tuple[Parameter, ...]:
    """``values`` with the entries of ``overrides`` replacing their ``value``."""
    return tuple(Parameter(p.name, float(overrides.get(p.name, p.value)), p.unit, p.meaning, p.positive)
                 for p in values)
