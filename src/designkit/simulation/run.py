"""Closed-loop simulation of any plant under a designed controller (the notes' POSSPEED and SIMNOG).

:func:`build` assembles a :class:`Simulator` from a spec's ``simulation`` section and a design:
the reference (:func:`~designkit.simulation.reference.reference_of`: a step, a trajectory, a square
wave or a PRBS, or the task-space path of ``design.motion``), the law (``design.law``, which carries
the spec's anti-windup), the nonlinear element, the noise and the perturbation, the time grid
(:mod:`designkit.simulation.timing`) and the step (:mod:`designkit.simulation.step`, where the
signal chain is described).  :meth:`Simulator.run` evaluates it.

With ``spec.implementation`` the loop is the controller as implemented (:mod:`designkit.simulation.implementation`):
its sampling period and computation delay drive the sampling and the delay line, its quantisation the measurement
the law reads, and its actuator (saturation, first-order lag) stands between the command and the true plant; the
settings then say in words what the verdict is on (``settings["implementation"]``), and a switching law run without
the section says that its verdict holds for a continuous-time switch (``settings["scope"]``).

Where the run starts: the plant at rest at the reference's start (``simulation.initial_position``),
the controller at :func:`~designkit.synthesis.closed_loop.rest_state` -- the states a law names in
``rest_start`` (integrals, reference models) solved so that the loop is at rest at the reference
before the motion, the others at the law's ``initial_state``.  The settings record the initial
controller state and whether the loop starts at rest.

The true plant's parameters ``p`` are an input of the step (repeated in every column of ``w``), so
one built simulator runs on any parameter values (``Simulator.run(parameters=...)``): sweeps over
an uncertainty box and model-mismatch studies never rebuild the step, and the compiled step is
shared by every parameter value.

Integrators (``numerics.integrator``): ``dopri5`` (compiled Dormand--Prince 5(4) with error control and dense output
over the whole grid, :mod:`designkit.simulation.dopri5`), ``rk4`` (classical, fixed step) or ``cvodes`` (CVODES, for
stiff plants: one call over the whole grid on a smooth loop, :mod:`designkit.simulation.cvodes_grid`, else a BDF
inside every step).  Without ``numerics.integrator`` the integrator is chosen from the poles
(:func:`~designkit.simulation.timing.resolve`): CVODES with an output step set by the non-stiff poles when RK4 would
need more steps than the bound, else the pair for a smooth loop and RK4 for one held per step, sampled, noisy or on
a non-smooth plant (:mod:`designkit.simulation.regime`; ``settings["integrator_choice"]`` says why).  The output
grid is the same whichever integrator runs.  RK4 and per-step CVODES steps are rolled by ``Function.mapaccum``
(:func:`~designkit.simulation.integrate.run_steps`): no Python loop per step.
A discontinuous law is held over each step (:mod:`designkit.simulation.step`), so CVODES integrates
a smooth right-hand side inside each step and never meets the switch.

Compiled evaluation (``numerics.compile``): the rolled RK4 step can be turned into C by CasADi's
code generator and the system C compiler (:func:`designkit.models.codegen.compile_function`,
cached by content hash, ``-O1 -ffp-contract=off`` so the compiled run equals the interpreted one
to the last bit).  ``auto`` (default) uses the compiled library when it is already cached, and
compiles when the interpreted run is estimated to cost more than compiling
(:data:`COMPILE_BREAK_EVEN`) or when the loop will run more than once (``build(expected_runs > 1)``: trials,
parameter corners, a sweep) and its interpreted run is above :data:`CACHE_LOOKUP_FLOOR`; ``always`` and
``never`` force the choice.  The Dormand--Prince pair of a smooth loop is compiled under ``auto`` and
``always`` whatever the estimate (one library per loop, cached; it is the default integrator), and runs the
same algorithm interpreted under ``never``.  Without a compiler, or
for a CVODES step, the interpreted CasADi virtual machine runs (the settings say which and why).
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit import arguments
from designkit.errors import SpecError
from designkit.models.plant import Plant
from designkit.simulation.compiled import (
    CHUNK,
    COMPILE_BREAK_EVEN,
    INTERPRETED_SECONDS_PER_INSTRUCTION,
    evaluator,
)
from designkit.simulation.cvodes_grid import IGNORED_METHOD, cvodes_for
from designkit.simulation.dopri5 import ATOL as DOPRI5_ATOL
from designkit.simulation.dopri5 import FLAGS as DOPRI5_FLAGS
from designkit.simulation.dopri5 import RTOL as DOPRI5_RTOL
from designkit.simulation.dopri5 import build_dopri5
from designkit.simulation.implementation import (
    actuated,
    implemented_of,
    lag_rates,
    lag_step_error,
    measure_function,
    measuring_law,
    switching_scope,
)
from designkit.simulation.implementation import words as implementation_words
from designkit.simulation.integrate import flat_inputs, run_steps
from designkit.simulation.nonlinear import element_for
from designkit.simulation.reference import Reference, reference_of
from designkit.simulation.regime import regime_of
from designkit.simulation.result import SimulationResult
from designkit.simulation.scenario import (
    check_reference,
    noise_rows_of,
    parameter_rows,
    perturbation_rows,
    plant_change,
)
from designkit.simulation.step import layout, step_function
from designkit.simulation.timing import DT_FACTOR, delay_of, grid, rates_of, resolve, sampling_of
from designkit.synthesis.closed_loop import linearize, rest_state
from designkit.synthesis.design import Design, freeze
from designkit.synthesis.law import Law

__all__ = ["COMPILE_BREAK_EVEN", "MAX_EXPECTED_RUNS", "Simulator", "build", "simulate"]

MAX_EXPECTED_RUNS = 10**9
"""Largest ``expected_runs`` of :func:`build`."""

def _closed_loop_poles(design: Design, plant: Any) -> list[np.ndarray]:
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
    linear = design.linear_law
    if plant is not design.plant and op and linear is not None:
        with contextlib.suppress(ValueError):  # no equilibrium on the true plant: the nominal rates stand
            out.append(linearize(plant, linear, op["r"], z0=[*op["x"], *op["xc"]])[0].poles)
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
    restep : callable or None
        ``Law -> sim_step``: the step of this loop (plant, element, timing) with another law of the same layout,
        e.g. one whose functions call compiled C (the ``generated_code`` check).
    regime : Regime or None
        How the loop is evaluated in time (:mod:`designkit.simulation.regime`): held per step, or smooth.
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
    change: Any = None
    dopri5: Any = None
    cvodes: Any = None
    implementation: Any = None
    restep: Any = field(default=None, repr=False)
    regime: Any = None
    _flat: dict = field(default_factory=dict, repr=False)

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
                inputs[-npar:] = parameter_rows(plant, self.time.size, self.change)
        failure: dict[str, Any] = {}
        settings = self.settings
        if self.dopri5 is not None:  # a feedforward changing at a step is a breakpoint the pair ends a step on
            rec = self.dopri5.run(self.z0, inputs, failure)
            settings = freeze({**settings, "integrator_work": _work_words(self.dopri5.stats, self.time.size - 1)})
            if failure:  # a diverging loop: integrated again on the grid, every state as far as it stays finite
                t_stop = float(self.time[max(failure["step"], 0)])
                failure.clear()
                rec = run_steps(self.step, self.z0, inputs, chunk=CHUNK, failure=failure)
                settings = freeze({**settings, "integrator": (
                    f"{RK4_WORDS}: the Dormand-Prince pair stopped at t = {t_stop:.6g} s (its step fell below 1e-14 s "
                    "or its step budget ran out: a diverging or stiff loop), so the run was integrated again by RK4 "
                    "on the output grid")})
        elif self.cvodes is not None:  # a smooth loop on CVODES: one call over the whole grid
            rec = self.cvodes.run(self.z0, inputs, failure)
            settings = freeze({**settings, "integrator_work": self.cvodes.work_words(self.time.size - 1)})
        else:
            m = self.accumulated.size2_in(1) if self.accumulated is not None else max(1, min(CHUNK, inputs.shape[1]))
            flat = None
            if inputs is self.inputs:  # run again on its own inputs: laid out once
                kept = self._flat.get(m)
                flat = kept if kept is not None else self._flat.setdefault(m, flat_inputs(inputs, m))
            rec = run_steps(self.step, self.z0, inputs, chunk=CHUNK, accumulated=self.accumulated, failure=failure,
                            flat=flat)
        if parameters:
            settings = freeze({**settings, "plant": {q.name: q.value for q in plant.parameters}})
        if failure:
            t_fail = float(self.time[failure["step"]])
            settings = freeze({**settings, "integrator_failure": (
                f"the integrator stopped at t = {t_fail:.6g} s ({failure['error']}): the loop diverged or is too "
                "stiff for the step; the records are NaN from there")})
        return self.result(rec, plant=plant, settings=settings)

    def result(self, rec: np.ndarray, *, plant: Any = None, settings: Mapping[str, Any] | None = None
               ) -> SimulationResult:
        """The result of records ``rec`` (``(n_record, N)``, one column per step, as ``step`` writes them) of this
        loop, e.g. records moved along a sensitivity; ``plant`` and ``settings`` default to the simulator's."""
        p, law = (self.plant if plant is None else plant), self.law
        settings = self.settings if settings is None else settings
        rec.setflags(write=False)  # the result keeps views of the records instead of copies
        impl = self.implementation
        extra = impl.n_lag if impl is not None else 0
        sizes = layout(p, law, _NoElement, 0).record_sizes
        sizes[0] += extra  # the actuator's lag states follow the plant's, in the state and the measurement
        sizes[4] += extra
        cuts = np.cumsum([0, *sizes])
        x, xc, u_c, u_a, y, d, sig = (rec[a:b].T for a, b in zip(cuts[:-1], cuts[1:], strict=True))
        if impl is not None:
            nx = len(p.states)
            u_a = impl.applied(u_a, x[:, nx:])
            x, y = x[:, :nx], y[:, :nx]
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
            settings=settings, signals={name: sig[:, k] for k, name in enumerate(law.signal_names)},
            signal_units=dict(zip(law.signal_names, law.signal_units, strict=True)), **tracked,
        )


