"""A control law as named CasADi functions, written once per family and used everywhere.

The same :class:`Law` is composed with the plant for the simulation (every integration step),
linearized with it for the linear checks (:mod:`designkit.synthesis.closed_loop`) and named by
its family's display data in the report.  A law sees

* ``y`` -- the measured plant state (all states, noise added), in the plant's state order;
* ``xc`` -- its continuous state (integrals, filters, reference models, sensitivity states,
  parameter estimates), integrated with the plant;
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
* ``update(y, xc, m, r) -> m_next``: the discrete memory's update;
* ``signals(y, xc, m, r) -> s`` (optional): named signals of the law recorded along a run (a
  sliding function, the adapted gains, a reference model's output), ``signal_names`` naming them;
* ``feedforward(y, xc, m, r, v) -> u`` (optional): how a per-step feedforward ``v`` (one value per
  plant input, supplied by a trial: :mod:`designkit.simulation.trials`) enters the command; without
  it ``v`` is added to ``u`` as a torque.  A learning controller whose learned signal is an
  acceleration maps it through its model's inertia here.

**Initial state.**  ``initial_state`` gives ``xc(0)`` (zeros when empty).  The states named in
``rest_start`` are instead solved for so that the loop starts *at rest* at the reference's value
before the motion (:func:`designkit.synthesis.closed_loop.rest_state`): an integral starts where it
holds the plant still (``x3(0) = K4 q0`` for the PID servo at ``q0``, plus the share of a constant
load), a reference model starts at the plant's position.  So the simulated loop is the loop that
was designed, in deviations about where the arm starts, wherever that is.

**Integral action.**  ``integral_states`` names the states that integrate a joint's position error,
``x' = q_j - qD_j`` (times the anti-windup gate): in a stable loop with them, a constant disturbance
leaves no steady-state position error, so the disturbance-to-position transfer has a zero at ``s = 0``
(the ``pole_placement`` check verifies it).  :func:`integral_law` declares its integrals;
:func:`dynamic_law` the states given with ``State(..., integral=True)``.

**Discontinuous laws.**  A law that switches (``sign`` of a sliding function, a relay inside the
controller) declares ``discontinuous=True``: the simulator then evaluates its command (and its
state derivative) once per integration step, at the step's start, and holds both over the step --
as a sampled controller with the integration step as its period would -- so no integrator stage
ever straddles a switch, and a variable-step integrator (CVODES) integrates a smooth right-hand
side inside each step.  ``max_step`` (s) bounds the step the law can be simulated with and
``max_step_reason`` says why (e.g. the chattering band the hold leaves on the sliding function);
the simulation takes the smaller of it and its own choice and reports both.

**Sampled laws with discrete memory.**  A law designed in discrete time (a self-tuning regulator:
its estimates, covariance and past inputs and outputs) declares its memory entries
(:class:`Memory` in :func:`dynamic_law`: ``memory_names``, ``initial_memory``, ``memory_units`` and
the ``update`` function) and the period it was designed for, ``sampling_period`` (s), with
``sampling_period_source`` naming where it comes from (a spec key path such as
``controller.sampling_period``).  The simulation then samples the controller at that period (its
command held between samples, ``update`` called once per sample) and refuses a conflicting
``simulation.sampling_period``, naming both.  ``command_after_update`` (set by :func:`dynamic_law`
when a law has memory) orders a sample as a sampled controller does: measure ``y``, update the memory
``m <- update(y, xc, m, r)``, then compute the command (and record the signals) from the *updated*
memory; without it the command reads the memory as it was before the sample.

:func:`dynamic_law` builds a law from CasADi expressions (its states' derivatives, its memory's
update, the command, the recorded signals), so no family hand-assembles the functions.

Anti-windup of integral states (spec ``simulation.anti_windup``), per joint ``j``:
``threshold`` -- ``gate_j = 1`` while ``|e_j| <= value_j`` else 0; ``saturation`` -- the integral
clamped to ``|K3_j x3_j| <= value_j`` after every step.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit.synthesis.design import freeze

__all__ = ["Law", "LawSymbols", "Memory", "State", "dynamic_law", "integral_law", "law_symbols", "stateless_law"]


@dataclass(frozen=True)
class Law:
    """A controller as CasADi functions (see the module docstring for their signatures).

    Parameters
    ----------
    kind : str
        Controller kind (``design.kind``).
    state_names : tuple of str
        Continuous controller states.
    command, derivative, gate, project, update : casadi.Function
    memory_names : tuple of str
        Discrete memory entries.
    initial_memory : tuple of float
        Memory at ``t = 0``.
    settings : Mapping
        Gains and options, JSON-serialisable (deeply frozen).
    initial_state : tuple of float
        ``xc(0)``, one value per state (empty: zeros).
    rest_start : tuple of str
        States whose initial value is solved so that the loop starts at rest (module docstring).
    integral_states : tuple of str
        States that integrate a joint's position error (rad*s), ``x' = q_j - qD_j``: the law's integral action
        (module docstring).
    discontinuous : bool
        The command switches: held over each integration step.
    max_step : float or None
        Largest integration step (s) the law can be simulated with, and ``max_step_reason`` why.
    project_resets : bool
        ``project`` is a reset that acts only now and then (a state put back into a box once it has left it by a
        hysteresis), not a clamp that holds a state at a bound: a smooth loop's adaptive integrator applies it at
        the grid instants and starts again from there (:mod:`designkit.simulation.dopri5`) instead of the loop
        being stepped per grid step.
    signals : casadi.Function or None
        ``(y, xc, m, r) -> s``, the recorded signals named by ``signal_names`` (units in ``signal_units``).
    feedforward : casadi.Function or None
        ``(y, xc, m, r, v) -> u``: how a trial's feedforward ``v`` enters the command (default: added).
    memory_units : tuple of str
        Units of the memory entries (empty: unitless).
    sampling_period : float or None
        The period (s) the law was designed for: the simulation samples it there (module docstring);
        ``None``: a continuous law, sampled only when ``simulation.sampling_period`` says so.
    sampling_period_source : str
        Where ``sampling_period`` comes from (a spec key path), for messages.
    command_after_update : bool
        At a sample the command reads the memory updated by that sample (module docstring).
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
    initial_state: tuple[float, ...] = ()
    rest_start: tuple[str, ...] = ()
    integral_states: tuple[str, ...] = ()
    discontinuous: bool = False
    max_step: float | None = None
    max_step_reason: str = ""
    project_resets: bool = False
    signals: ca.Function | None = None
    signal_names: tuple[str, ...] = ()
    signal_units: tuple[str, ...] = ()
    feedforward: ca.Function | None = None
    memory_units: tuple[str, ...] = ()
    sampling_period: float | None = None
    sampling_period_source: str = ""
    command_after_update: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "settings", freeze(dict(self.settings)))
        n = len(self.state_names)
        initial = tuple(float(v) for v in self.initial_state) or (0.0,) * n
        if len(initial) != n:
            raise ValueError(f"law {self.kind!r}: initial_state has {len(initial)} values for {n} states")
        object.__setattr__(self, "initial_state", initial)
        for role in ("rest_start", "integral_states"):
            unknown = set(getattr(self, role)) - set(self.state_names)
            if unknown:
                raise ValueError(f"law {self.kind!r}: {role} names unknown states {sorted(unknown)}")
        if self.max_step is not None and not self.max_step > 0:
            raise ValueError(f"law {self.kind!r}: max_step must be positive, got {self.max_step}")
        size = 0 if self.signals is None else self.signals.size1_out(0)
        if size != len(self.signal_names):
            raise ValueError(f"law {self.kind!r}: {size} signals for {len(self.signal_names)} names")
        units = tuple(self.signal_units) or ("",) * size
        if len(units) != size:
            raise ValueError(f"law {self.kind!r}: {len(units)} signal units for {size} signals")
        object.__setattr__(self, "signal_units", units)
        nm = len(self.memory_names)
        memory = tuple(float(v) for v in self.initial_memory) or (0.0,) * nm
        if len(memory) != nm:
            raise ValueError(f"law {self.kind!r}: initial_memory has {len(memory)} values for {nm} memory entries")
        object.__setattr__(self, "initial_memory", memory)
        munits = tuple(self.memory_units) or ("",) * nm
        if len(munits) != nm:
            raise ValueError(f"law {self.kind!r}: {len(munits)} memory units for {nm} memory entries")
        object.__setattr__(self, "memory_units", munits)
        if self.sampling_period is not None and not (math.isfinite(self.sampling_period) and self.sampling_period > 0):
            raise ValueError(f"law {self.kind!r}: sampling_period must be positive and finite, got "
                             f"{self.sampling_period}")

    @property
    def n_state(self) -> int:
        """Number of continuous controller states."""
        return len(self.state_names)

    @property
    def n_memory(self) -> int:
        """Size of the discrete memory."""
        return len(self.memory_names)

    @property
    def n_signals(self) -> int:
        """Number of recorded signals."""
        return len(self.signal_names)

    def rest_indices(self) -> tuple[int, ...]:
        """Indices of the ``rest_start`` states in ``xc``."""
        return tuple(self.state_names.index(name) for name in self.rest_start)


