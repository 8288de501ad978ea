"""Closed-loop simulation of any plant under a designed controller (the notes' POSSPEED and SIMNOG).

Signal chain, per integration step ``[t_k, t_k + dt]`` (``dt`` from :mod:`designkit.simulation.timing`)::

    y = x + n_k                        measurement, Gaussian noise n_k held over the step
    u_c = law.command(y, xc, m, r)     controller (+ a per-step feedforward, zero unless a trial sets it);
                                       sampled: only at sampling instants, then held
    m <- law.update(y, xc, m, r)       the law's discrete memory, at each controller sample
    v = element(u_c, e)                nonlinear element per input (saturation, dead zone, relay, quantizer)
    u_a(t) = v(t - delay)              delay line of ``delay/dt`` steps
    x' = plant.ode(x, u_a, d_k, p)     the true plant (its own parameters), integrated with xc' = law.derivative

State layout (computed from the plant, the law and the element, never fixed)::

    z = (x[nx], xc[nc], m[nm], e[ne], u_hold[nu], xc_dot_hold[nc], delay line[nu * delay_steps])
    w = (r(t)[3n], r(t + dt/2)[3n], r(t + dt)[3n], noise[nx], d[nd], sample flag, u_feedforward[nu], p[np])

The true plant's parameters ``p`` are an input of the step (repeated in every column of ``w``), so
one built simulator runs on any parameter values (``Simulator.run(parameters=...)``): sweeps over
an uncertainty box and model-mismatch studies never rebuild the step, and the compiled step is
shared by every parameter value.

Evaluation: when the controller is continuous (``sampling_period = 0``), there is no delay and
the element is continuous and memoryless (none, saturation, dead zone), the whole chain is
evaluated inside the integrator (fourth-order accurate with RK4).  Otherwise the discontinuous
parts (relay switching, quantizer, sampling instants, delay line) are evaluated once per step,
at the step's start, and the applied control is held over the step.  A sampled controller runs
at ``t = j Ts``: it computes ``u`` and the derivative of its state there and holds both.  The
anti-windup gate is evaluated at each step's start; its clamp after each step.  The
disturbance is held per step: a step at ``time`` acts from the first ``t_k >= time``.

Integrators (``numerics.integrator``): ``rk4`` (classical, fixed step) or ``cvodes`` (CasADi's
variable-step BDF inside every step, for stiff plants).  Without ``numerics.integrator`` the
integrator is chosen from the poles (:func:`~designkit.simulation.timing.resolve`): RK4, or
CVODES with an output step set by the non-stiff poles when RK4 would need more steps than the
bound (``settings["integrator_choice"]`` says why).  Either way the steps are rolled by
``Function.mapaccum`` (:func:`~designkit.simulation.integrate.run_steps`): no Python loop per step.

Compiled evaluation (``numerics.compile``): the rolled RK4 step can be turned into C by CasADi's
code generator and the system C compiler (:func:`designkit.models.codegen.compile_function`,
cached by content hash, ``-O1 -ffp-contract=off`` so the compiled run equals the interpreted one
to the last bit).  ``auto`` (default) uses the compiled library when it is already cached, and
compiles when the interpreted run is estimated to cost more than compiling
(:data:`COMPILE_BREAK_EVEN`); ``always`` and ``never`` force the choice.  Without a compiler, or
for a CVODES step, the interpreted CasADi virtual machine runs (the settings say which and why).
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.families import family
from designkit.simulation.integrate import rk4, run_steps, variable_step
from designkit.simulation.nonlinear import Element, element_for
from designkit.simulation.reference import Reference, reference_for
from designkit.simulation.result import SimulationResult
from designkit.simulation.timing import Timing, grid, rates_of, resolve
from designkit.spec.fields import per_joint
from designkit.spec.schema import Spec
from designkit.synthesis.closed_loop import linearize
from designkit.synthesis.design import Design, freeze
from designkit.synthesis.law import Law

__all__ = ["COMPILE_BREAK_EVEN", "Simulator", "build", "simulate"]

CHUNK = 200
"""Steps per ``mapaccum`` evaluation (see :func:`~designkit.simulation.integrate.run_steps`)."""
COMPILE_BREAK_EVEN = 0.25
"""Compile (``numerics.compile: auto``) when the interpreted run is estimated above this (s): about what
compiling the rolled two-link step costs with ``cc -O1`` (0.21-0.25 s measured, ``benchmarks/bench_simnog.py``)."""
CACHE_LOOKUP_FLOOR = 0.01
"""Below this estimated interpreted cost (s) the compiled cache is not even looked up (generating the C source
to hash it costs a few milliseconds)."""
INTERPRETED_SECONDS_PER_INSTRUCTION = 6e-9
"""Measured cost of one CasADi virtual-machine instruction in a rolled step on a quiet machine (SIMNOG:
56 ms for 10^4 steps of 882 instructions; -O1 C runs the same steps in 5.5 ms)."""
COMPILE_FLAGS = ("-O1", "-ffp-contract=off", "-fPIC", "-shared")
"""No reassociation and no fused multiply-add: the compiled step gives the interpreted step's numbers."""


