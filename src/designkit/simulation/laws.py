"""Control laws as CasADi Functions, one builder per controller kind (a registry, no if/elif).

A law sees the measurement ``y = (y1, y2)`` (position rad, speed rad/s: state plus noise), its
own state ``xc`` and the reference ``r = (xD, xD', xD'')``, and provides four named Functions:

* ``command(y, xc, r) -> u``: the commanded control (N*m);
* ``derivative(y, xc, r, gate) -> xc'``: the controller state's ODE; ``gate`` (0 or 1) is the
  anti-windup switch, multiplying the integrand of integral states;
* ``gate(y, xc, r) -> gate``: evaluated once per integration step, at the step's start;
* ``project(xc) -> xc``: applied after every step (clamps integral states).

PID laws (``designkit.synthesis.pid``), with ``e = y1 - xD`` and ``x3`` the integral of ``e``:

* ``pid_servo``:    ``u = -K1 e - K2 y2 - K3 x3 + K3 K4 xD``,  ``x3' = gate * e``;
* ``pid_tracking``: ``u = (tau0/Km0) xD'' + y2/Km0 - K1 e - K2 (y2 - xD') - K3 x3``,
  ``x3' = gate * e``, with ``tau0``, ``Km0`` the nominal plant of the design.

Anti-windup (spec ``simulation.anti_windup``) on the integral ``x3``:

* ``threshold``:  ``gate = 1`` while ``|e| <= value`` (rad), else 0 (integration frozen);
* ``saturation``: ``x3`` clamped to ``|K3 x3| <= value`` (N*m) after every step.

A new controller kind with internal state = one builder ``(design, anti_windup) -> Law`` added to
:data:`LAWS`; see ``docs/simulation.md``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.errors import SpecError
from designkit.synthesis.design import Design


@dataclass(frozen=True)
class Law:
    """A controller as CasADi Functions (see the module docstring for their signatures).

    Parameters
    ----------
    kind : str
        Controller kind (``design.kind``).
    state_names : tuple of str
        Names of the controller state components (``("x3",)`` for the PIDs).
    command, derivative, gate, project : casadi.Function
        The law's output, state ODE, anti-windup switch and state projection.
    settings : dict
        Gains and anti-windup options, JSON-serialisable.
    """

    kind: str
    state_names: tuple[str, ...]
    command: ca.Function
    derivative: ca.Function
    gate: ca.Function
    project: ca.Function
    settings: dict[str, Any]

    @property
    def n_state(self) -> int:
        """Number of controller states."""
        return len(self.state_names)


# ----------------------------------------------------------------------------- anti-windup

# kind -> (value, integral gain) -> (gate(e) expression builder, projection(x_int) builder)
AntiWindupBuilder = Callable[[float, float], tuple[Callable[[ca.SX], ca.SX], Callable[[ca.SX], ca.SX]]]


def _no_anti_windup(value: float, gain: float):
    return (lambda e: ca.SX(1.0)), (lambda xi: xi)


def _threshold(value: float, gain: float):
    return (lambda e: ca.if_else(ca.fabs(e) <= value, 1.0, 0.0)), (lambda xi: xi)


def _clamp(value: float, gain: float):
    bound = value / abs(gain) if gain != 0 else float("inf")
    return (lambda e: ca.SX(1.0)), (lambda xi: ca.fmin(ca.fmax(xi, -bound), bound))


ANTI_WINDUP: dict[str, AntiWindupBuilder] = {"none": _no_anti_windup, "threshold": _threshold, "saturation": _clamp}


def integral_anti_windup(section: Any | None, gain: float):
    """Anti-windup of one integral state whose control contribution is ``-gain * x_int``.

    Parameters
    ----------
    section : AntiWindup or None
        The spec's ``simulation.anti_windup``.
    gain : float
        Integral gain (N*m per rad*s), for the ``saturation`` bound ``|gain * x_int| <= value``.

    Returns
    -------
    gate_of, project_of : callable
        ``e -> gate`` and ``x_int -> clamped x_int`` on CasADi expressions.
    settings : dict
        ``{"kind": ..., "value": ...}``.
    """
    kind, value = ("none", None) if section is None else (section.kind, float(section.value))
    try:
        builder = ANTI_WINDUP[kind]
    except KeyError:
        raise SpecError("simulation.anti_windup.kind", f"unknown kind {kind!r}; known: {sorted(ANTI_WINDUP)}") from None
    gate, project = builder(0.0 if value is None else value, gain)
    return gate, project, {"kind": kind, "value": value}


# ----------------------------------------------------------------------------- PID laws


def _pid_law(kind: str, design: Design, anti_windup: Any | None,
             output: Callable[[ca.SX, ca.SX, ca.SX, ca.SX], ca.SX]) -> Law:
    """Common frame of the PID laws: one integral state ``x3' = gate * (y1 - xD)``."""
    y, xc, r, g = ca.SX.sym("y", 2), ca.SX.sym("xc", 1), ca.SX.sym("r", 3), ca.SX.sym("gate")
    e = y[0] - r[0]
    gate_of, project_of, aw = integral_anti_windup(anti_windup, float(design.gains["K3"]))
    names_in = ["y", "xc", "r"]
    return Law(
        kind=kind,
        state_names=("x3",),
        command=ca.Function(f"{kind}_command", [y, xc, r], [output(y, xc, r, e)], names_in, ["u"]),
        derivative=ca.Function(f"{kind}_derivative", [y, xc, r, g], [g * e], [*names_in, "gate"], ["xc_dot"]),
        gate=ca.Function(f"{kind}_gate", [y, xc, r], [gate_of(e)], names_in, ["gate"]),
        project=ca.Function(f"{kind}_project", [xc], [project_of(xc)], ["xc"], ["xc_projected"]),
        settings={"gains": {k: float(v) for k, v in design.gains.items()}, "anti_windup": aw},
    )


def servo_law(design: Design, anti_windup: Any | None = None) -> Law:
    """``u = -K1 (y1 - xD) - K2 y2 - K3 x3 + K3 K4 xD``, ``x3' = y1 - xD``."""
    K1, K2, K3, K4 = (float(design.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    return _pid_law(
        "pid_servo", design, anti_windup,
        lambda y, xc, r, e: -K1 * e - K2 * y[1] - K3 * xc[0] + K3 * K4 * r[0],
    )


def tracking_law(design: Design, anti_windup: Any | None = None) -> Law:
    """``u = (tau0/Km0) xD'' + y2/Km0 - K1 (y1 - xD) - K2 (y2 - xD') - K3 x3``, ``x3' = y1 - xD``."""
    K1, K2, K3 = (float(design.gains[k]) for k in ("K1", "K2", "K3"))
    Km0, tau0 = float(design.plant.Km), float(design.plant.tau)
    return _pid_law(
        "pid_tracking", design, anti_windup,
        lambda y, xc, r, e: (tau0 / Km0) * r[2] + y[1] / Km0 - K1 * e - K2 * (y[1] - r[1]) - K3 * xc[0],
    )


LAWS: dict[str, Callable[[Design, Any | None], Law]] = {"pid_servo": servo_law, "pid_tracking": tracking_law}
"""Controller kind -> law builder ``(design, anti_windup section or None) -> Law``."""


def law_for(design: Design, anti_windup: Any | None = None) -> Law:
    """The law of ``design.kind``; :class:`SpecError` naming ``controller.kind`` otherwise."""
    try:
        build = LAWS[design.kind]
    except KeyError:
        raise SpecError(
            "controller.kind", f"no simulation law for {design.kind!r}; known: {sorted(LAWS)}"
        ) from None
    return build(design, anti_windup)