def law_symbols(n_y: int, n_c: int, n_m: int, n_joints: int) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """Symbols ``y, xc, m, r`` of a law's functions."""
    return ca.SX.sym("y", n_y), ca.SX.sym("xc", n_c), ca.SX.sym("m", n_m), ca.SX.sym("r", 3 * n_joints)


@dataclass(frozen=True)
class LawSymbols:
    """The symbols a law's expressions are written in, with the plant's layout.

    Attributes
    ----------
    y, xc, m, r : casadi.SX
        Measured state, controller state, memory, reference (module docstring).
    positions, velocities : tuple of int
        Indices of the joint positions and velocities in ``y``.
    names : tuple of str
        Controller state names (for :meth:`state`).
    memory_names : tuple of str
        Memory entry names (for :meth:`memory`).
    """

    y: ca.SX
    xc: ca.SX
    m: ca.SX
    r: ca.SX
    positions: tuple[int, ...]
    velocities: tuple[int, ...]
    names: tuple[str, ...] = ()
    memory_names: tuple[str, ...] = ()

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.positions)

    @property
    def q(self) -> ca.SX:
        """Measured joint positions (rad or m)."""
        return ca.vertcat(*[self.y[i] for i in self.positions])

    @property
    def qd(self) -> ca.SX:
        """Measured joint velocities."""
        return ca.vertcat(*[self.y[i] for i in self.velocities])

    @property
    def qD(self) -> ca.SX:
        """Reference positions."""
        return self.r[0:self.n]

    @property
    def qDd(self) -> ca.SX:
        """Reference velocities."""
        return self.r[self.n:2 * self.n]

    @property
    def qDdd(self) -> ca.SX:
        """Reference accelerations."""
        return self.r[2 * self.n:3 * self.n]

    def state(self, name: str) -> ca.SX:
        """The controller state ``name``."""
        return self.xc[self.names.index(name)]

    def memory(self, name: str) -> ca.SX:
        """The memory entry ``name`` (its value before the sample's update)."""
        return self.m[self.memory_names.index(name)]