RK4_WORDS = "rk4 (classical, fixed step)"


def _work_words(stats: Mapping[str, float], n_steps: int) -> str:
    """The adaptive integrator's work, in words."""
    return (f"{stats.get('evaluations', 0):,} evaluations of the right-hand side over the {n_steps:,} output steps "
            f"({stats.get('accepted', 0):,} steps accepted, {stats.get('rejected', 0):,} rejected)")


class _NoElement:
    """Sizes of the record only (an element's memory is not recorded)."""

    n_memory = 0


def build(spec: Any, design: Design, *, plant: Any = None, law: Law | None = None, expected_runs: int = 1,
          reference: Reference | None = None) -> Simulator:
    """Build the simulation of ``design`` in the scenario ``spec.simulation`` on ``plant``.

    Parameters
    ----------
    spec : Spec
        Its ``simulation``, ``implementation`` (and ``requirements.settling_time`` for the default duration) and
        ``numerics`` sections are used.
    design : Design
        The controller; ``design.plant`` is the nominal plant its model terms use.
    plant : Plant, optional
        The true plant (default: ``design.plant``), e.g. with other parameter values.
    law : Law, optional
        The controller (default: ``design.law``); any :class:`~designkit.synthesis.law.Law`, e.g. a
        frozen-gain variant of an adaptive law.
    expected_runs : int
        How many times the simulator will run (a sweep), 1 to :data:`MAX_EXPECTED_RUNS`: weighs the choice of
        compiled evaluation.
    reference : Reference, optional
        The reference to follow (default :func:`~designkit.simulation.reference.reference_of`), e.g. the
        spec's scaled to a small signal.

    Raises
    ------
    SpecError
        On a per-joint list of the wrong length, ``simulation.dt`` incompatible with the sampling
        period, the delay, the poles or the law's largest step, or a run beyond the step bound
        (naming ``simulation.dt``, ``simulation.duration`` or an explicit ``numerics.integrator: rk4`` on
        a stiff loop; see :mod:`designkit.simulation.timing`); an ``implementation`` whose sampling period or delay
        conflicts with ``simulation``'s or the law's, is not shorter than the run, or whose per-state or per-input
        list has the wrong length (naming its key).
    ValueError
        ``design`` has no law and none is given.
    """
    from designkit.spec.fields import spec_argument

    spec = spec_argument(spec)
    if not isinstance(design, Design):
        raise SpecError("design", f"must be a Design (dk.synthesize(spec)), got {type(design).__name__}")
    arguments.instance(plant, "plant", Plant, "a Plant (dk.zoo_plant, spec.plant.build())", optional=True)
    arguments.instance(law, "law", Law, "a Law (a design's law)", optional=True)
    arguments.instance(reference, "reference", Reference, "a Reference", optional=True)
    expected_runs = arguments.integer(expected_runs, "expected_runs", low=1, high=MAX_EXPECTED_RUNS)
    true_plant = design.plant if plant is None else plant
    sim, kind = spec.simulation, design.reference
    motion = design.motion
    ref = reference_of(spec, design) if reference is None else reference
    law = design.law if law is None else law
    if law is None:
        raise ValueError(f"this {design.kind} design carries no law to simulate")
    _check_anti_windup(sim.anti_windup, law)
    element = element_for(sim.nonlinearity, len(true_plant.inputs))
    impl = implemented_of(spec, true_plant)
    rates = rates_of(_requested_poles(design), *_closed_loop_poles(design, true_plant), lag_rates(impl),
                     reference_rate=ref.rate)
    sampling = sampling_of(spec, law)
    delay = delay_of(spec)
    measure = measure_function(impl, len(true_plant.states) + (impl.n_lag if impl is not None else 0))
    quantized = measure is not None
    noisy = sim.noise is not None and bool(np.any(np.asarray(sim.noise.std, dtype=float) > 0))
    regime = regime_of(law, element, sampled=sampling[0] > 0, delayed=delay[0] > 0, noisy=noisy, quantized=quantized)
    held_per_step = sampling[0] == 0 and regime.per_step
    try:
        timing = resolve(spec, rates, ref.horizon, held_per_step=held_per_step, max_dt=law.max_step,
                         max_dt_reason=law.max_step_reason, sampling=sampling, delay=delay)
    except SpecError as exc:
        others = rates_of(_requested_poles(design), *_closed_loop_poles(design, true_plant), reference_rate=ref.rate)
        law_rate = DT_FACTOR / law.max_step if law.max_step else 0.0
        raise lag_step_error(exc, impl, max(others.fast, law_rate)) from None

    t = grid(timing)
    if motion is None:  # a task-space path is checked on its joint path (the family's motion)
        check_reference(ref, t, true_plant, spec, kind)
    N, dt = timing.n_samples, timing.dt
    nx, nd, nu = len(true_plant.states), len(true_plant.disturbances), len(true_plant.inputs)
    noise, noise_settings = noise_rows_of(spec, N, nx, tuple(s.name for s in true_plant.states))
    n_lag = impl.n_lag if impl is not None else 0
    if n_lag:  # the actuator's states are not measured with noise (the law does not read them)
        noise = np.vstack([noise, np.zeros((n_lag, N))])
    dist, pert_settings = perturbation_rows(spec, t, dt, nd)
    flag = np.ones((1, N))
    if timing.steps_per_sample:
        flag[:] = 0.0
        flag[0, :: timing.steps_per_sample] = 1.0
    change, change_settings = plant_change(sim.plant_change, true_plant, t, dt)
    p_rows = parameter_rows(true_plant, N, change)
    stages = (ref.flat(t).T,) * 3 if ref.piecewise_constant else (
        ref.flat(t).T, ref.flat(t + 0.5 * dt).T, ref.flat(t + dt).T)  # a jump acts from the step it falls on
    inputs = np.vstack([*stages, noise, dist, flag, np.zeros((nu, N)), p_rows])
    x0 = np.asarray(true_plant.rest_state(ref.start), dtype=float)
    rest = rest_state(true_plant, law, x0, ref.rest())
    loop_plant, loop_law = actuated(true_plant, impl), measuring_law(law, nx, n_lag)
    x0_loop = np.concatenate([x0, _lag_start(impl, law, x0, rest, ref.rest(), measure)])
    z0 = np.concatenate([x0_loop, rest.xc, np.asarray(law.initial_memory, dtype=float),
                         np.asarray(element.initial_memory, dtype=float),
                         np.zeros(nu + law.n_state + nu * timing.delay_steps)])
    step = step_function(loop_plant, loop_law, element, timing, spec.numerics, measure=measure)

    def restep(other: Law) -> ca.Function:  # the same step with another law of the same layout
        return step_function(loop_plant, measuring_law(other, nx, n_lag), element, timing, spec.numerics,
                             measure=measure)

    if regime.smooth and true_plant.nonsmooth():  # smooth unless the law leaves the plant's jump in the loop
        regime = regime_of(law, element, sampled=sampling[0] > 0, delayed=delay[0] > 0, noisy=noisy,
                           plant=loop_plant, probe=_probe(loop_plant, loop_law, element, z0, inputs),
                           quantized=quantized)
    dopri5, integrator, choice = _pair(spec, timing, regime, loop_plant, loop_law, element)
    cvodes = cvodes_for(spec.numerics, timing, regime, rates, loop_plant, loop_law, element, t)  # None unless so
    if cvodes is not None:
        integrator, accumulated, compile_info = cvodes.settings_words, None, cvodes.compile_info
    elif dopri5 is None:
        accumulated, compile_info = evaluator(step, N, spec.numerics.compile, expected_runs)
    else:
        accumulated = None
        estimate = expected_runs * N * step.n_instructions() * INTERPRETED_SECONDS_PER_INSTRUCTION
        compile_info = {"mode": spec.numerics.compile, "compiled": dopri5.library is not None,
                        "integrator": "dopri5", "interpreted_estimate_s": round(estimate, 4),
                        "why": ("compiled now" if dopri5.compiled_now else "cached library") if dopri5.library
                        else integrator.rsplit("interpreted: ", 1)[-1].rstrip(")"), "flags": " ".join(DOPRI5_FLAGS)}

    if kind == "trajectory":
        ignored = (["simulation.step (a tracking controller is driven by simulation.trajectory)"]
                   if "step" in sim.model_fields_set else [])
    else:  # a servo follows simulation.trajectory when given (a square wave, a PRBS), else simulation.step
        ignored = (["simulation.step (the reference is simulation.trajectory)"]
                   if sim.trajectory is not None and "step" in sim.model_fields_set else [])
    if "cvodes_method" in spec.numerics.model_fields_set and cvodes is None:
        ignored.append(IGNORED_METHOD)
    evaluation = ("chain inside every integration step" if not held_per_step and timing.steps_per_sample == 0
                  else "controller output, nonlinear element and delay once per step, held over the step")
    if law.discontinuous and timing.steps_per_sample == 0:
        evaluation = ("discontinuous law: its command and state derivative evaluated once per step, at the step's "
                      "start, and held over the step (the step is its sampling period)")
    elif quantized and timing.steps_per_sample == 0:
        evaluation = ("quantised measurements: the law's command and state derivative evaluated once per step on the "
                      "quantised measurement, at the step's start, and held over the step")
    settings = {
        "integrator": integrator,
        **timing.settings,
        "integrator_choice": choice,
        "evaluation": evaluation,
        "plant": {q.name: q.value for q in true_plant.parameters},
        "nominal_plant": {q.name: q.value for q in design.plant.parameters},
        "controller": {"kind": law.kind, **law.settings},
        "reference": dict(ref.settings),
        "nonlinearity": element.settings,
        "delay": float(delay[0]),
        "sampling_period": float(sampling[0]),
        "sampling_period_source": sampling[1] if sampling[0] > 0 else "",
        **_scope(spec, impl, law, true_plant, timing.dt, sampling[0], delay[0]),
        "noise": noise_settings,
        "perturbation": pert_settings,
        "plant_change": change_settings,
        "initial_state": {**{s.name: float(v) for s, v in zip(loop_plant.states, x0_loop, strict=True)},
                          **{name: float(v) for name, v in zip(law.state_names, rest.xc, strict=True)}},
        "start": _start_words(law, rest),
        "ignored": ignored,
    }
    reference = ref.evaluate(t)
    for arr in (t, reference):  # shared by every run's result, never written
        arr.setflags(write=False)
    return Simulator(step=step, inputs=inputs, z0=z0, time=t, reference=reference, kind=kind,
                     plant=true_plant, law=law, settings=freeze(settings), accumulated=accumulated,
                     compiled=freeze(compile_info), motion=motion, change=change, dopri5=dopri5, cvodes=cvodes,
                     implementation=impl if impl is not None and impl.changes_plant else None, restep=restep,
                     regime=regime)


