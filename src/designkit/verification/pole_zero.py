"""Check ``"pole_placement"``: does the synthesised closed loop have the requested poles and zeros?

Computed independently of the synthesis formulas, from the closed loop's state space (NumPy and
SciPy; the tests compare every quantity with python-control's ``poles``, ``zeros`` and ``dcgain``):

- poles: eigenvalues of the closed loop's ``A``, matched to ``design.poles`` as multisets (optimal
  assignment); a pole's error is ``|p - p_ref| / R`` with ``R`` the largest requested magnitude.
  Simple poles must agree to ``POLE_REL``; an ``m``-fold cluster of requested poles (e.g. the
  double pole of a critically damped pair) to ``POLE_REL**(1/m)``, the accuracy to which any
  algorithm can compute an ``m``-fold root.  The characteristic polynomial (well conditioned even
  for multiple roots) must agree to ``POLE_REL`` in scaled coefficients ``c_k / R^k``.
The reference kind is the design's (``design.reference``), never guessed from signal names; the
first joint's channels are used (the families that place zeros have one joint).

- servo (``reference == "step"``): zeros of the SISO ``xD -> x1`` subsystem (generalised eigenvalues of
  its Rosenbrock pencil, QZ), after discarding infinite zeros that the QZ algorithm returns as huge
  finite numbers
  (``|z| > ZERO_INFINITE_REL * ||[A B; C D]||``), matched to ``design.zeros``.  A zero cancelling a
  pole (zero placed on the third pole) is a genuine root of the numerator and is matched like any
  other.  DC gain of ``x1/xD`` (``D - C A^-1 B``) must be 1.
- tracker (``reference == "trajectory"``): the reference transfer with ``xD' = s xD`` and
  ``xD'' = s^2 xD`` must be identically 1 (perfect tracking, notes F1) -- evaluated at
  ``s = 0, jR/10, jR, 10jR`` -- so it has no zeros (``design.zeros == ()``); and ``xi -> x1`` must have
  its single finite zero at 0 when the law has integral action (states integrating the position error, the
  linearized law's ``integral_states``: :class:`designkit.synthesis.law.Law`; notes F2 =
  (Km/tau) s / ((s-p1)(s-p2)(s-p3))), besides the zeros the design lists under
  ``design.extra["disturbance_zeros"]`` (a linear plant's own zeros, and the feedforward filter's modes that
  ``xi`` does not reach: :mod:`designkit.synthesis.linear_tracking`).

``margin = 1 - max(error / tolerance)`` over every comparison: positive when all hold.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.verification.check import Check
from designkit.verification.tolerances import (
    DC_GAIN_TOL,
    POLE_CLUSTER_REL,
    POLE_REL,
    ZERO_INFINITE_REL,
    cluster_tolerance,
    scaled_error,
)


def _integral_action(design: Any) -> bool:
    """Whether the law the closed loop linearizes integrates a position error (its ``integral_states``)."""
    law = design.linear_law
    return law is not None and bool(law.integral_states)


def _pairs(z: Sequence[complex]) -> list[list[float]]:
    return [[complex(v).real, complex(v).imag] for v in z]


def cluster_sizes(ref: Sequence[complex], scale: float) -> np.ndarray:
    """For each requested root, the size of its cluster (roots within ``POLE_CLUSTER_REL * scale``, transitively)."""
    ref = np.asarray(ref, dtype=complex)
    n = len(ref)
    label = np.arange(n)
    close = np.abs(ref[:, None] - ref[None, :]) <= POLE_CLUSTER_REL * scale
    for _ in range(n):  # label propagation: n rounds suffice
        label = np.min(np.where(close, label[None, :], n), axis=1)
    return np.array([np.count_nonzero(label == label[i]) for i in range(n)])


EXHAUSTIVE_MATCH_MAX = 8
"""Up to this many roots, :func:`assignment` tries every pairing (at most 8! = 40,320) in NumPy."""


def assignment(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a pairing of minimum total ``cost`` (square matrix), as
    :func:`scipy.optimize.linear_sum_assignment` returns it.

    Up to :data:`EXHAUSTIVE_MATCH_MAX` roots every permutation is tried (vectorised; the exact
    optimum, first in lexicographic order among ties), which spares the synth command the 0.3 s
    import of ``scipy.optimize``; larger sets use SciPy.  The tests compare the two.
    """
    cost = np.asarray(cost, dtype=float)
    n = cost.shape[0]
    rows = np.arange(n)
    if n > EXHAUSTIVE_MATCH_MAX:
        from scipy.optimize import linear_sum_assignment

        return linear_sum_assignment(cost)
    import itertools

    perms = np.array(list(itertools.permutations(range(n))), dtype=np.intp).reshape(-1, n)
    totals = cost[rows[None, :], perms].sum(axis=1)
    return rows, perms[int(np.argmin(totals))]