@dataclass(frozen=True)
class State:
    """One continuous state of a :func:`dynamic_law`.

    Parameters
    ----------
    name : str
        As recorded (``"a1"``, ``"ym1"``).
    derivative : callable
        ``LawSymbols -> SX`` scalar: the state's time derivative.
    initial : float or None
        ``xc(0)``; ``None`` starts the state at the loop's rest (``rest_start``).
    integral : bool
        The state integrates a joint's position error, ``x' = q_j - qD_j`` (rad*s): it is one of the law's
        ``integral_states``.
    """

    name: str
    derivative: Callable[[LawSymbols], ca.SX]
    initial: float | None = None
    integral: bool = False


@dataclass(frozen=True)
class Memory:
    """One discrete memory entry of a :func:`dynamic_law`, updated once per controller sample.

    Parameters
    ----------
    name : str
        As in ``memory_names`` (``"theta1"``, ``"y_prev"``).
    update : callable
        ``LawSymbols -> SX`` scalar: the entry's value after the sample, from ``y``, ``xc``, the memory
        before the sample ``m`` and ``r``.
    initial : float
        Its value before the first sample.
    unit : str
        Its unit (``"rad"``, ``""``).
    """

    name: str
    update: Callable[[LawSymbols], ca.SX]
    initial: float = 0.0
    unit: str = ""


