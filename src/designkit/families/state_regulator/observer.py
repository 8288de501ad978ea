"""The state regulator's Luenberger observer, for a linear plant that measures only its outputs ``y = C x``.

``x̂' = A x̂ + B u + L (y − C x̂)``, ``u = −K x̂ + N xD``: ``L`` places ``eig(A − L C)`` by duality
(:func:`~designkit.synthesis.pole_placement.observer_gain`).  With the estimation error ``e = x − x̂``,
``e' = (A − L C) e`` on the nominal plant, so the closed loop ``[x; e]`` is block triangular and its poles are those
of ``A − B K`` and of ``A − L C`` (the separation principle); the observer's modes do not reach ``y/xD`` (``e`` is
not excited by ``xD``), so they are also zeros of it, cancelling.  ``A``, ``B`` are the nominal plant's: on another
plant of the box the estimate is biased and the generic checks judge the loop as it is.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.synthesis.law import LawSymbols, State
from designkit.synthesis.linear_servo import plant_zeros
from designkit.synthesis.pole_placement import observer_gain
from designkit.synthesis.state_space import CONTROLLABILITY_TOL, controllability_ratio

__all__ = ["Observer", "design_observer", "observer_states"]


@dataclass(frozen=True)
class Observer:
    """The observer's model and gain (nested tuples, row by row).

    Attributes
    ----------
    A, B, C : tuple of tuples
        The nominal ``A`` (1/s), ``B`` and the measured outputs' ``C``.
    L : tuple of tuples
        ``n x q`` (state units per output unit per second).
    poles : tuple of complex
        ``eig(A − L C)`` requested (1/s).
    outputs : tuple of str
        The measured outputs' names.
    """

    A: tuple[tuple[float, ...], ...]
    B: tuple[tuple[float, ...], ...]
    C: tuple[tuple[float, ...], ...]
    L: tuple[tuple[float, ...], ...]
    poles: tuple[complex, ...]
    outputs: tuple[str, ...]


def _rows(M: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in np.atleast_2d(M))


def design_observer(plant: object, A: np.ndarray, B: np.ndarray, poles: Sequence[complex]) -> Observer:
    """``L`` placing ``poles`` for the outputs of the linear ``plant`` (``SpecError`` at ``plant.C`` when ``(A, C)``
    is not observable, at ``controller.observer_poles`` when the poles cannot be placed)."""
    _, _, C, _ = plant.matrices()  # type: ignore[attr-defined]
    ratio = controllability_ratio(A.T, C.T)
    if ratio < CONTROLLABILITY_TOL:
        raise SpecError("plant.C", f"(A, C) is not observable (ratio {ratio:.3g}): no observer estimates the state "
                        "from these outputs")
    try:
        L = observer_gain(A, C, poles)
    except ValueError as exc:
        raise SpecError("controller.observer_poles", str(exc)) from None
    return Observer(A=_rows(A), B=_rows(B), C=_rows(C), L=_rows(L), poles=tuple(complex(p) for p in poles),
                    outputs=tuple(s.name for s in plant.outputs))  # type: ignore[attr-defined]


def closed_loop_zeros(obs: Observer, K: np.ndarray, N: np.ndarray, position: int) -> tuple[complex, ...]:
    """The zeros of ``y/xD`` of the loop ``[x; x̂]`` (the observer's poles among them, cancelling)."""
    A, B, C, L = (np.asarray(M, float) for M in (obs.A, obs.B, obs.C, obs.L))
    n = A.shape[0]
    Acl = np.block([[A, -B @ K], [L @ C, A - B @ K - L @ C]])
    b = np.concatenate([B @ N, B @ N])
    c = np.concatenate([np.eye(n)[position], np.zeros(n)])
    return plant_zeros(Acl, b, c)


def observer_states(obs: Observer, K: np.ndarray, N: np.ndarray, names: Sequence[str]) -> tuple[list[State], object]:
    """The law's states ``x̂`` (started at the loop's rest) and its command ``s -> −K x̂ + N xD``."""
    A, B, C, L = (ca.DM(np.asarray(M, float)) for M in (obs.A, obs.B, obs.C, obs.L))
    Kd, Nd = ca.DM(np.asarray(K, float)), ca.DM(np.asarray(N, float).reshape(-1, 1))
    hat = [f"{nm}_hat" for nm in names]

    def estimate(s: LawSymbols) -> ca.SX:
        return ca.vertcat(*[s.state(h) for h in hat])

    def command(s: LawSymbols) -> ca.SX:
        return -ca.mtimes(Kd, estimate(s)) + Nd * s.qD[0]

    def rate(s: LawSymbols) -> ca.SX:
        xh = estimate(s)
        return ca.mtimes(A, xh) + ca.mtimes(B, command(s)) + ca.mtimes(L, ca.mtimes(C, s.y) - ca.mtimes(C, xh))

    states = [State(h, (lambda s, i=i: rate(s)[i]), None) for i, h in enumerate(hat)]
    return states, command