def match_roots(computed: Sequence[complex], ref: Sequence[complex], scale: float) -> dict[str, Any]:
    """Match two multisets of roots; errors are ``|x - ref| / scale``, tolerances cluster-aware.

    Returns a dict with ``ok`` (bool), ``ratio`` (worst error/tolerance), and per-root rows.
    Multisets of different sizes never match.
    """
    computed = np.asarray(computed, dtype=complex)
    ref = np.asarray(ref, dtype=complex)
    if len(computed) != len(ref):
        return {"ok": False, "ratio": np.inf, "rows": [], "reason": f"{len(computed)} computed vs {len(ref)} requested"}
    if len(ref) == 0:
        return {"ok": True, "ratio": 0.0, "rows": []}
    cost = np.abs(computed[:, None] - ref[None, :]) / scale
    ci, ri = assignment(cost)
    sizes = cluster_sizes(ref, scale)
    rows = []
    for c, r in zip(ci, ri, strict=True):
        tol = cluster_tolerance(int(sizes[r]))
        rows.append({
            "requested": [ref[r].real, ref[r].imag], "computed": [computed[c].real, computed[c].imag],
            "scaled_error": float(cost[c, r]), "tolerance": tol, "cluster": int(sizes[r]),
        })
    ratio = max(r["scaled_error"] / r["tolerance"] for r in rows)
    return {"ok": bool(ratio <= 1.0), "ratio": float(ratio), "rows": rows}


def coefficient_error(computed: Sequence[complex], ref: Sequence[complex], scale: float) -> float:
    """``max_k |c_k - r_k| / scale^k`` between the monic polynomials with roots ``computed`` and ``ref``."""
    c, r = np.poly(np.asarray(computed)), np.poly(np.asarray(ref))
    if len(c) != len(r):
        return float("inf")
    k = np.arange(len(c))
    return float(np.max(np.abs(c - r) / scale**k))