@dataclass(frozen=True)
class _Layout:
    nx: int
    nc: int
    nm: int
    ne: int
    nu: int
    nd: int
    n: int
    delay_steps: int

    @property
    def z_sizes(self) -> list[int]:
        return [self.nx, self.nc, self.nm, self.ne, self.nu, self.nc, self.nu * self.delay_steps]

    np_: int = 0

    @property
    def w_sizes(self) -> list[int]:
        return [3 * self.n, 3 * self.n, 3 * self.n, self.nx, self.nd, 1, self.nu, self.np_]


def _split(v: Any, sizes: list[int]) -> list[Any]:
    return ca.vertsplit(v, np.cumsum([0, *sizes]).tolist())


def _step_function(plant: Any, law: Law, element: Element, timing: Timing, numerics: Any) -> ca.Function:
    """One integration step ``sim_step: (z, w) -> (z_next, record)`` (layout in the module docstring).

    ``record`` is ``(x, xc, u_command, u_applied, y, d)`` at the step's start.
    """
    L = _Layout(len(plant.states), law.n_state, law.n_memory, element.n_memory, len(plant.inputs),
                len(plant.disturbances), len(plant.positions), timing.delay_steps, len(plant.parameters))
    sampled = timing.steps_per_sample > 0
    per_step = sampled or L.delay_steps > 0 or not element.continuous
    ode = plant.ode()

    # the right-hand side over one step, in fresh symbols: s = (x, xc), a = reference, h = held values
    s, a = ca.SX.sym("s", L.nx + L.nc), ca.SX.sym("a", 3 * L.n)
    h_sizes = [L.nx, L.nd, L.nu, L.nm, L.ne, L.nc, L.nu, L.nc, L.np_]
    h = ca.SX.sym("h", sum(h_sizes))
    noise, dist, uff, m, e, gate, u_held, d_held, p_true = _split(h, h_sizes)
    x, xc = s[:L.nx], s[L.nx:]
    u_in = u_held if per_step else element.function(law.command(x + noise, xc, m, a) + uff, e)[0]
    xc_dot = d_held if sampled else law.derivative(x + noise, xc, m, a, gate)
    rhs = ca.Function("loop_rhs", [s, a, h], [ca.vertcat(ode(x, u_in, dist, p_true), xc_dot)], ["s", "a", "h"],
                      ["s_dot"])

    sym = ca.MX.sym if timing.integrator == "cvodes" else ca.SX.sym
    z, w = sym("z", sum(L.z_sizes)), sym("w", sum(L.w_sizes))
    x, xc, m, e, u_hold, d_hold, line = _split(z, L.z_sizes)
    r0, rm, r1, noise, dist, flag, uff, p = _split(w, L.w_sizes)
    y = x + noise
    gate = law.gate(y, xc, m, r0)
    if sampled:
        u_hold = ca.if_else(flag, law.command(y, xc, m, r0) + uff, u_hold)
        d_hold = ca.if_else(flag, law.derivative(y, xc, m, r0, gate), d_hold)
        u_cmd = u_hold
    else:
        u_cmd = law.command(y, xc, m, r0) + uff
    m_next = ca.if_else(flag, law.update(y, xc, m, r0), m) if L.nm else m
    if per_step:
        v, e_next = element.function(u_cmd, e)
        u_app = line[L.nu * (L.delay_steps - 1):] if L.delay_steps > 0 else v
        line_next = ca.vertcat(v, line[: L.nu * (L.delay_steps - 1)]) if L.delay_steps > 0 else line
    else:
        u_app, e_next, line_next = element.function(u_cmd, e)[0], e, line
    held = ca.vertcat(noise, dist, uff, m, e, gate, u_app, d_hold, p)
    s0 = ca.vertcat(x, xc)
    if timing.integrator == "cvodes":
        s_next = variable_step(rhs, s0, timing.dt, (r0, rm, r1), held, rtol=numerics.rtol, atol=numerics.atol)
    else:
        s_next = rk4(lambda state, ref: rhs(state, ref, held), s0, timing.dt, (r0, rm, r1))
    z_next = ca.vertcat(s_next[:L.nx], law.project(s_next[L.nx:]), m_next, e_next, u_hold, d_hold, line_next)
    record = ca.vertcat(x, xc, u_cmd, u_app, y, dist)
    return ca.Function("sim_step", [z, w], [z_next, record], ["z", "w"], ["z_next", "record"])


