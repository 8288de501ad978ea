"""Closed-loop simulation of the link under a designed controller (the notes' POSSPEED, appendix B).

Signal chain, per integration step ``[t_k, t_k + dt]`` (``dt`` from
:mod:`designkit.simulation.timing`)::

    y = x + n_k                     measurement, Gaussian noise n_k held over the step
    u_c = law.command(y, x_c, r)    controller (sampled: only at sampling instants, then held)
    v = element(u_c, m)             nonlinear element (saturation, dead zone, relay, quantizer)
    u_a(t) = v(t - delay)           delay line of ``delay/dt`` steps
    x' = link(x, u_a, xi_k)         plant, RK4; x_c' = law.derivative(...) integrated alongside

Evaluation: when the controller is continuous (``sampling_period = 0``), there is no delay and
the element is continuous and memoryless (none, saturation, dead zone), the whole chain is
evaluated inside every RK4 stage (fourth-order accurate, with the reference at ``t``,
``t + dt/2``, ``t + dt``).  Otherwise the discontinuous parts (relay switching, quantizer,
sampling instants, delay line) are evaluated once per step, at the step's start, and the
applied control is held over the step: ``dt`` must be small compared with the dynamics, which
the default guarantees.  A sampled controller runs at ``t = j Ts``: it computes ``u`` and the
derivative of its state there and holds both (rectangular integration of the integral).  The
anti-windup gate is evaluated at each step's start; its clamp after each step.  The
perturbation ``xi`` is held per step: a step at ``time`` acts from the first ``t_k >= time``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from designkit.models.link import LinkPlant
from designkit.simulation.integrate import link_ode, rk4, run_steps
from designkit.simulation.laws import Law, law_for
from designkit.simulation.nonlinear import Element, element_for
from designkit.simulation.reference import reference_for
from designkit.simulation.result import SimulationResult
from designkit.simulation.timing import Timing, grid, resolve
from designkit.spec.schema import Spec
from designkit.synthesis.design import Design
from designkit.synthesis.registry import family

N_INPUTS = 13
"""Per-step inputs: reference at start, middle, end (3 x 3), noise (2), xi, sampling flag."""


def _step_function(plant: LinkPlant, law: Law, element: Element, timing: Timing) -> ca.Function:
    """One integration step ``sim_step: (z, w) -> (z_next, record)`` of the augmented state.

    ``z = (x[2], x_c[nc], m[nm], u_hold, d_hold[nc], line[nd])``: plant, controller state,
    element memory, the zero-order-hold values (control and controller-state derivative) and the
    delay line (most recent first).  ``w`` is described by :data:`N_INPUTS`.  ``record`` is
    ``(x, x_c, u_command, u_applied, y, xi)`` at the step's start.
    """
    nc, nm, nd = law.n_state, element.n_memory, timing.delay_steps
    sampled = timing.steps_per_sample > 0
    per_step = sampled or nd > 0 or not element.continuous
    ode = link_ode(plant)
    z = ca.SX.sym("z", 2 + nc + nm + 1 + nc + nd)
    w = ca.SX.sym("w", N_INPUTS)
    parts = ca.vertsplit(z, np.cumsum([0, 2, nc, nm, 1, nc, nd]).tolist())
    x, xc, mem, u_hold, d_hold, line = parts
    r0, rm, r1, noise, xi, flag = w[0:3], w[3:6], w[6:9], w[9:11], w[11], w[12]

    y = x + noise
    gate = law.gate(y, xc, r0)
    if sampled:
        u_hold = ca.if_else(flag, law.command(y, xc, r0), u_hold)
        d_hold = ca.if_else(flag, law.derivative(y, xc, r0, gate), d_hold)
        u_cmd = u_hold
    else:
        u_cmd = law.command(y, xc, r0)

    if per_step:
        v, mem_next = element.function(u_cmd, mem)
        u_app = line[nd - 1] if nd > 0 else v
        line_next = ca.vertcat(v, line[: nd - 1]) if nd > 0 else line

        def applied(s, r):
            return u_app
    else:
        u_app, mem_next, line_next = element.function(u_cmd, mem)[0], mem, line

        def applied(s, r):
            return element.function(law.command(s[:2] + noise, s[2:], r), mem)[0]

    def rhs(s, r):
        xc_dot = d_hold if sampled else law.derivative(s[:2] + noise, s[2:], r, gate)
        return ca.vertcat(ode(s[:2], applied(s, r), xi), xc_dot)

    s_next = rk4(rhs, ca.vertcat(x, xc), timing.dt, (r0, rm, r1))
    z_next = ca.vertcat(s_next[:2], law.project(s_next[2:]), mem_next, u_hold, d_hold, line_next)
    record = ca.vertcat(x, xc, u_cmd, u_app, y, xi)
    return ca.Function("sim_step", [z, w], [z_next, record], ["z", "w"], ["z_next", "record"])


def _noise(spec: Spec, n: int) -> tuple[np.ndarray, dict[str, Any]]:
    noise = spec.simulation.noise
    if noise is None or noise.std == 0.0:
        return np.zeros((2, n)), {"std": 0.0, "seed": None}
    rng = np.random.default_rng(noise.seed)
    samples = rng.normal(0.0, noise.std, size=(n, 2)).T
    return samples, {"std": float(noise.std), "seed": int(noise.seed), "on": ["x1", "x2"],
                     "samples": "one per integration step, held over the step", "generator": "numpy PCG64"}


def _perturbation(spec: Spec, t: np.ndarray, dt: float) -> tuple[np.ndarray, dict[str, Any] | None]:
    pert = spec.simulation.perturbation
    if pert is None:
        return np.zeros_like(t), None
    on = t >= pert.time - 1e-9 * dt
    applied = float(t[on][0]) if on.any() else None
    return np.where(on, pert.value, 0.0), {"value": float(pert.value), "time": float(pert.time),
                                           "time_applied": applied}


def simulate(spec: Spec, design: Design, *, plant: LinkPlant | None = None) -> SimulationResult:
    """Simulate the link under ``design``'s controller in the scenario ``spec.simulation``.

    Parameters
    ----------
    spec : Spec
        The validated spec; its ``simulation`` section (and ``requirements.settling_time`` for
        the default duration) is used.
    design : Design
        Gains of a ``pid_servo`` or ``pid_tracking`` controller; ``design.plant`` is the nominal
        link the tracking law's model terms use.
    plant : LinkPlant, optional
        The true plant (default: ``design.plant``).

    Returns
    -------
    SimulationResult
        Trajectories at ``t_k = k dt`` (values at each step's start) and every option used.

    Raises
    ------
    SpecError
        On ``simulation.dt`` incompatible with the sampling period, the delay or the poles, or a
        controller kind without a simulation law.

    Examples
    --------
    >>> from designkit.spec.loader import parse_spec
    >>> from designkit.synthesis.registry import synthesize
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
    true_plant = design.plant if plant is None else plant
    sim = spec.simulation
    ref_kind = family(design.kind).reference
    ref = reference_for(ref_kind, sim)
    law = law_for(design, sim.anti_windup)
    element = element_for(sim.nonlinearity)
    timing = resolve(spec, design, true_plant, ref.rate, ref.horizon)

    t = grid(timing)
    n, dt = timing.n_samples, timing.dt
    noise, noise_settings = _noise(spec, n)
    xi, pert_settings = _perturbation(spec, t, dt)
    flag = np.zeros(n)
    if timing.steps_per_sample:
        flag[:: timing.steps_per_sample] = 1.0
    inputs = np.vstack([ref.evaluate(t).T, ref.evaluate(t + 0.5 * dt).T, ref.evaluate(t + dt).T, noise, xi, flag])

    z0 = np.concatenate([np.zeros(2 + law.n_state), element.initial_memory,
                         np.zeros(1 + law.n_state + timing.delay_steps)])
    records = run_steps(_step_function(true_plant, law, element, timing), z0, inputs)
    nc = law.n_state
    unused = {"step": ("trajectory", "a servo is driven by simulation.step"),
              "trajectory": ("step", "a tracking controller is driven by simulation.trajectory")}[ref_kind]
    ignored = [f"simulation.{unused[0]} ({unused[1]})"] if unused[0] in sim.model_fields_set else []
    settings = {
        "integrator": "rk4 (classical, fixed step)",
        **timing.settings,
        "evaluation": "chain inside every RK4 stage" if (
            timing.steps_per_sample == 0 and timing.delay_steps == 0 and element.continuous)
        else "controller output, nonlinear element and delay once per step, held over the step",
        "plant": {"Km": float(true_plant.Km), "tau": float(true_plant.tau)},
        "nominal_plant": {"Km": float(design.plant.Km), "tau": float(design.plant.tau)},
        "controller": {"kind": design.kind, **law.settings},
        "reference": ref.settings,
        "nonlinearity": element.settings,
        "delay": float(sim.delay),
        "sampling_period": float(sim.sampling_period),
        "noise": noise_settings,
        "perturbation": pert_settings,
        "initial_state": {"x1": 0.0, "x2": 0.0, **dict.fromkeys(law.state_names, 0.0)},
        "ignored": ignored,
    }
    return SimulationResult(
        time=t,
        reference=ref.evaluate(t),
        state=records[0:2].T.copy(),
        controller_state=records[2:2 + nc].T.copy(),
        u_command=records[2 + nc].copy(),
        u_applied=records[3 + nc].copy(),
        perturbation=records[6 + nc].copy(),
        measured=records[4 + nc:6 + nc].T.copy(),
        kind=ref_kind,
        state_names=("x1", "x2"),
        controller_state_names=law.state_names,
        settings=settings,
    )