def _lag_start(impl: Any, law: Law, x0: np.ndarray, rest: Any, before: np.ndarray, measure: Any) -> np.ndarray:
    """The actuator lag's initial states: the clipped command of the loop at rest before the motion (empty without
    a lag)."""
    if impl is None or not impl.bandwidth:
        return np.zeros(0)
    y0 = x0 if measure is None else np.asarray(measure(np.r_[x0, np.zeros(impl.n_lag)]), dtype=float).ravel()[
        :x0.size]
    m0 = np.asarray(law.initial_memory, dtype=float)
    u0 = np.asarray(law.command(y0, rest.xc, m0, np.asarray(before, dtype=float)), dtype=float).ravel()
    if impl.limit:
        lim = np.asarray(impl.limit, dtype=float)
        u0 = np.clip(u0, -lim, lim)
    return np.where(np.isfinite(u0), u0, 0.0) + 0.0  # no negative zero in the settings


def _scope(spec: Any, impl: Any, law: Law, plant: Any, dt: float, sampling: float, delay: float) -> dict[str, str]:
    """The settings that say what the verdict is on: ``implementation`` (the controller as implemented, in words)
    when the spec gives the section; ``scope`` for a switching law run without it."""
    if getattr(spec, "implementation", None) is not None:
        return {"implementation": implementation_words(impl, plant, sampling, delay)}
    if law.discontinuous:
        return {"scope": switching_scope(law, dt, sampling)}
    return {}


