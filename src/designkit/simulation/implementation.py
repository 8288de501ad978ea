"""The controller as implemented (``spec.implementation``): the loop the verdict is on when the section is given.

Signal chain of the implemented loop (:mod:`designkit.simulation.step` evaluates it)::

    y   = step * floor((x + n) / step + 1/2)   measurement quantised per state (implementation.quantization),
                                               read once per integration step, the law held over the step
    u_c = law(y, ...)                          sampled every implementation.sampling_period, held in between
    v   = element(u_c)                         simulation.nonlinearity, when given (before the actuator)
    u_d(t) = v(t - delay)                      implementation.delay: the computation delay (a delay line)
    u_a' = bandwidth (clip(u_d, -limit, limit) - u_a)
                                               implementation.actuator: saturation, then a first-order lag,
                                               one continuous state per input integrated with the plant
    x'  = f(x, u_a, d, p)                      the true plant

The sampling period and the delay reuse the simulator's sampling and delay line: ``implementation.sampling_period``
and ``simulation.sampling_period`` both given and different are refused (naming the implementation's key), and so
is a period that differs from the one a law declares (:func:`designkit.simulation.timing.sampling_of`);
``implementation.delay`` and ``simulation.delay`` likewise (:func:`designkit.simulation.timing.delay_of`).

The actuator is a wrapper of the true plant (:func:`actuated`): its state is the plant's followed by the lag's
``u_a`` (one per input), its input the command reaching the actuator.  Without a ``bandwidth`` the actuator is the
saturation alone (no state); without a ``limit`` the lag alone.  A saturation is continuous, and the lag is a
smooth state: a smooth loop stays smooth and the Dormand--Prince pair still integrates it.  The law reads the
plant's states only (:func:`measuring_law`); the recorded ``state`` is the plant's, ``u_applied`` the actuator's
output (the plant's input) and ``u_command`` the law's command.  The lag starts where the loop is at rest: at the
clipped command of the rest state before the motion (zero when the loop rests without effort).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.models.plant import Signal

__all__ = ["Implemented", "actuated", "implemented_of", "lag_rates", "lag_step_error", "measure_function",
           "measuring_law", "switching_scope", "words"]


@dataclass(frozen=True)
class Implemented:
    """The implementation section resolved against a plant (the per-state and per-input values broadcast).

    Parameters
    ----------
    quantization : tuple of float
        Resolution of each measured state (its unit), empty: exact measurements.
    limit : tuple of float
        The actuator's saturation per input (the input's unit), empty: none.
    bandwidth : tuple of float
        The actuator's lag per input (rad/s), empty: none.
    nx : int
        Number of plant states.
    """

    quantization: tuple[float, ...] = ()
    limit: tuple[float, ...] = ()
    bandwidth: tuple[float, ...] = ()
    nx: int = 0

    @property
    def n_lag(self) -> int:
        """Number of actuator states (one per input with a lag)."""
        return len(self.bandwidth)

    @property
    def changes_plant(self) -> bool:
        """True when the actuator (saturation or lag) stands between the command and the plant."""
        return bool(self.limit or self.bandwidth)

    def applied(self, u_in: np.ndarray, lag_states: np.ndarray) -> np.ndarray:
        """The plant's input (the actuator's output) from the input reaching the actuator ``(N, nu)`` and the lag's
        recorded states ``(N, n_lag)``."""
        if self.bandwidth:
            return lag_states
        if self.limit:
            lim = np.asarray(self.limit, dtype=float)
            return np.clip(u_in, -lim, lim)
        return u_in


def _broadcast(value: Any, n: int, key: str, what: str) -> tuple[float, ...]:
    """``value`` (one number or a list) as ``n`` numbers; :class:`SpecError` on ``key`` for a list of another
    length."""
    if value is None:
        return ()
    if isinstance(value, list | tuple):
        if len(value) != n:
            raise SpecError(key, f"needs one value for every {what} or one per {what} ({n}), got {len(value)}")
        return tuple(float(v) for v in value)
    return (float(value),) * n


def implemented_of(spec: Any, plant: Any) -> Implemented | None:
    """The :class:`Implemented` of ``spec.implementation`` on ``plant`` (None without the section).

    Raises
    ------
    SpecError
        ``implementation.quantization`` with a list of another length than the plant's states,
        ``implementation.actuator.limit`` or ``.bandwidth`` with a list of another length than its inputs.
    """
    section = getattr(spec, "implementation", None)
    if section is None:
        return None
    nx, nu = len(plant.states), len(plant.inputs)
    actuator = section.actuator
    return Implemented(
        quantization=_broadcast(section.quantization, nx, "implementation.quantization", "measured state"),
        limit=_broadcast(getattr(actuator, "limit", None), nu, "implementation.actuator.limit", "input"),
        bandwidth=_broadcast(getattr(actuator, "bandwidth", None), nu, "implementation.actuator.bandwidth", "input"),
        nx=nx)


class _ActuatedPlant:
    """The true plant behind the actuator (module docstring): what the step function integrates.

    It carries the plant's signals and parameters and ``ode() -> (x_a, u, d, p) -> x_a'`` over ``x_a = (x, u_a)``;
    everything else a simulation reads from a plant (names, limits, linearization) is read from the plant itself.
    """

    def __init__(self, plant: Any, impl: Implemented) -> None:
        self.plant, self.impl = plant, impl
        self.kind = plant.kind
        lags = tuple(Signal(f"{s.name}_actuator", s.unit, f"actuator output of {s.name}") for s in plant.inputs)
        self.states = tuple(plant.states) + (lags if impl.bandwidth else ())
        self.inputs, self.disturbances = tuple(plant.inputs), tuple(plant.disturbances)
        self.parameters = tuple(plant.parameters)
        self.positions, self.velocities = tuple(plant.positions), tuple(plant.velocities)

    def nonsmooth(self) -> tuple[str, ...]:
        """The plant's terms that are not differentiable at rest (the saturation is continuous: not one of them)."""
        return tuple(self.plant.nonsmooth()) if hasattr(self.plant, "nonsmooth") else ()

    def ode(self) -> ca.Function:
        """``actuated_ode: (x_a, u, d, p) -> x_a'``: the plant driven by the actuator's output, and the lag's
        ``u_a' = bandwidth (clip(u) - u_a)`` (rad/s times the input's unit)."""
        inner = self.plant.ode()
        nx, nu = len(self.plant.states), len(self.inputs)
        xa = ca.SX.sym("x", len(self.states))
        u = ca.SX.sym("u", nu)
        d = ca.SX.sym("d", inner.size1_in(2))
        p = ca.SX.sym("p", inner.size1_in(3))
        clipped = u
        if self.impl.limit:
            lim = ca.DM(list(self.impl.limit))
            clipped = ca.fmin(ca.fmax(u, -lim), lim)
        if self.impl.bandwidth:
            ua = xa[nx:]
            bw = ca.DM(list(self.impl.bandwidth))
            xdot = ca.vertcat(inner(xa[:nx], ua, d, p), bw * (clipped - ua))
        else:
            xdot = inner(xa[:nx], clipped, d, p)
        return ca.Function("actuated_ode", [xa, u, d, p], [xdot], ["x", "u", "d", "p"], ["xdot"])


