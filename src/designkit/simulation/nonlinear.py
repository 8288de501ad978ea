"""The nonlinear element between controller and plant (POSSPEED, notes fig. B.1.2).

Every element is a pure map ``(u, m) -> (v, m_next)`` from the commanded controls ``u`` (one per
plant input, N*m) and a memory vector ``m`` to the applied controls ``v`` and the next memory,
acting input by input with its own level per input (a scalar applies to every input).  It is
given twice: as a named CasADi :class:`casadi.Function` (used by the simulator) and as a NumPy
reference (used by the tests).  Memoryless elements have an empty memory (``n_memory = 0``); the
relay remembers one output per input.

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
    n : int
        Number of inputs it acts on.
    function : casadi.Function
        ``(u, m) -> (v, m_next)`` with ``u``, ``v`` of size ``n`` (N*m) and ``m`` of size ``n_memory``.
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
    n: int
    function: ca.Function
    reference: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
    n_memory: int
    initial_memory: tuple[float, ...]
    continuous: bool
    settings: dict[str, Any]


def _function(kind: str, v: ca.SX, u: ca.SX, m: ca.SX, m_next: ca.SX) -> ca.Function:
    return ca.Function(f"nl_{kind}", [u, m], [v, m_next], ["u", "m"], ["v", "m_next"])


def _levels(value: Any, n: int | None) -> tuple[np.ndarray, int]:
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    n = arr.size if n is None else n
    return np.broadcast_to(arr, (n,)).astype(float), n


def _plain(arr: np.ndarray) -> float | list[float]:
    return float(arr[0]) if np.all(arr == arr[0]) else arr.tolist()


def _memoryless(kind: str, n: int, expr: Callable[[ca.SX, int], ca.SX], ref, continuous: bool, settings) -> Element:
    u, m = ca.SX.sym("u", n), ca.SX.sym("m", 0)
    v = ca.vertcat(*[expr(u[j], j) for j in range(n)])
    return Element(
        kind=kind, n=n, function=_function(kind, v, u, m, m), reference=ref, n_memory=0,
        initial_memory=(), continuous=continuous, settings=settings,
    )


def identity(n: int = 1) -> Element:
    """No nonlinear element: ``v = u``."""
    return _memoryless("none", n, lambda u, j: u, lambda u, m: (np.asarray(u, float), m), True, {"kind": "none"})


def saturation(limit: Any, n: int | None = None) -> Element:
    """``v = clip(u, -limit, limit)``; ``limit`` in N*m (one per input or one for all)."""
    lim, n = _levels(limit, n)
    return _memoryless(
        "saturation", n, lambda u, j: ca.fmin(ca.fmax(u, -lim[j]), lim[j]),
        lambda u, m: (np.minimum(np.maximum(np.asarray(u, float), -lim), lim), m),
        True, {"kind": "saturation", "limit": _plain(lim)},
    )


def dead_zone(width: Any, n: int | None = None) -> Element:
    """``v = 0`` for ``|u| <= width``, ``u - sign(u) width`` beyond; ``width`` in N*m."""
    w, n = _levels(width, n)

    def ref(u, m):
        u = np.asarray(u, float)
        return np.where(u > w, u - w, np.where(u < -w, u + w, 0.0)), m

    return _memoryless(
        "dead_zone", n, lambda u, j: ca.if_else(u > w[j], u - w[j], ca.if_else(u < -w[j], u + w[j], 0.0)),
        ref, True, {"kind": "dead_zone", "width": _plain(w)},
    )


def quantizer(step: Any, n: int | None = None) -> Element:
    """``v = step * floor(u/step + 1/2)``: nearest level, ties upward; ``step`` in N*m."""
    q, n = _levels(step, n)
    return _memoryless(
        "quantizer", n, lambda u, j: q[j] * ca.floor(u / q[j] + 0.5),
        lambda u, m: (q * np.floor(np.asarray(u, float) / q + 0.5), m),
        False, {"kind": "quantizer", "step": _plain(q), "rounding": "floor(u/step + 1/2)"},
    )


def relay(amplitude: Any, hysteresis: Any, n: int | None = None) -> Element:
    """Relay with hysteresis, per input; memory = previous outputs (start at 0)."""
    amp, n = _levels(amplitude, n)
    hys, _ = _levels(hysteresis, n)
    u, m = ca.SX.sym("u", n), ca.SX.sym("m", n)
    v = ca.vertcat(*[ca.if_else(u[j] > hys[j], amp[j], ca.if_else(u[j] < -hys[j], -amp[j], m[j])) for j in range(n)])

    def ref(u, m):
        u, m = np.asarray(u, float), np.asarray(m, float)
        out = np.where(u > hys, amp, np.where(u < -hys, -amp, m))
        return out, out

    return Element(
        kind="relay", n=n, function=_function("relay", v, u, m, v), reference=ref, n_memory=n,
        initial_memory=(0.0,) * n, continuous=False,
        settings={"kind": "relay", "amplitude": _plain(amp), "hysteresis": _plain(hys), "initial_output": 0.0},
    )


ELEMENTS: dict[str, Callable[[Any, int], Element]] = {
    "saturation": lambda s, n: saturation(s.limit, n),
    "dead_zone": lambda s, n: dead_zone(s.width, n),
    "quantizer": lambda s, n: quantizer(s.step, n),
    "relay": lambda s, n: relay(s.amplitude, s.hysteresis, n),
}
"""Spec section kind -> element builder (takes the validated spec section and the number of inputs)."""

_LEVEL_KEYS = {"saturation": ("limit",), "dead_zone": ("width",), "quantizer": ("step",),
               "relay": ("amplitude", "hysteresis")}


def element_for(section: Any | None, n: int = 1) -> Element:
    """The element a ``simulation.nonlinearity`` section describes for ``n`` inputs (``None``: identity).

    Raises
    ------
    SpecError
        Unknown kind, or a per-input list whose length is not ``n``.
    """
    if section is None:
        return identity(n)
    try:
        build = ELEMENTS[section.kind]
    except KeyError:
        raise SpecError(
            "simulation.nonlinearity.kind", f"unknown element {section.kind!r}; known: {sorted(ELEMENTS)}"
        ) from None
    for key in _LEVEL_KEYS[section.kind]:
        value = getattr(section, key)
        if isinstance(value, list) and len(value) != n:
            raise SpecError(f"simulation.nonlinearity.{key}",
                            f"needs one value per input ({n}), got {len(value)}")
    return build(section, n)