@dataclass(frozen=True)
class Siso:
    """A single-input single-output state-space system ``(A, B, C, D)`` (``B`` one column, ``C`` one row)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray


def finite_zeros(sys: Any) -> tuple[np.ndarray, int]:
    """Finite zeros of a SISO state-space system (anything with ``A``, ``B``, ``C``, ``D``, e.g. :class:`Siso`
    or a ``control.StateSpace``), without spurious infinite ones.

    The zeros are the finite generalised eigenvalues ``s`` of the Rosenbrock pencil
    ``[[A, B], [C, D]] - s [[I, 0], [0, 0]]`` (QZ, :func:`scipy.linalg.eigvals`); QZ returns the
    pencil's infinite eigenvalues as ``inf`` or as huge finite numbers, which are discarded when
    ``|z| > ZERO_INFINITE_REL * ||[A B; C D]||``.

    Returns the finite zeros (1/s) and how many eigenvalues were discarded as infinite.
    """
    from scipy.linalg import eigvals

    A, B, C, D = (np.atleast_2d(np.asarray(getattr(sys, k), dtype=float)) for k in "ABCD")
    n = A.shape[0]
    L = np.block([[A, B], [C, D]])
    M = np.zeros_like(L)
    M[:n, :n] = np.eye(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.asarray(eigvals(L, M), dtype=complex)
    limit = ZERO_INFINITE_REL * max(float(np.linalg.norm(L)), 1.0)
    keep = np.isfinite(z) & (np.abs(z) <= limit)
    return z[keep], int(np.count_nonzero(~keep))


def dc_gain(sys: Any) -> complex:
    """``D - C A^-1 B`` of a SISO state-space system (NaN when ``A`` is singular: a pole at 0)."""
    A, B, C, D = (np.atleast_2d(np.asarray(getattr(sys, k), dtype=float)) for k in "ABCD")
    try:
        return complex((D - C @ np.linalg.solve(A, B))[0, 0])
    except np.linalg.LinAlgError:
        return complex(np.nan)


def _siso(cl: Any, i: int, j: int) -> Siso:
    """Output ``i`` and input ``j`` of the state-space system ``cl``."""
    return Siso(np.asarray(cl.A, float), np.asarray(cl.B, float)[:, j : j + 1], np.asarray(cl.C, float)[i : i + 1, :],
                np.asarray(cl.D, float)[i : i + 1, j : j + 1])


def _channels(design: Any) -> tuple[int, int, int, int]:
    """Indices of the first joint's ``xD``, ``xD'``, ``xD''`` and disturbance inputs of the closed loop
    (its inputs are the ``3 n`` reference signals, then the disturbances)."""
    n = len(design.plant.positions)
    return 0, n, 2 * n, 3 * n


def reference_transfer(design: Any, s: complex) -> complex:
    """``x1(s)/xD(s)`` of a tracker driven by ``(xD, s xD, s^2 xD)`` (dimensionless)."""
    cl = design.closed_loop
    A, B, C, D = cl.A, cl.B, cl.C, cl.D
    i_pos, i_vel, i_acc, _ = _channels(design)
    w = np.zeros(len(cl.inputs), dtype=complex)
    for k, factor in ((i_pos, 1.0), (i_vel, s), (i_acc, s * s)):
        w[k] = factor
    x = np.linalg.solve(s * np.eye(len(A)) - A, B @ w)
    return complex(C[0] @ x + D[0] @ w)


def pole_placement(design: Any) -> Check:
    """Check ``"pole_placement"`` (see module docstring).

    Parameters
    ----------
    design : Design
        With ``closed_loop`` (inputs the reference signals then the disturbances; first output the
        first joint's position), requested ``poles`` and ``zeros`` (1/s) and its ``reference`` kind.

    Returns
    -------
    Check
        ``achieved``: worst scaled pole error; ``margin``: ``1 - max(error/tolerance)``.
    """
    cl = design.closed_loop
    poles = np.linalg.eigvals(np.asarray(cl.A, dtype=float)).astype(complex)
    ref = np.asarray(design.poles, dtype=complex)
    R = float(np.max(np.abs(ref))) if len(ref) and np.max(np.abs(ref)) > 0 else 1.0
    pm = match_roots(poles, ref, R)
    cerr = coefficient_error(poles, ref, R)
    ratios = {"poles": pm["ratio"], "characteristic polynomial": cerr / POLE_REL}
    failures = []
    if not pm["ok"]:
        failures.append(f"poles {np.round(poles, 9).tolist()} != requested {np.round(ref, 9).tolist()}")
    if not cerr <= POLE_REL:
        failures.append(f"characteristic polynomial differs by {cerr:.3g} (scaled)")
    cert: dict[str, Any] = {
        "poles": _pairs(poles), "requested_poles": _pairs(ref), "pole_scale": R, "pole_matching": pm["rows"],
        "coefficient_error": cerr, "tolerance": POLE_REL,
    }
    i_pos, _, _, i_dist = _channels(design)
    if design.reference == "step":  # servo: zeros and DC gain of x1/xD
        sub = _siso(cl, 0, i_pos)
        z, n_inf = finite_zeros(sub)
        zref = np.asarray(design.zeros, dtype=complex)
        Rz = max([R, *np.abs(zref).tolist()])
        zm = match_roots(z, zref, Rz)
        dc = dc_gain(sub)
        dc_err = scaled_error(dc, 1.0)
        ratios["zeros"] = zm["ratio"]
        ratios["dc gain"] = dc_err / DC_GAIN_TOL
        if not zm["ok"]:
            failures.append(f"zeros of x1/xD {np.round(z, 9).tolist()} != requested {np.round(zref, 9).tolist()}")
        if not dc_err <= DC_GAIN_TOL:
            failures.append(f"DC gain of x1/xD = {dc.real:.12g}, not 1")
        cert.update(
            zeros=_pairs(z), requested_zeros=_pairs(zref), zero_matching=zm["rows"], infinite_zeros_discarded=n_inf,
            dc_gain=dc.real, dc_gain_error=dc_err,
        )
    else:  # tracker: x1/xD == 1 identically, xi -> x1 zero at 0
        points = [0.0, 0.1j * R, 1j * R, 10j * R]
        vals = [reference_transfer(design, s) for s in points]
        errs = [scaled_error(v, 1.0) for v in vals]
        ratios["reference transfer"] = max(errs) / DC_GAIN_TOL
        if max(errs) > DC_GAIN_TOL:
            failures.append(f"x1/xD is not 1 (scaled error {max(errs):.3g})")
        if len(design.zeros):
            failures.append(f"the tracker's reference transfer has no zeros, but the design lists {design.zeros}")
            ratios["requested zeros"] = np.inf
        dz, n_inf = finite_zeros(_siso(cl, 0, i_dist))
        if _integral_action(design):  # an integral of the position error rejects a constant xi
            expected = [0.0, *(complex(z) for z in design.extra.get("disturbance_zeros", ()))]
            dm = match_roots(dz, expected, R)
            ratios["xi zeros"] = dm["ratio"]
            if not dm["ok"]:
                failures.append(f"zeros of x1/xi {np.round(dz, 9).tolist()} != {np.round(expected, 9).tolist()} "
                                "(integral action)")
        cert.update(
            reference_transfer={"s": _pairs(points), "value": _pairs(vals), "scaled_error": errs},
            disturbance_zeros=_pairs(dz), infinite_zeros_discarded=n_inf, zeros=[],
            requested_zeros=_pairs(design.zeros),
        )
    worst = max(ratios.values())
    cert["error_over_tolerance"] = {k: (float(v) if np.isfinite(v) else None) for k, v in ratios.items()}
    worst_pole = max((r["scaled_error"] for r in pm["rows"]), default=None)
    passed = not failures
    detail = (
        f"closed-loop poles and zeros as requested (worst error {worst:.2g} x tolerance)"
        if passed else "; ".join(failures)
    )
    return Check(
        name="pole_placement", passed=passed, target=f"poles and zeros as requested to {POLE_REL:g} (scaled)",
        achieved=worst_pole, margin=float(1.0 - worst) if np.isfinite(worst) else None, unit="1 (scaled)",
        detail=detail, certificate=cert,
    )