def _probe(plant: Any, law: Law, element: Any, z0: np.ndarray, inputs: np.ndarray) -> tuple[Any, np.ndarray]:
    """The closed loop's ``s -> s_dot`` at the first step's reference and held inputs, and the start ``s``."""
    from designkit.simulation.dopri5 import loop_functions

    rhs, _, _, n_ref = loop_functions(plant, law, element)
    a, q = inputs[:n_ref, 0], inputs[3 * n_ref:, 0]
    return (lambda s: rhs(s, a, q)), np.asarray(z0[:rhs.size1_in(0)], dtype=float)


def _pair(spec: Any, timing: Any, regime: Any, plant: Any, law: Law, element: Any) -> tuple[Any, str, str]:
    """``(runner, integrator words, choice words)``: the compiled Dormand--Prince pair for a smooth loop (the
    default, or ``numerics.integrator: dopri5``), else None and the fixed-step or CVODES words.

    Raises
    ------
    SpecError
        ``numerics.integrator: dopri5`` on a loop that is not smooth (held per step, sampled, noisy).
    """
    numerics = spec.numerics
    given = numerics.model_fields_set
    choice = str(timing.settings.get("integrator_choice", ""))
    if timing.integrator == "cvodes":
        return None, f"cvodes (variable-step BDF inside each step, rtol {numerics.rtol:g}, atol {numerics.atol:g})", \
            choice
    explicit = "integrator" in given
    if timing.integrator == "dopri5" and not regime.smooth:
        raise SpecError("numerics.integrator", f"dopri5 integrates smooth continuous loops only, and here "
                        f"{regime.why}; use rk4 or leave numerics.integrator out")
    if explicit and timing.integrator == "rk4":
        return None, RK4_WORDS, choice
    if not regime.smooth:
        return None, RK4_WORDS, f"default: rk4 on the output grid, because {regime.why}"
    rtol = float(numerics.rtol) if "rtol" in given else DOPRI5_RTOL
    atol = float(numerics.atol) if "atol" in given else DOPRI5_ATOL
    runner, how = build_dopri5(plant, law, element, timing.dt, rtol=rtol, atol=atol,
                               compile=numerics.compile != "never", resets=bool(getattr(regime, "resets", False)))
    source = "numerics.rtol and numerics.atol" if {"rtol", "atol"} & given else "defaults"
    ran = "compiled C" if runner.library is not None else f"interpreted: {how}"
    words = (f"dopri5 (Dormand-Prince 5(4), adaptive step with error control: rtol {rtol:g}, atol {atol:g}, "
             f"{source}; PI step-size control; the output grid written from its 4th-order continuous extension; "
             f"{ran})")
    if runner.proj is not None:
        words += ("; the law's projection applied at every grid instant, the integration started again from the "
                  "projected state where it moved it")
    why = "numerics.integrator" if explicit else ("default for a smooth continuous loop (no sampling, switching, "
                                                  "delay, memory, anti-windup or noise)")
    if plant.nonsmooth():
        why += (f"; the plant's {'; '.join(plant.nonsmooth())} is cancelled by the law's compensation (the closed "
                "loop is continuous across zero velocity)")
    return runner, words, why