def _joint_values(value: Any, n: int, path: str) -> np.ndarray:
    try:
        return np.array(per_joint(value, n, path))
    except ValueError as exc:
        key, msg = str(exc).split(": ", 1)
        raise SpecError(key, msg.replace("per joint", "per entry")) from None


def _noise(spec: Spec, n: int, nx: int, names: tuple[str, ...]) -> tuple[np.ndarray, dict[str, Any]]:
    noise = spec.simulation.noise
    if noise is None:
        return np.zeros((nx, n)), {"std": 0.0, "seed": None}
    std = _joint_values(noise.std, nx, "simulation.noise.std")
    if not np.any(std > 0):
        return np.zeros((nx, n)), {"std": 0.0, "seed": None}
    rng = np.random.default_rng(noise.seed)
    samples = rng.normal(0.0, 1.0, size=(n, nx)).T * std[:, None]
    return samples, {"std": float(std[0]) if np.all(std == std[0]) else std.tolist(), "seed": int(noise.seed),
                     "on": list(names), "samples": "one per integration step, held over the step",
                     "generator": "numpy PCG64"}


def _perturbation(spec: Spec, t: np.ndarray, dt: float, nd: int) -> tuple[np.ndarray, dict[str, Any] | None]:
    pert = spec.simulation.perturbation
    if pert is None:
        return np.zeros((nd, t.size)), None
    value = _joint_values(pert.value, nd, "simulation.perturbation.value")
    on = t >= pert.time - 1e-9 * dt
    applied = float(t[on][0]) if on.any() else None
    return np.where(on[None, :], value[:, None], 0.0), {
        "value": float(value[0]) if nd == 1 else value.tolist(), "time": float(pert.time), "time_applied": applied}


def _closed_loop_poles(design: Design, plant: Any, law: Law) -> list[np.ndarray]:
    """Poles that set the time scales: the nominal closed loop and the closed loop on the true plant.

    The open-loop plant's poles are left out on purpose: a stiff open-loop mode that the loop
    moves (the PUMA's wrist, ``tau6 = 0.2 ms``, slowed down by its PID) would make the step
    thousands of times smaller than the simulated closed loop needs.  A design without a linear
    closed loop falls back to the requested poles (and a user ``dt`` or ``numerics.integrator:
    cvodes`` for stiff cases).
    """
    out = []
    if design.closed_loop is not None:
        out.append(design.closed_loop.poles)
    op = design.operating_point
    if plant is not design.plant and op:
        with contextlib.suppress(ValueError):  # no equilibrium on the true plant: the nominal rates stand
            out.append(linearize(plant, law, op["r"], z0=[*op["x"], *op["xc"]])[0].poles)
    return out


def _requested_poles(design: Design) -> list[complex]:
    return [*design.poles, *[p for loop in design.loops for p in loop.poles]]


