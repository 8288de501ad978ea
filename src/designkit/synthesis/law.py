"""A control law as named CasADi functions, written once per family and used everywhere.

The same :class:`Law` is composed with the plant for the simulation (every integration step),
linearized with it for the linear checks (:mod:`designkit.synthesis.closed_loop`) and named by
its family's display data in the report.  A law sees

* ``y`` -- the measured plant state (all states, noise added), in the plant's state order;
* ``xc`` -- its continuous state (integrals, filters), integrated with the plant;
* ``m`` -- its discrete memory (held values, estimates, a learning controller's tables), updated
  at each controller sample by ``update`` (every integration step for a continuous controller);
* ``r`` -- the reference, ``3 n`` numbers for ``n`` joints: positions ``xD``, then velocities
  ``xD'``, then accelerations ``xD''`` (rad, rad/s, rad/s^2).

Functions (all ``casadi.Function``, named ``<kind>_<what>``):

* ``command(y, xc, m, r) -> u``: the commanded plant inputs (N*m);
* ``derivative(y, xc, m, r, gate) -> xc_dot``: ``gate`` (one 0/1 per controller state, the
  anti-windup switch) multiplies each integrand;
* ``gate(y, xc, m, r) -> gate``: evaluated once per integration step, at its start;
* ``project(xc) -> xc``: applied after every step (clamps integral states);
* ``update(y, xc, m, r) -> m_next``: the discrete memory's update.

Anti-windup of integral states (spec ``simulation.anti_windup``), per joint ``j``:
``threshold`` -- ``gate_j = 1`` while ``|e_j| <= value_j`` else 0; ``saturation`` -- the integral
clamped to ``|K3_j x3_j| <= value_j`` after every step.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit.synthesis.design import freeze

__all__ = ["Law", "integral_law", "law_symbols", "stateless_law"]


@dataclass(frozen=True)
class Law:
    """A controller as CasADi functions (see the module docstring for their signatures).

    Parameters
    ----------
    kind : str
        Controller kind (``design.kind``).
    state_names : tuple of str
        Continuous controller states.
    memory_names : tuple of str
        Discrete memory entries.
    initial_memory : tuple of float
        Memory at ``t = 0``.
    command, derivative, gate, project, update : casadi.Function
    settings : Mapping
        Gains and options, JSON-serialisable (deeply frozen).
    """

    kind: str
    state_names: tuple[str, ...]
    command: ca.Function
    derivative: ca.Function
    gate: ca.Function
    project: ca.Function
    update: ca.Function
    memory_names: tuple[str, ...] = ()
    initial_memory: tuple[float, ...] = ()
    settings: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "settings", freeze(dict(self.settings)))

    @property
    def n_state(self) -> int:
        """Number of continuous controller states."""
        return len(self.state_names)

    @property
    def n_memory(self) -> int:
        """Size of the discrete memory."""
        return len(self.memory_names)


def law_symbols(n_y: int, n_c: int, n_m: int, n_joints: int) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """Symbols ``y, xc, m, r`` of a law's functions."""
    return ca.SX.sym("y", n_y), ca.SX.sym("xc", n_c), ca.SX.sym("m", n_m), ca.SX.sym("r", 3 * n_joints)


def _anti_windup(section: Any, n: int, K3: np.ndarray) -> tuple[Callable, Callable, dict[str, Any]]:
    """``(gate(e) -> SX, project(x_int) -> SX, settings)`` of ``simulation.anti_windup`` for ``n`` integrals."""
    if section is None:
        return (lambda e: ca.SX.ones(n)), (lambda xi: xi), {"kind": "none", "value": None}
    values = np.broadcast_to(np.asarray(section.value, dtype=float), (n,)).copy()
    settings = {"kind": section.kind, "value": values.tolist() if n > 1 else float(values[0])}
    if section.kind == "threshold":
        return (lambda e: ca.vertcat(*[ca.if_else(ca.fabs(e[j]) <= values[j], 1.0, 0.0) for j in range(n)]),
                (lambda xi: xi), settings)
    bounds = [values[j] / abs(K3[j]) if K3[j] != 0 else np.inf for j in range(n)]
    return ((lambda e: ca.SX.ones(n)),
            (lambda xi: ca.vertcat(*[ca.fmin(ca.fmax(xi[j], -bounds[j]), bounds[j]) for j in range(n)])), settings)