def _check_anti_windup(section: Any, law: Law) -> None:
    """The law carries the spec's anti-windup (it is part of the designed law), else :class:`SpecError`."""
    carried = law.settings.get("anti_windup")
    if carried is None:
        return
    wanted = "none" if section is None else section.kind
    if carried.get("kind") != wanted or (section is not None and not np.allclose(
            np.asarray(carried.get("value"), dtype=float), np.asarray(section.value, dtype=float))):
        raise SpecError("simulation.anti_windup", f"the design's law carries anti-windup {carried.get('kind')!r} but "
                        f"the spec asks for {wanted!r}: the anti-windup is part of the designed law, so synthesize "
                        "the design from this spec (designkit.families.synthesize)")


def _start_words(law: Law, rest: Any) -> dict[str, Any]:
    """How the run starts, for the settings: at rest or not, and which controller states were solved for."""
    solved = ", ".join(rest.solved)
    how = (f"the loop starts at rest at the reference before the motion ({solved} solved for it)" if rest.solved
           else "the loop starts from the law's initial state")
    if not rest.at_rest:
        how = (f"the loop does not start at rest: |dz/dt| = {rest.residual:.3g} at t = 0 with the plant at rest "
               "at its initial position" + (f" ({solved} solved for the closest rest)" if rest.solved else ""))
    return {"at_rest": rest.at_rest, "residual": rest.residual, "solved": list(rest.solved), "words": how}


def simulate(spec: Any, design: Design, *, plant: Any = None) -> SimulationResult:
    """Simulate ``design`` in the scenario ``spec.simulation`` (see :func:`build`).

    Examples
    --------
    >>> from designkit.schema.loader import parse_spec
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

    A design that runs its own trials (``design.learning.run``: a sampled plant the simulator does not integrate)
    runs them, on ``plant`` or the spec's plant, and its last trial is returned.
    """
    learning = getattr(design, "learning", None)
    if learning is not None and learning.run is not None:
        if plant is None:
            from designkit.spec.plant_builder import plant_from_spec

            plant = plant_from_spec(spec.plant)
        return learning.run(spec, plant).results[-1]
    return build(spec, design, plant=plant).run()