@dataclass(frozen=True, eq=False)
class Simulator:
    """A built simulation (step function, per-step inputs, initial state), ready to run.

    Building is the costly part (CasADi graphs); :meth:`run` only evaluates, so repeated trials
    (:mod:`designkit.simulation.trials`) reuse one simulator.

    Parameters
    ----------
    step : casadi.Function
        ``sim_step: (z, w) -> (z_next, record)``.
    inputs : ndarray, shape (nw, N)
        Per-step inputs (reference, noise, disturbance, sample flag; the feedforward rows zero).
    z0 : ndarray
        Initial augmented state.
    time, reference : ndarray
        Instants (s) and the reference ``(N, n, 3)``.
    plant, law : Plant, Law
        The simulated plant and controller.
    settings : Mapping
        Every option used.
    """

    step: ca.Function
    inputs: np.ndarray
    z0: np.ndarray
    time: np.ndarray
    reference: np.ndarray
    kind: str
    plant: Any
    law: Law
    settings: Mapping[str, Any] = field(default_factory=dict)
    accumulated: ca.Function | None = None
    compiled: Mapping[str, Any] = field(default_factory=dict)
    motion: Any = None

    @property
    def n_inputs(self) -> int:
        """Number of plant inputs (columns of a feedforward)."""
        return len(self.plant.inputs)

    def run(self, *, feedforward: np.ndarray | None = None, parameters: Mapping[str, float] | None = None
            ) -> SimulationResult:
        """Simulate.

        Parameters
        ----------
        feedforward : ndarray, shape (N, nu), optional
            Added to the controller's command at each step (N*m).
        parameters : mapping, optional
            True-plant parameter values replacing the plant's (validated as ``plant.with_params`` does);
            the step function is not rebuilt.
        """
        inputs = self.inputs
        plant = self.plant
        npar = len(plant.parameters)
        if feedforward is not None or parameters:
            inputs = inputs.copy()
        if feedforward is not None:
            ff = np.asarray(feedforward, dtype=float).reshape(self.time.size, self.n_inputs)
            inputs[inputs.shape[0] - npar - self.n_inputs:inputs.shape[0] - npar] = ff.T
        if parameters:
            plant = plant.with_params(**parameters)
            if npar:
                inputs[-npar:] = np.asarray(plant.parameter_vector, dtype=float)[:, None]
        failure: dict[str, Any] = {}
        rec = run_steps(self.step, self.z0, inputs, chunk=CHUNK, accumulated=self.accumulated, failure=failure)
        settings = self.settings
        if parameters:
            settings = freeze({**settings, "plant": {q.name: q.value for q in plant.parameters}})
        if failure:
            t_fail = float(self.time[failure["step"]])
            settings = freeze({**settings, "integrator_failure": (
                f"the integrator stopped at t = {t_fail:.6g} s ({failure['error']}): the loop diverged or is too "
                "stiff for the step; the records are NaN from there")})
        p, law = plant, self.law
        nx, nc, nu, nd = len(p.states), law.n_state, len(p.inputs), len(p.disturbances)
        cuts = np.cumsum([0, nx, nc, nu, nu, nx, nd])
        x, xc, u_c, u_a, y, d = (rec[a:b].T for a, b in zip(cuts[:-1], cuts[1:], strict=True))
        tracked: dict[str, Any] = {}
        if self.motion is not None:
            from designkit.simulation.motion import tracked_outputs

            tracked = {"tracked": tracked_outputs(self.motion, x[:, list(p.positions)]),
                       "tracked_names": self.motion.space.names, "tracked_units": self.motion.space.units}
        return SimulationResult(
            time=self.time, reference=self.reference, state=x, controller_state=xc, u_command=u_c, u_applied=u_a,
            perturbation=d, measured=y, kind=self.kind, positions=tuple(p.positions), velocities=tuple(p.velocities),
            state_names=tuple(s.name for s in p.states), controller_state_names=law.state_names,
            input_names=tuple(s.name for s in p.inputs), disturbance_names=tuple(s.name for s in p.disturbances),
            settings=settings, **tracked,
        )


def _evaluator(step: ca.Function, n_steps: int, mode: str, runs: int = 1) -> tuple[ca.Function | None, dict[str, Any]]:
    """The compiled ``mapaccum`` to run ``step`` with, or None for the interpreted one, and why."""
    from designkit.models.codegen import cached_library, compile_function, find_compiler

    estimate = runs * n_steps * step.n_instructions() * INTERPRETED_SECONDS_PER_INSTRUCTION
    info: dict[str, Any] = {"mode": mode, "interpreted_estimate_s": round(estimate, 4)}
    if mode == "never":
        return None, {**info, "compiled": False, "why": "numerics.compile: never"}
    if not step.is_a("SXFunction"):
        return None, {**info, "compiled": False, "why": "a CVODES step is not compiled"}
    if find_compiler() is None:
        return None, {**info, "compiled": False, "why": "no C compiler on PATH"}
    if mode == "auto" and estimate < CACHE_LOOKUP_FLOOR:
        return None, {**info, "compiled": False,
                      "why": f"interpreted run estimated at {estimate:.3g} s: nothing to gain"}
    acc = step.mapaccum(f"{step.name()}_acc", CHUNK)
    cached = cached_library(acc, flags=COMPILE_FLAGS) is not None
    if mode == "auto" and not cached and estimate < COMPILE_BREAK_EVEN:
        return None, {**info, "compiled": False,
                      "why": f"interpreted run estimated at {estimate:.3g} s, below the {COMPILE_BREAK_EVEN:g} s "
                             "it costs to compile"}
    compiled = compile_function(acc, flags=COMPILE_FLAGS)
    if not compiled.compiled:
        return None, {**info, "compiled": False, "why": compiled.reason}
    return compiled.function, {**info, "compiled": True, "why": "cached library" if cached else "compiled now",
                               "flags": " ".join(COMPILE_FLAGS)}


