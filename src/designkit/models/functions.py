"""The named CasADi functions of a manipulator model, built on first use.

:class:`FunctionTable` maps a name to a named ``casadi.Function``; each one is
built from shared, lazily constructed ``SX`` expressions (:class:`Expressions`)
on first access and cached.  What each name means is one entry of
:data:`FUNCTION_SPECS` (inputs, outputs, output kinds and a builder):

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
of ``description.symbols``.  Units are SI (m, rad, kg, s, N, N*m).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping
from functools import cached_property
from typing import Any, NamedTuple

import casadi as ca

from designkit.models import chain, dynamics, euler_lagrange, regressor
from designkit.models.description import ChainDescription

__all__ = ["FUNCTION_SPECS", "Expressions", "FunctionSpec", "FunctionTable"]


class Expressions:
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
    def lagrangian(self) -> euler_lagrange.Lagrangian:
        terms = euler_lagrange.lagrangian(self.description, self.q, self.parameters[: 10 * self.description.n])
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
        return euler_lagrange.christoffel(self.lagrangian.mass_matrix, self.q)

    def inverse_dynamics(self, qdd: Any) -> ca.SX:
        return regressor.inverse_dynamics(self.description, self.q, self.qd, qdd, self.parameters,
                                          friction=self.friction, motor_inertia=self.motor_inertia)

    @cached_property
    def friction_torque(self) -> ca.SX:
        links = self.description.links
        if not self.friction:
            return ca.SX.zeros(len(links), 1)
        return dynamics.friction_torque([lk.viscous for lk in links], [lk.coulomb for lk in links], self.qd)


class FunctionSpec(NamedTuple):
    """One entry of :data:`FUNCTION_SPECS`.

    Parameters
    ----------
    inputs : tuple of str
        Input names, attributes of :class:`Expressions` (``"q"``, ``"qd"``, ``"qdd"``, ``"tau"``).
    outputs : tuple of str
        Output names.
    kinds : tuple of str
        Per output, ``"scalar"`` (1x1 -> float), ``"vector"`` (k x 1 -> ``(k,)``) or ``"matrix"`` (kept 2-D).
    build : callable
        ``build(expressions) -> list`` of the output ``SX``.
    """

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    kinds: tuple[str, ...]
    build: Callable[[Expressions], list[Any]]


def _analytic(name: str) -> FunctionSpec:
    def build(e: Expressions) -> list[Any]:
        ja, x = chain.analytic_jacobian(e.description, e.q, name)
        return [ja, x]

    return FunctionSpec(("q",), ("Ja", "x"), ("matrix", "vector"), build)


_M, _V, _S = ("matrix",), ("vector",), ("scalar",)

FUNCTION_SPECS: dict[str, FunctionSpec] = {
    "fkine": FunctionSpec(("q",), ("T",), _M, lambda e: [e.tool]),
    "fkine_all": FunctionSpec(("q",), ("T_all",), _M, lambda e: [ca.horzcat(*e.frames)]),
    "jacobian": FunctionSpec(("q",), ("J",), _M, lambda e: [e.jacobian]),
    "jacobian_dot_qd": FunctionSpec(("q", "qd"), ("Jdot_qd",), _V,
                                    lambda e: [chain.jacobian_dot_qd(e.jacobian, e.q, e.qd)]),
    "analytic_jacobian": _analytic("rpy"),
    **{f"analytic_jacobian_{name}": _analytic(name) for name in chain.REPRESENTATIONS},
    "inverse_dynamics": FunctionSpec(("q", "qd", "qdd"), ("tau",), _V, lambda e: [e.inverse_dynamics(e.qdd)]),
    "mass_matrix": FunctionSpec(("q",), ("M",), _M, lambda e: [e.mass_matrix]),
    "christoffel": FunctionSpec(("q",), ("Gamma",), _M, lambda e: [e.christoffel]),
    "coriolis_matrix": FunctionSpec(("q", "qd"), ("C",), _M,
                                    lambda e: [euler_lagrange.coriolis_from_christoffel(e.christoffel, e.qd)]),
    "gravity_torque": FunctionSpec(("q",), ("g",), _V, lambda e: [e.lagrangian.gravity_torque]),
    "friction_torque": FunctionSpec(("qd",), ("tau_f",), _V, lambda e: [e.friction_torque]),
    "forward_dynamics": FunctionSpec(("q", "qd", "tau"), ("qdd",), _V, lambda e: [
        dynamics.forward_dynamics(e.mass_matrix, e.inverse_dynamics(ca.SX.zeros(e.description.n)), e.tau)]),
    "regressor": FunctionSpec(("q", "qd", "qdd"), ("W",), _M, lambda e: [regressor.regressor(
        e.description, e.q, e.qd, e.qdd, friction=e.friction, motor_inertia=e.motor_inertia)]),
    "parameters": FunctionSpec((), ("P",), _V, lambda e: [ca.vertcat(*[ca.SX(v) for v in e.parameters])]),
    "kinetic_energy": FunctionSpec(("q", "qd"), ("T",), _S, lambda e: [0.5 * ca.bilin(e.mass_matrix, e.qd, e.qd)]),
    "potential_energy": FunctionSpec(("q",), ("V",), _S, lambda e: [e.lagrangian.potential]),
}
"""Name -> :class:`FunctionSpec`: the dispatch table behind :class:`FunctionTable` (see the module docstring)."""


class FunctionTable(Mapping[str, ca.Function]):
    """Read-only mapping name -> named ``casadi.Function``, each built on first access and cached."""

    def __init__(self, expressions: Expressions) -> None:
        self._expressions = expressions
        self._cache: dict[str, ca.Function] = {}

    def __getitem__(self, name: str) -> ca.Function:
        if name not in self._cache:
            try:
                in_names, out_names, _, build = FUNCTION_SPECS[name]
            except (KeyError, TypeError):
                from designkit.errors import NameNotFoundError

                raise NameNotFoundError(f"functions[{name!r}]", f"no such function; available: "
                                        f"{sorted(FUNCTION_SPECS)}") from None
            e = self._expressions
            inputs = [getattr(e, arg) for arg in in_names]
            names = list(in_names)
            if e.p is not None:
                inputs.append(e.p)
                names.append("p")
            self._cache[name] = ca.Function(name, inputs, build(e), names, list(out_names))
        return self._cache[name]

    def __contains__(self, name: object) -> bool:
        return name in FUNCTION_SPECS

    def __iter__(self) -> Iterator[str]:
        return iter(FUNCTION_SPECS)

    def __len__(self) -> int:
        return len(FUNCTION_SPECS)

