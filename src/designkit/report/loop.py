"""The loop transfer at the plant input, its margins, and the zeros of the closed loop.

The loop transfer (:func:`loop_matrices`, :func:`loop_frequency_response`,
:func:`loop_margins`) is the open loop broken at the plant input, where
the input-equivalent perturbation ``xi`` enters (``u + xi``).  With the closed loop
``x' = A x + B r``, ``u = K x + D_u r`` and ``b`` the ``xi`` column of ``B`` (which is the plant
input matrix), the loop before closing is ``A - b K`` and

    L(s) = -K (sI - A + b K)^-1 b,     1 + L(s) = det(sI - A) / det(sI - A + b K).

For the PID servo on the link this is ``L(s) = Km (K2 s^2 + K1 s + K3) / (s^2 (tau s + 1))``,
i.e. ``C(s) P(s)`` with ``C(s) = K1 + K2 s + K3/s`` acting on ``x1`` and
``P(s) = Km / (s (tau s + 1))``; for the tracker the ``x2/Km`` term replaces ``K2`` by
``K2 - 1/Km``.

SciPy and python-control are imported lazily, inside the functions that need them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LoopMargins:
    """Classical margins of the loop broken at the plant input.

    Parameters
    ----------
    gain_margin : float
        Gain margin (ratio; ``inf`` when the phase never crosses -180 deg at a finite frequency;
        below 1 for a conditionally stable loop, where the gain may only be *reduced* by that factor).
    phase_margin : float
        Phase margin (deg), ``inf`` when ``|L|`` never crosses 1.
    w_phase_crossover, w_gain_crossover : float
        Frequencies (rad/s) of the phase and gain crossovers (``nan`` when absent).
    modulus_margin : float
        ``inf |1 + L(jw)|`` over the plotted frequency grid and ``w -> inf`` (dimensionless; at
        most 1 because ``L`` is strictly proper).
    """

    gain_margin: float
    phase_margin: float
    w_phase_crossover: float
    w_gain_crossover: float
    modulus_margin: float


def input_index(system, name: str) -> int | None:
    """Index of the input ``name`` of ``system`` (a closed loop with named inputs), or ``None``."""
    return system.inputs.index(name) if name in system.inputs else None


def siso_zeros(A: np.ndarray, b: np.ndarray, c: np.ndarray, d: float) -> np.ndarray:
    """Finite transmission zeros of a SISO state-space system (generalised eigenvalues of the
    Rosenbrock pencil)."""
    from scipy.linalg import eigvals

    n = A.shape[0]
    M = np.block([[A, b.reshape(n, 1)], [c.reshape(1, n), np.array([[d]])]])
    N = np.zeros((n + 1, n + 1))
    N[:n, :n] = np.eye(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = eigvals(M, N)
    return np.sort_complex(z[np.isfinite(z)])


def achieved_zeros(design) -> np.ndarray:
    """Zeros of the ``xD -> x1`` channel of the closed loop (empty when the design has none)."""
    cl = design.closed_loop
    i_in = input_index(cl, "xD")
    if not design.zeros or i_in is None or "x1" not in cl.outputs:
        return np.array([], dtype=complex)
    i_out = cl.outputs.index("x1")
    return siso_zeros(cl.A, cl.B[:, i_in], cl.C[i_out], float(cl.D[i_out, i_in]))


def loop_matrices(design) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(A_open, b, -K)`` of the loop broken at the plant input (see the module docstring),
    or ``None`` when the closed loop has no ``xi`` input or no ``u`` output."""
    cl = design.closed_loop
    i_xi = input_index(cl, "xi")
    if i_xi is None or "u" not in cl.outputs:
        return None
    b = cl.B[:, [i_xi]]
    K = cl.C[[cl.outputs.index("u")], :]
    return cl.A - b @ K, b, -K


def loop_frequency_response(design, w: np.ndarray) -> np.ndarray | None:
    """``L(jw)`` at the frequencies ``w`` (rad/s)."""
    mats = loop_matrices(design)
    if mats is None:
        return None
    A, b, c = mats
    eye = np.eye(A.shape[0])
    return np.array([(c @ np.linalg.solve(1j * wk * eye - A, b))[0, 0] for wk in w])


def frequency_grid(design) -> np.ndarray:
    """600 log-spaced frequencies (rad/s), one decade beyond the slowest and fastest pole magnitudes."""
    mags = [abs(p) for p in np.linalg.eigvals(design.closed_loop.A) if abs(p) > 1e-9]
    mags += [abs(p) for p in design.poles if abs(p) > 1e-9]
    lo, hi = (min(mags), max(mags)) if mags else (1.0, 1.0)
    return np.logspace(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 1, 600)


def loop_margins(design) -> LoopMargins | None:
    """Gain and phase margins of the loop broken at the plant input (python-control
    ``stability_margins``) and the modulus margin ``inf |1 + L(jw)|``."""
    import control

    mats = loop_matrices(design)
    if mats is None:
        return None
    A, b, c = mats
    gm, pm, _sm, wpc, wgc, _wms = control.stability_margins(control.ss(A, b, c, 0.0))
    resp = loop_frequency_response(design, frequency_grid(design))
    return LoopMargins(
        gain_margin=float(gm), phase_margin=float(pm), w_phase_crossover=float(wpc),
        # L is strictly proper, so |1 + L(jw)| -> 1 as w -> inf: the infimum is at most 1
        w_gain_crossover=float(wgc), modulus_margin=min(float(np.min(np.abs(1.0 + resp))), 1.0),
    )