def dynamic_law(kind: str, plant: Any, *, command: Callable[[LawSymbols], ca.SX], states: Sequence[State] = (),
                settings: Mapping[str, Any] | None = None, signals: Mapping[str, Callable[[LawSymbols], ca.SX]]
                | None = None, signal_units: Sequence[str] = (), discontinuous: bool = False,
                max_step: float | None = None, max_step_reason: str = "",
                feedforward: Callable[[LawSymbols, ca.SX], ca.SX] | None = None, memory: Sequence[Memory] = (),
                sampling_period: float | None = None, sampling_period_source: str = "") -> Law:
    """A law from CasADi expressions: its states' derivatives, its memory's update, its command and its signals.

    With ``memory``, the command and the signals are written on the memory *after* the sample's update
    (``command_after_update``): in them ``s.m`` / ``s.memory(name)`` are the updated entries, in each
    :attr:`Memory.update` the entries before it.

    Parameters
    ----------
    kind : str
        Controller kind.
    plant : Plant
        Gives the layout (states, positions, velocities, joints).
    command : callable
        ``LawSymbols -> SX``: the plant inputs (one per input).
    states : sequence of State
        The controller's continuous states, in order.
    settings : Mapping, optional
        Gains and options for the record.
    signals : Mapping, optional
        Name -> ``LawSymbols -> SX`` scalar, recorded along the run; ``signal_units`` their units.
    discontinuous, max_step, max_step_reason
        See :class:`Law`.
    feedforward : callable, optional
        ``(LawSymbols, v) -> SX``: how a trial's feedforward ``v`` (one per plant input) enters the command.
    memory : sequence of Memory
        The discrete memory, in order (module docstring, "Sampled laws").
    sampling_period : float, optional
        The period (s) the law was designed for, and ``sampling_period_source`` the spec key that sets it.

    Examples
    --------
    A PD law with a first-order reference filter ``xf' = 10 (xD - xf)`` that starts at rest:

    >>> from designkit.models.link import LinkPlant
    >>> law = dynamic_law("demo", LinkPlant(Km=2.0, tau=0.5),
    ...                   states=[State("xf", lambda s: 10 * (s.qD[0] - s.state("xf")))],
    ...                   command=lambda s: -20 * (s.q[0] - s.state("xf")) - 2 * s.qd[0])
    >>> law.state_names, law.rest_start
    (('xf',), ('xf',))

    A sampled integrator of the position error, ``i(k) = i(k-1) + Ts e(k)``, ``u = -5 i``, designed for
    ``Ts = 0.01`` s:

    >>> law = dynamic_law("demo", LinkPlant(Km=2.0, tau=0.5), sampling_period=0.01,
    ...                   memory=[Memory("i", lambda s: s.memory("i") + 0.01 * (s.q[0] - s.qD[0]), unit="rad*s")],
    ...                   command=lambda s: -5 * s.memory("i"))
    >>> law.memory_names, law.command_after_update, float(law.update([1, 0], [], [0.0], [0, 0, 0]))
    (('i',), True, 0.01)
    """
    n = len(plant.positions)
    names = tuple(s.name for s in states)
    mnames = tuple(e.name for e in memory)
    y, xc, m, r = law_symbols(len(plant.states), len(states), len(memory), n)
    sym = LawSymbols(y, xc, m, r, tuple(plant.positions), tuple(plant.velocities), names, mnames)
    args, arg_names = [y, xc, m, r], ["y", "xc", "m", "r"]
    m_next = ca.vertcat(*[e.update(sym) for e in memory]) if memory else m
    g = ca.SX.sym("gate", len(states))
    xc_dot = ca.vertcat(*[s.derivative(sym) for s in states]) if states else ca.SX(0, 1)
    ff_fn = None
    if feedforward is not None:
        v = ca.SX.sym("v", len(plant.inputs))
        ff_fn = ca.Function(f"{kind}_feedforward", [*args, v], [feedforward(sym, v)], [*arg_names, "v"], ["u"])
    signal_fn = None
    if signals:
        signal_fn = ca.Function(f"{kind}_signals", args, [ca.vertcat(*[f(sym) for f in signals.values()])],
                                arg_names, ["s"])
    return Law(
        kind=kind, state_names=names,
        command=ca.Function(f"{kind}_command", args, [command(sym)], arg_names, ["u"]),
        derivative=ca.Function(f"{kind}_derivative", [*args, g], [g * xc_dot if states else xc_dot],
                               [*arg_names, "gate"], ["xc_dot"]),
        gate=ca.Function(f"{kind}_gate", args, [ca.SX.ones(len(states)) if states else ca.SX(0, 1)], arg_names,
                         ["gate"]),
        project=ca.Function(f"{kind}_project", [xc], [xc], ["xc"], ["xc_projected"]),
        update=ca.Function(f"{kind}_update", args, [m_next], arg_names, ["m_next"]),
        settings=settings or {},
        memory_names=mnames, initial_memory=tuple(float(e.initial) for e in memory),
        memory_units=tuple(e.unit for e in memory), sampling_period=sampling_period,
        sampling_period_source=sampling_period_source, command_after_update=bool(memory),
        initial_state=tuple(0.0 if s.initial is None else float(s.initial) for s in states),
        rest_start=tuple(s.name for s in states if s.initial is None),
        integral_states=tuple(s.name for s in states if s.integral),
        discontinuous=discontinuous, max_step=max_step, max_step_reason=max_step_reason,
        signals=signal_fn, signal_names=tuple(signals or ()), signal_units=tuple(signal_units), feedforward=ff_fn,
    )