def integral_law(
    kind: str, plant: Any, K3: Sequence[float], anti_windup: Any,
    output: Callable[[ca.SX, ca.SX, ca.SX, ca.SX], ca.SX], settings: Mapping[str, Any],
) -> Law:
    """The frame of the PID laws: one integral state per joint, ``x3_j' = gate_j (y_pos_j - xD_j)``.

    Parameters
    ----------
    kind : str
        Controller kind.
    plant : Plant
        Gives the state layout (``positions``, number of joints).
    K3 : sequence of float
        Integral gain per joint (for the ``saturation`` anti-windup bound).
    anti_windup : AntiWindup or None
        The spec's ``simulation.anti_windup``.
    output : callable
        ``(y, xc, r, e) -> u`` on SX (``e`` the position errors ``y_pos - xD``).
    settings : Mapping
        Gains for the record.
    """
    n = len(plant.positions)
    y, xc, m, r = law_symbols(len(plant.states), n, 0, n)
    pos = ca.vertcat(*[y[i] for i in plant.positions])
    e = pos - r[0:n]
    gate_of, project_of, aw = _anti_windup(anti_windup, n, np.asarray(K3, dtype=float).reshape(n))
    g = ca.SX.sym("gate", n)
    names = ["y", "xc", "m", "r"]
    args = [y, xc, m, r]
    return Law(
        kind=kind,
        state_names=tuple("x3" if n == 1 else f"x3_{j + 1}" for j in range(n)),
        command=ca.Function(f"{kind}_command", args, [output(y, xc, r, e)], names, ["u"]),
        derivative=ca.Function(f"{kind}_derivative", [*args, g], [g * e], [*names, "gate"], ["xc_dot"]),
        gate=ca.Function(f"{kind}_gate", args, [gate_of(e)], names, ["gate"]),
        project=ca.Function(f"{kind}_project", [xc], [project_of(xc)], ["xc"], ["xc_projected"]),
        update=ca.Function(f"{kind}_update", args, [m], names, ["m_next"]),
        settings={**settings, "anti_windup": aw},
    )


def stateless_law(kind: str, plant: Any, output: Callable[[ca.SX, ca.SX], ca.SX], settings: Mapping[str, Any]) -> Law:
    """A law without continuous state or memory: ``u = output(y, r)`` (computed torque, resolved acceleration).

    Parameters
    ----------
    kind : str
        Controller kind.
    plant : Plant
        Gives the sizes (states, joints).
    output : callable
        ``(y, r) -> u`` on SX.
    settings : Mapping
        Gains and options for the record.
    """
    n = len(plant.positions)
    y, xc, m, r = law_symbols(len(plant.states), 0, 0, n)
    names, args = ["y", "xc", "m", "r"], [y, xc, m, r]
    g = ca.SX.sym("gate", 0)
    empty = ca.SX(0, 1)
    return Law(
        kind=kind, state_names=(),
        command=ca.Function(f"{kind}_command", args, [output(y, r)], names, ["u"]),
        derivative=ca.Function(f"{kind}_derivative", [*args, g], [empty], [*names, "gate"], ["xc_dot"]),
        gate=ca.Function(f"{kind}_gate", args, [empty], names, ["gate"]),
        project=ca.Function(f"{kind}_project", [xc], [xc], ["xc"], ["xc_projected"]),
        update=ca.Function(f"{kind}_update", args, [m], names, ["m_next"]),
        settings=settings,
    )
