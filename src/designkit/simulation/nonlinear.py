"""The nonlinear element between controller and plant (POSSPEED, notes fig. B.1.2).

Every element is a pure map ``(u, m) -> (v, m_next)`` from the commanded control ``u`` (N*m)
and a memory vector ``m`` to the applied control ``v`` and the next memory, given twice: as a
named CasADi :class:`casadi.Function` (used by the simulator) and as a NumPy reference (used by
the tests).  Memoryless elements have an empty memory (``n_memory = 0``).

Definitions (``u`` the input, ``v`` the output):

* ``none``        ``v = u``.
* ``saturation``  ``v = min(max(u, -limit), limit)``.
* ``dead_zone``   ``v = 0`` for ``|u| <= width``, ``v = u - sign(u) width`` beyond.
* ``quantizer``   ``v = step * floor(u / step + 1/2)`` (round to the nearest level, ties upward).
* ``relay``       ``v = +amplitude`` if ``u > hysteresis``, ``-amplitude`` if ``u < -hysteresis``,
  else the previous output ``m``; ``m_next = v``.  The memory starts at 0: the relay gives 0
  until ``|u|`` first exceeds the hysteresis.

``continuous`` tells whether ``v`` is a continuous function of ``u`` without memory: such an
element may be evaluated inside the integrator's stages; the others (relay, quantizer) are
evaluated once per integration step, at the step's start (see :mod:`designkit.simulation.run`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError


@dataclass(frozen=True)
class Element:
    """One nonlinear element.

    Parameters
    ----------
    kind : str
        ``"none"``, ``"saturation"``, ``"dead_zone"``, ``"quantizer"`` or ``"relay"``.
    function : casadi.Function
        ``(u, m) -> (v, m_next)`` with ``u``, ``v`` scalars (N*m) and ``m`` of size ``n_memory``.
    reference : callable
        NumPy implementation with the same signature, for arrays of ``u`` (elementwise; memory
        elements take and return arrays of memories of the same shape).
    n_memory : int
        Size of the memory vector.
    initial_memory : tuple of float
        Memory at ``t = 0``.
    continuous : bool
        True when ``v`` is a continuous memoryless function of ``u``.
    settings : dict
        The element's parameters, JSON-serialisable.
    """

    kind: str
    function: ca.Function
    reference: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
    n_memory: int
    initial_memory: tuple[float, ...]
    continuous: bool
    settings: dict[str, Any]


def _function(kind: str, v: ca.SX, u: ca.SX, m: ca.SX, m_next: ca.SX) -> ca.Function:
    return ca.Function(f"nl_{kind}", [u, m], [v, m_next], ["u", "m"], ["v", "m_next"])


def _memoryless(kind: str, expr: Callable[[ca.SX], ca.SX], ref, continuous: bool, settings) -> Element:
    u, m = ca.SX.sym("u"), ca.SX.sym("m", 0)
    return Element(
        kind=kind, function=_function(kind, expr(u), u, m, m), reference=ref, n_memory=0,
        initial_memory=(), continuous=continuous, settings=settings,
    )


def identity() -> Element:
    """No nonlinear element: ``v = u``."""
    return _memoryless("none", lambda u: u, lambda u, m: (np.asarray(u, float), m), True, {"kind": "none"})


def saturation(limit: float) -> Element:
    """``v = clip(u, -limit, limit)``; ``limit`` in N*m."""
    return _memoryless(
        "saturation", lambda u: ca.fmin(ca.fmax(u, -limit), limit),
        lambda u, m: (np.minimum(np.maximum(np.asarray(u, float), -limit), limit), m),
        True, {"kind": "saturation", "limit": float(limit)},
    )


def dead_zone(width: float) -> Element:
    """``v = 0`` for ``|u| <= width``, ``u - sign(u) width`` beyond; ``width`` in N*m."""

    def ref(u, m):
        u = np.asarray(u, float)
        return np.where(u > width, u - width, np.where(u < -width, u + width, 0.0)), m

    return _memoryless(
        "dead_zone", lambda u: ca.if_else(u > width, u - width, ca.if_else(u < -width, u + width, 0.0)),
        ref, True, {"kind": "dead_zone", "width": float(width)},
    )


def quantizer(step: float) -> Element:
    """``v = step * floor(u/step + 1/2)``: nearest level, ties upward; ``step`` in N*m."""
    return _memoryless(
        "quantizer", lambda u: step * ca.floor(u / step + 0.5),
        lambda u, m: (step * np.floor(np.asarray(u, float) / step + 0.5), m),
        False, {"kind": "quantizer", "step": float(step), "rounding": "floor(u/step + 1/2)"},
    )


def relay(amplitude: float, hysteresis: float) -> Element:
    """Relay with hysteresis; memory = previous output (starts at 0)."""
    u, m = ca.SX.sym("u"), ca.SX.sym("m", 1)
    v = ca.if_else(u > hysteresis, amplitude, ca.if_else(u < -hysteresis, -amplitude, m))

    def ref(u, m):
        u, m = np.asarray(u, float), np.asarray(m, float)
        out = np.where(u > hysteresis, amplitude, np.where(u < -hysteresis, -amplitude, m))
        return out, out

    return Element(
        kind="relay", function=_function("relay", v, u, m, v), reference=ref, n_memory=1,
        initial_memory=(0.0,), continuous=False,
        settings={"kind": "relay", "amplitude": float(amplitude), "hysteresis": float(hysteresis),
                  "initial_output": 0.0},
    )


ELEMENTS: dict[str, Callable[[Any], Element]] = {
    "saturation": lambda s: saturation(s.limit),
    "dead_zone": lambda s: dead_zone(s.width),
    "quantizer": lambda s: quantizer(s.step),
    "relay": lambda s: relay(s.amplitude, s.hysteresis),
}
"""Spec section kind -> element builder (takes the validated spec section)."""


def element_for(section: Any | None) -> Element:
    """The element a ``simulation.nonlinearity`` section describes (``None``: identity)."""
    if section is None:
        return identity()
    try:
        build = ELEMENTS[section.kind]
    except KeyError:
        raise SpecError(
            "simulation.nonlinearity.kind", f"unknown element {section.kind!r}; known: {sorted(ELEMENTS)}"
        ) from None
    return build(section)