def check_reference(ref: Reference, t: np.ndarray, plant: Any, spec: Spec, kind: str) -> None:
    """The commanded motion must stay within the robot's joint limits (``qlim``) and, when the spec gives
    them, ``plant.limits.velocity`` and ``acceleration``; else :class:`SpecError` naming the reference."""
    key = "simulation.trajectory" if kind == "trajectory" else "simulation.step"
    x = ref.evaluate(t)
    for j, lim in enumerate(getattr(plant, "joint_limits", ())):
        if lim is None:
            continue
        bad = np.flatnonzero((x[:, j, 0] < lim[0] - 1e-12) | (x[:, j, 0] > lim[1] + 1e-12))
        start = ref.start[j] if j < len(ref.start) else 0.0
        if not lim[0] - 1e-12 <= start <= lim[1] + 1e-12:
            raise SpecError("simulation.initial_position", f"joint {j + 1} starts at {start:.4g} rad, outside its "
                                                           f"limits [{lim[0]:.4g}, {lim[1]:.4g}] rad")
        if bad.size:
            k = int(bad[0])
            raise SpecError(key, f"joint {j + 1} leaves its limits [{lim[0]:.4g}, {lim[1]:.4g}] rad at t = "
                                 f"{t[k]:.4g} s (qD = {x[k, j, 0]:.4g} rad)")
    limits = getattr(spec.plant, "limits", None)
    for name, column, unit in (("velocity", 1, "rad/s"), ("acceleration", 2, "rad/s^2")):
        value = getattr(limits, name, None) if limits is not None else None
        if value is None or kind != "trajectory":
            continue
        bound = np.broadcast_to(np.asarray(value, dtype=float), (ref.n,))
        peak = np.max(np.abs(x[:, :, column]), axis=0)
        j = int(np.argmax(peak / bound))
        if peak[j] > bound[j] * (1 + 1e-9):
            k = int(np.argmax(np.abs(x[:, j, column])))
            raise SpecError(key, f"joint {j + 1} needs {peak[j]:.4g} {unit} at t = {t[k]:.4g} s, above "
                                 f"plant.limits.{name} {bound[j]:g} {unit}")