def actuated(plant: Any, impl: Implemented | None) -> Any:
    """``plant`` behind the actuator of ``impl`` (:class:`_ActuatedPlant`), or ``plant`` itself when there is
    none."""
    return plant if impl is None or not impl.changes_plant else _ActuatedPlant(plant, impl)


_Y_FIRST = ("command", "derivative", "gate", "update", "signals", "feedforward")


def _reading(f: ca.Function, nx: int, extra: int) -> ca.Function:
    """``f`` with its first argument ``y`` extended by ``extra`` entries it does not read."""
    args = [ca.SX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
    y = ca.SX.sym("y", nx + extra)
    out = f(y[:nx], *args[1:])
    outs = list(out) if isinstance(out, list | tuple) else [out]
    return ca.Function(f.name(), [y, *args[1:]], outs, [f.name_in(k) for k in range(f.n_in())],
                       [f.name_out(k) for k in range(f.n_out())])


def measuring_law(law: Any, nx: int, extra: int) -> Any:
    """``law`` reading the first ``nx`` entries of a measurement extended by ``extra`` (the actuator's states)."""
    if extra == 0:
        return law
    changed = {name: _reading(getattr(law, name), nx, extra) for name in _Y_FIRST if getattr(law, name) is not None}
    return dataclasses.replace(law, **changed)


def measure_function(impl: Implemented | None, n_measured: int) -> ca.Function | None:
    """``measure: y -> y_q``, the quantised measurement ``step * floor(y / step + 1/2)`` on each plant state (ties
    upward, like the quantizer element; the actuator's states, beyond ``impl.nx``, pass unchanged), or None without
    quantization."""
    if impl is None or not impl.quantization:
        return None
    y = ca.SX.sym("y", n_measured)
    out = []
    for k in range(n_measured):
        step = impl.quantization[k] if k < impl.nx else 0.0
        out.append(step * ca.floor(y[k] / step + 0.5) if step > 0 else y[k])
    return ca.Function("measure", [y], [ca.vertcat(*out)], ["y"], ["y_measured"])


def _rate(period: float) -> str:
    """``1 kHz`` for 1e-3 s."""
    f = 1.0 / period
    for scale, prefix in ((1e6, "M"), (1e3, "k"), (1.0, "")):
        if f >= scale:
            return f"{f / scale:.4g} {prefix}Hz"
    return f"{f:.4g} Hz"


def _time(t: float) -> str:
    """``0.2 ms`` for 2e-4 s."""
    for scale, name in ((1.0, "s"), (1e-3, "ms"), (1e-6, "µs")):
        if t >= 0.1 * scale:
            return f"{t / scale:.4g} {name}"
    return f"{t * 1e9:.4g} ns"


def _values(values: tuple[float, ...], units: list[str], names: list[str]) -> str:
    """One value with its unit when all agree, else each with its signal's name."""
    if len(set(values)) == 1 and len(set(units)) == 1:
        return f"{values[0]:.4g} {units[0]}".rstrip()
    return ", ".join(f"{n}: {v:.4g} {u}".rstrip() for n, v, u in zip(names, values, units, strict=True))


def words(impl: Implemented | None, plant: Any, sampling: float, delay: float) -> str:
    """What the verdict is on, in words: ``"as implemented: sampled at 1 kHz (command held between samples),
    0.2 ms computation delay, ..."``."""
    parts = []
    if sampling > 0:
        parts.append(f"sampled at {_rate(sampling)} (every {_time(sampling)}, the command held between samples)")
    else:
        parts.append("not sampled (the law computed continuously)")
    if delay > 0:
        parts.append(f"{_time(delay)} computation delay")
    if impl is not None and impl.quantization:
        parts.append("measurements quantised to " + _values(
            impl.quantization, [s.unit for s in plant.states], [s.name for s in plant.states]))
    if impl is not None and impl.changes_plant:
        units, names = [s.unit for s in plant.inputs], [s.name for s in plant.inputs]
        lim = f"limited to ±{_values(impl.limit, units, names)}" if impl.limit else "not limited"
        lag = (f"a {_values(impl.bandwidth, ['rad/s'] * len(names), names)} first-order lag "
               f"(time constant {_time(1.0 / max(impl.bandwidth))}"
               + ("" if len(set(impl.bandwidth)) == 1 else " for the fastest") + ")") if impl.bandwidth else "no lag"
        parts.append(f"actuator {lim} with {lag}")
    return "as implemented: " + ", ".join(parts)


def switching_scope(law: Any, dt: float, sampling: float) -> str:
    """For a switching law run without an implementation section: what its verdict holds for, in words."""
    if sampling > 0:
        return (f"the switching law was simulated sampled at {_rate(sampling)}; no implementation section: the "
                "verdict holds for that sampling, without computation delay, quantisation or actuator")
    return (f"the verdict holds for a continuous-time switch: the switching law was simulated with its command "
            f"updated at every integration step, at {_rate(dt)} (1/dt, dt = {_time(dt)}); a controller that samples "
            "it more slowly, with a delay or through an actuator is another loop (give the implementation section to "
            "judge it)")


def lag_step_error(exc: SpecError, impl: Implemented | None, fast: float) -> SpecError:
    """The resource-bound refusal ``exc`` named after ``implementation.actuator.bandwidth`` when the actuator's lag,
    faster than every other rate of the loop (``fast``, 1/s), set the step; ``exc`` itself otherwise."""
    if impl is None or not impl.bandwidth or exc.path != "simulation.duration" or max(impl.bandwidth) <= fast:
        return exc
    return SpecError("implementation.actuator.bandwidth", f"{max(impl.bandwidth):g} rad/s sets the integration step "
                     f"(the loop's other rates reach {fast:.4g} 1/s): {exc.message}; lower the bandwidth or leave it "
                     "out when the actuator is much faster than the loop")


def lag_rates(impl: Implemented | None) -> list[float]:
    """The actuator lag's poles ``-bandwidth`` (1/s): time scales the default step must resolve."""
    return [-float(b) for b in impl.bandwidth] if impl is not None and impl.bandwidth else []