def _anti_windup(section: Any, n: int, K3: np.ndarray) -> tuple[Callable, Callable, dict[str, Any]]:
    """``(gate(e) -> SX, project(x_int) -> SX, settings)`` of ``simulation.anti_windup`` for ``n`` integrals."""
    if section is None:
        return (lambda e: ca.SX.ones(n)), (lambda xi: xi), {"kind": "none", "value": None}
    given = np.asarray(section.value, dtype=float).reshape(-1)
    if given.size not in (1, n):
        from designkit.errors import SpecError

        raise SpecError("simulation.anti_windup.value", f"needs one value or one per joint ({n}), got {given.size}")
    values = np.broadcast_to(given, (n,)).copy()
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

    The integrals start at the loop's rest (``rest_start``): where they hold the plant still at the
    reference before the motion, so that a step from any initial position is the designed step.

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
    states = tuple("x3" if n == 1 else f"x3_{j + 1}" for j in range(n))
    return Law(
        kind=kind,
        state_names=states,
        command=ca.Function(f"{kind}_command", args, [output(y, xc, r, e)], names, ["u"]),
        derivative=ca.Function(f"{kind}_derivative", [*args, g], [g * e], [*names, "gate"], ["xc_dot"]),
        gate=ca.Function(f"{kind}_gate", args, [gate_of(e)], names, ["gate"]),
        project=ca.Function(f"{kind}_project", [xc], [project_of(xc)], ["xc"], ["xc_projected"]),
        update=ca.Function(f"{kind}_update", args, [m], names, ["m_next"]),
        settings={**settings, "anti_windup": aw},
        rest_start=states,
        integral_states=states,
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
    return dynamic_law(kind, plant, command=lambda s: output(s.y, s.r), settings=settings)
