"""One integration step of the closed loop as a CasADi function: ``sim_step: (z, w) -> (z_next, record)``.

Signal chain over the step ``[t_k, t_k + dt]``::

    y = x + n_k                        measurement, Gaussian noise n_k held over the step (quantised when the
                                       spec gives implementation.quantization: ``measure``)
    u_c = law.command(y, xc, m, r) + F(y, xc, m, r, v_k)
                                       controller plus the trial's feedforward v_k (F = law.feedforward,
                                       v_k itself when the law declares none); sampled or discontinuous:
                                       only at the step's start, then held
    m <- law.update(y, xc, m, r)       the law's discrete memory, at each controller sample (before the
                                       command when the law says ``command_after_update``: measure,
                                       update, compute; the signals are recorded on the same memory)
    v = element(u_c, e)                nonlinear element per input (saturation, dead zone, relay, quantizer)
    u_a(t) = v(t - delay)              delay line of ``delay/dt`` steps
    x' = plant.ode(x, u_a, d_k, p)     the true plant (its own parameters), integrated with xc' = law.derivative;
                                       behind an actuator (implementation.actuator) the plant is the actuated one
                                       (:mod:`designkit.simulation.implementation`)

State and per-step input layouts (computed from the plant, the law and the element, never fixed)::

    z = (x[nx], xc[nc], m[nm], e[ne], u_hold[nu], xc_dot_hold[nc], delay line[nu * delay_steps])
    w = (r(t)[3n], r(t + dt/2)[3n], r(t + dt)[3n], noise[nx], d[nd], sample flag, v[nu], p[np])

``record`` is ``(x, xc, u_command, u_applied, y, d, signals)`` at the step's start, ``signals`` the
law's recorded signals (:attr:`designkit.synthesis.law.Law.signals`).

The chain is evaluated inside the integrator (fourth-order accurate with RK4) when the controller
is continuous and smooth, there is no delay and the element is continuous and memoryless.  A
sampled controller (``sampling_period > 0``: ``simulation.sampling_period``, or the period the law
declares, :attr:`designkit.synthesis.law.Law.sampling_period`) computes its command and the
derivative of its state at ``t = j Ts`` and holds both; a **discontinuous** law is held the same
way at every step (its sample is the step); a relay, quantizer or delay line is evaluated once per step and held.

A law whose functions cannot be expanded into SX (calls of compiled C loaded with :func:`casadi.external`, the
``generated_code`` check's law) is composed in MX instead: the same operations, the law's functions called.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.simulation.integrate import rk4, variable_step
from designkit.simulation.regime import regime_of
from designkit.synthesis.law import Law

__all__ = ["Layout", "step_function"]


@dataclass(frozen=True)
class Layout:
    """Sizes of the augmented state ``z`` and of the per-step inputs ``w`` (module docstring)."""

    nx: int
    nc: int
    nm: int
    ne: int
    nu: int
    nd: int
    n: int
    delay_steps: int
    np_: int = 0
    ns: int = 0

    @property
    def z_sizes(self) -> list[int]:
        return [self.nx, self.nc, self.nm, self.ne, self.nu, self.nc, self.nu * self.delay_steps]

    @property
    def w_sizes(self) -> list[int]:
        return [3 * self.n, 3 * self.n, 3 * self.n, self.nx, self.nd, 1, self.nu, self.np_]

    @property
    def record_sizes(self) -> list[int]:
        return [self.nx, self.nc, self.nu, self.nu, self.nx, self.nd, self.ns]


def layout(plant: Any, law: Law, element: Any, delay_steps: int) -> Layout:
    """The :class:`Layout` of ``plant`` under ``law`` with ``element``."""
    return Layout(len(plant.states), law.n_state, law.n_memory, element.n_memory, len(plant.inputs),
                  len(plant.disturbances), len(plant.positions), delay_steps, len(plant.parameters), law.n_signals)


def _split(v: Any, sizes: list[int]) -> list[Any]:
    return ca.vertsplit(v, np.cumsum([0, *sizes]).tolist())


def _feedforward(law: Law, y: Any, xc: Any, m: Any, r: Any, v: Any) -> Any:
    """The trial's feedforward ``v`` as it enters the command (``law.feedforward``, or ``v`` itself)."""
    return v if law.feedforward is None else law.feedforward(y, xc, m, r, v)