def build(spec: Spec, design: Design, *, plant: Any = None, law: Law | None = None, expected_runs: int = 1
          ) -> Simulator:
    """Build the simulation of ``design`` in the scenario ``spec.simulation`` on ``plant``.

    Parameters
    ----------
    spec : Spec
        Its ``simulation`` (and ``requirements.settling_time`` for the default duration) and
        ``numerics`` sections are used.
    design : Design
        The controller; ``design.plant`` is the nominal plant its model terms use.
    plant : Plant, optional
        The true plant (default: ``design.plant``), e.g. with other parameter values.
    law : Law, optional
        The controller (default: the design's family's law with the spec's anti-windup); any
        :class:`~designkit.synthesis.law.Law`, e.g. one with a discrete memory.
    expected_runs : int
        How many times the simulator will run (a sweep): weighs the choice of compiled evaluation.

    Raises
    ------
    SpecError
        On a per-joint list of the wrong length, ``simulation.dt`` incompatible with the
        sampling period, the delay or the poles, or a run beyond the step bound (naming
        ``simulation.dt``, ``simulation.duration`` or an explicit ``numerics.integrator: rk4`` on a
        stiff loop; see :mod:`designkit.simulation.timing`).
    """
    from designkit.simulation.motion import motion_of

    true_plant = design.plant if plant is None else plant
    sim, kind = spec.simulation, design.reference
    n = len(true_plant.positions)
    motion = motion_of(spec, design)
    ref: Reference = motion.reference if motion is not None else reference_for(kind, sim, n)
    law = family(design.kind).law(design, sim.anti_windup) if law is None else law
    element = element_for(sim.nonlinearity, len(true_plant.inputs))
    rates = rates_of(_requested_poles(design), *_closed_loop_poles(design, true_plant, law), reference_rate=ref.rate)
    held_per_step = sim.sampling_period == 0 and (sim.delay > 0 or not element.continuous)
    timing = resolve(spec, rates, ref.horizon, held_per_step=held_per_step)

    t = grid(timing)
    if motion is None:  # a task-space path is checked on its joint path (the family's motion)
        check_reference(ref, t, true_plant, spec, kind)
    N, dt = timing.n_samples, timing.dt
    nx, nd, nu = len(true_plant.states), len(true_plant.disturbances), len(true_plant.inputs)
    noise, noise_settings = _noise(spec, N, nx, tuple(s.name for s in true_plant.states))
    dist, pert_settings = _perturbation(spec, t, dt, nd)
    flag = np.ones((1, N))
    if timing.steps_per_sample:
        flag[:] = 0.0
        flag[0, :: timing.steps_per_sample] = 1.0
    p_rows = np.repeat(np.asarray(true_plant.parameter_vector, dtype=float).reshape(-1, 1), N, axis=1)
    inputs = np.vstack([ref.flat(t).T, ref.flat(t + 0.5 * dt).T, ref.flat(t + dt).T, noise, dist, flag,
                        np.zeros((nu, N)), p_rows])
    x0 = np.asarray(true_plant.rest_state(ref.start), dtype=float)
    z0 = np.concatenate([x0, np.zeros(law.n_state), np.asarray(law.initial_memory, dtype=float),
                         np.asarray(element.initial_memory, dtype=float),
                         np.zeros(nu + law.n_state + nu * timing.delay_steps)])
    step = _step_function(true_plant, law, element, timing, spec.numerics)
    accumulated, compile_info = _evaluator(step, N, spec.numerics.compile, expected_runs)

    unused = {"step": ("trajectory", "a servo is driven by simulation.step"),
              "trajectory": ("step", "a tracking controller is driven by simulation.trajectory")}[kind]
    ignored = [f"simulation.{unused[0]} ({unused[1]})"] if unused[0] in sim.model_fields_set else []
    numerics = spec.numerics
    integrator = ("rk4 (classical, fixed step)" if timing.integrator == "rk4" else
                  f"cvodes (variable-step BDF inside each step, rtol {numerics.rtol:g}, atol {numerics.atol:g})")
    settings = {
        "integrator": integrator,
        **timing.settings,
        "evaluation": "chain inside every integration step" if (
            timing.steps_per_sample == 0 and timing.delay_steps == 0 and element.continuous)
        else "controller output, nonlinear element and delay once per step, held over the step",
        "plant": {q.name: q.value for q in true_plant.parameters},
        "nominal_plant": {q.name: q.value for q in design.plant.parameters},
        "controller": {"kind": law.kind, **law.settings},
        "reference": dict(ref.settings),
        "nonlinearity": element.settings,
        "delay": float(sim.delay),
        "sampling_period": float(sim.sampling_period),
        "noise": noise_settings,
        "perturbation": pert_settings,
        "initial_state": {**{s.name: float(v) for s, v in zip(true_plant.states, x0, strict=True)},
                          **dict.fromkeys(law.state_names, 0.0)},
        "ignored": ignored,
    }
    return Simulator(step=step, inputs=inputs, z0=z0, time=t, reference=ref.evaluate(t), kind=kind,
                     plant=true_plant, law=law, settings=freeze(settings), accumulated=accumulated,
                     compiled=freeze(compile_info), motion=motion)


def simulate(spec: Spec, design: Design, *, plant: Any = None) -> SimulationResult:
    """Simulate ``design`` in the scenario ``spec.simulation`` (see :func:`build`).

    Examples
    --------
    >>> from designkit.spec.loader import parse_spec
    >>> from designkit.families import synthesize
    >>> spec = parse_spec(
    ...     "name: demo\\nplant: {kind: link, Km: 2, tau: 0.5}\\n"
    ...     "controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}\\n"
    ...     "simulation: {duration: 3, nonlinearity: {kind: saturation, limit: 20}}"
    ... ).spec
    >>> res = simulate(spec, synthesize(spec))
    >>> res.settings["dt"], len(res.time), round(float(res.position[-1]), 4)
    (0.001, 3001, 1.0)
    >>> float(abs(res.u_applied).max())
    20.0
    """
    return build(spec, design, plant=plant).run()