def step_function(plant: Any, law: Law, element: Any, timing: Any, numerics: Any, *,
                  measure: ca.Function | None = None) -> ca.Function:
    """One integration step ``sim_step: (z, w) -> (z_next, record)`` (module docstring).

    Parameters
    ----------
    plant : Plant
        The simulated (true) plant; its parameters are an input of the step.
    law : Law
    element : Element
        The nonlinear element at the plant input (:mod:`designkit.simulation.nonlinear`).
    timing : Timing
        Step, sampling and delay (:mod:`designkit.simulation.timing`).
    numerics : Numerics
        ``rtol`` and ``atol`` of CVODES.
    measure : casadi.Function, optional
        ``y -> y_measured``: the quantised measurement the law reads (``implementation.quantization``,
        :func:`designkit.simulation.implementation.measure_function`), evaluated once per step; the law is then
        held over the step.
    """
    L = layout(plant, law, element, timing.delay_steps)
    regime = regime_of(law, element, sampled=timing.steps_per_sample > 0, delayed=L.delay_steps > 0,
                       quantized=measure is not None)
    held_law, per_step = regime.held_law, regime.per_step
    ode = plant.ode()

    # the right-hand side over one step, in fresh symbols: s = (x, xc), a = reference, h = held values; MX when a
    # law function cannot be expanded into SX (a call of compiled C, casadi.external)
    expands = all(getattr(law, role).is_a("SXFunction") for role in ("command", "derivative", "gate", "project",
                                                                      "update"))
    rsym = ca.SX.sym if expands else ca.MX.sym
    s, a = rsym("s", L.nx + L.nc), rsym("a", 3 * L.n)
    h_sizes = [L.nx, L.nd, L.nu, L.nm, L.ne, L.nc, L.nu, L.nc, L.np_]
    h = rsym("h", sum(h_sizes))
    noise, dist, uff, m, e, gate, u_held, d_held, p_true = _split(h, h_sizes)
    x, xc = s[:L.nx], s[L.nx:]
    if per_step:
        u_in = u_held
    else:
        y_in = x + noise
        u_in = element.function(law.command(y_in, xc, m, a) + _feedforward(law, y_in, xc, m, a, uff), e)[0]
    xc_dot = d_held if held_law else law.derivative(x + noise, xc, m, a, gate)
    rhs = ca.Function("loop_rhs", [s, a, h], [ca.vertcat(ode(x, u_in, dist, p_true), xc_dot)], ["s", "a", "h"],
                      ["s_dot"])

    sym = ca.MX.sym if timing.integrator == "cvodes" or not expands else ca.SX.sym
    z, w = sym("z", sum(L.z_sizes)), sym("w", sum(L.w_sizes))
    x, xc, m, e, u_hold, d_hold, line = _split(z, L.z_sizes)
    r0, rm, r1, noise, dist, flag, uff, p = _split(w, L.w_sizes)
    y = x + noise if measure is None else measure(x + noise)
    m_next = ca.if_else(flag, law.update(y, xc, m, r0), m) if L.nm else m
    m_cmd = m_next if law.command_after_update else m  # the memory the command and the signals read
    gate = law.gate(y, xc, m_cmd, r0)
    command = law.command(y, xc, m_cmd, r0) + _feedforward(law, y, xc, m_cmd, r0, uff)
    if held_law:
        u_hold = ca.if_else(flag, command, u_hold)
        d_hold = ca.if_else(flag, law.derivative(y, xc, m_cmd, r0, gate), d_hold)
        u_cmd = u_hold
    else:
        u_cmd = command
    if per_step:
        v, e_next = element.function(u_cmd, e)
        u_app = line[L.nu * (L.delay_steps - 1):] if L.delay_steps > 0 else v
        kept = L.nu * (L.delay_steps - 1)  # a one-step line keeps nothing (CasADi slices a scalar [:0] to 1x0)
        line_next = (ca.vertcat(v, line[:kept]) if kept > 0 else v) if L.delay_steps > 0 else line
    else:
        u_app, e_next, line_next = element.function(u_cmd, e)[0], e, line
    held = ca.vertcat(noise, dist, uff, m_cmd, e, gate, u_app, d_hold, p)
    s0 = ca.vertcat(x, xc)
    if timing.integrator == "cvodes":
        s_next = variable_step(rhs, s0, timing.dt, (r0, rm, r1), held, rtol=numerics.rtol, atol=numerics.atol)
    else:
        s_next = rk4(lambda state, ref: rhs(state, ref, held), s0, timing.dt, (r0, rm, r1))
    z_next = ca.vertcat(s_next[:L.nx], law.project(s_next[L.nx:]), m_next, e_next, u_hold, d_hold, line_next)
    signals = law.signals(y, xc, m_cmd, r0) if law.signals is not None else ca.DM(0, 1)
    record = ca.vertcat(x, xc, u_cmd, u_app, y, dist, signals)
    return ca.Function("sim_step", [z, w], [z_next, record], ["z", "w"], ["z_next", "record"])
