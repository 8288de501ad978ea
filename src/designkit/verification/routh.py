"""Routh-Hurwitz stability test of a real polynomial: the Routh array, batched and shift-refined.

A real polynomial ``a0 s^n + a1 s^(n-1) + ... + an`` (``a0 != 0``) has all its roots in the open
left half plane iff every entry of the first column of its Routh array is nonzero and of the
sign of ``a0``.  An entry that is zero to working precision means a root on, or numerically
indistinguishable from, the imaginary axis, or a singular array with roots elsewhere (``s^3 + 1``).
The array is *not* continued with an epsilon (that decides by a convention, not by the data).
Instead:

- a clearly negative coefficient proves instability (a Hurwitz polynomial has all coefficients of
  one sign), as does a negative entry met before the zero;
- otherwise the polynomial is re-tested with a shifted variable, ``p(x + delta)`` and
  ``p(x - delta)`` with ``delta = ROUTH_SHIFT_REL * w``: the first Hurwitz-unstable proves a
  root with ``Re > delta`` (unstable), the second Hurwitz-stable proves every root has
  ``Re < -delta`` (stable);
- only if neither decides is the test **marginal** (``passed=None``): a root within ``delta`` of
  the imaginary axis.

Scaling.  Before building the array the polynomial is made monic and its variable scaled,
``s = w * x`` with ``w = |an/a0|^(1/n)``, so that the first column is dimensionless and of order
one for a well-balanced polynomial; ``(s + w)^3`` gives ``1, 3, 8/3, 1`` whatever ``w``.  The
margin reported is the smallest scaled first-column entry.

The conditions of a design's cubic characteristic polynomial, solved for its gains, and the
design-level check are in :mod:`designkit.verification.hurwitz_conditions`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from designkit.verification.check import Check
from designkit.verification.tolerances import ROUTH_SHIFT_REL, ROUTH_ZERO_REL

RouthStatus = Literal["stable", "unstable", "marginal"]

STABLE, MARGINAL, UNSTABLE = 1, 0, -1
"""Status codes of :func:`routh_batch`."""


@dataclass(frozen=True)
class RouthBatch:
    """First columns of the Routh arrays of a batch of polynomials of one degree.

    Parameters
    ----------
    first_column : ndarray, shape (P, n+1)
        Scaled first-column entries (dimensionless).  Entries after a zero pivot are NaN.
    tolerance : ndarray, shape (P, n+1)
        Magnitude under which each entry counts as zero (see
        :data:`~designkit.verification.tolerances.ROUTH_ZERO_REL`).
    status : ndarray of int8, shape (P,)
        ``1`` stable, ``0`` marginal (zero entry met before any negative one), ``-1`` unstable.
    margin : ndarray, shape (P,)
        Smallest scaled first-column entry up to the first non-positive one (positive iff stable).
    scale : ndarray, shape (P,)
        Frequency scale ``w`` (same unit as ``s``).
    shifted : ndarray of bool, shape (P,)
        True where the status was decided by the shifted re-test (the array itself met a zero).
    """

    first_column: np.ndarray
    tolerance: np.ndarray
    status: np.ndarray
    margin: np.ndarray
    scale: np.ndarray
    shifted: np.ndarray


def _frequency_scale(c: np.ndarray) -> np.ndarray:
    """``|an/a0|^(1/n)``, or ``max_k |ak/a0|^(1/k)`` when ``an = 0`` (``c`` is monic, shape (P, n+1))."""
    n = c.shape[1] - 1
    if n == 0:
        return np.ones(c.shape[0])
    with np.errstate(divide="ignore"):
        geo = np.abs(c[:, n]) ** (1.0 / n)
        k = np.arange(1, n + 1)
        bound = np.max(np.abs(c[:, 1:]) ** (1.0 / k), axis=1)
    w = np.where(geo > 0, geo, bound)
    return np.where(w > 0, w, 1.0)


def taylor_shift(c: np.ndarray, delta: float) -> np.ndarray:
    """Coefficients (highest power first, shape (P, n+1)) of ``p(x + delta)`` from those of ``p(x)``.

    Repeated synthetic division by ``x - delta`` (loops over the degree, not over polynomials).
    """
    b = np.array(c, dtype=float, copy=True)
    n = b.shape[1] - 1
    for i in range(n):
        for j in range(1, n + 1 - i):
            b[:, j] += delta * b[:, j - 1]
    return b


def routh_batch(coeffs: np.ndarray | Sequence[np.ndarray], *, refine: bool = True) -> RouthBatch:
    """Routh first columns of many polynomials at once (loops over rows, never over polynomials).

    Parameters
    ----------
    coeffs : array_like, shape (P, n+1), or sequence of n+1 arrays broadcastable together
        Coefficients, highest power first.  A sequence of arrays (as returned by a family's
        ``characteristic``) is stacked on the last axis and flattened to ``(P, n+1)``.

    Returns
    -------
    RouthBatch

    Raises
    ------
    ValueError
        When a leading coefficient is zero or a coefficient is not finite.

    Notes
    -----
    ``refine=False`` skips the shifted re-test of marginal polynomials (used by the re-test itself).
    """
    if isinstance(coeffs, tuple | list):
        arrays = np.broadcast_arrays(*[np.asarray(a, dtype=float) for a in coeffs])
        a = np.stack([x.ravel() for x in arrays], axis=-1)
    else:
        a = np.atleast_2d(np.asarray(coeffs, dtype=float))
    if not np.all(np.isfinite(a)):
        raise ValueError("polynomial coefficients must be finite")
    if np.any(a[:, 0] == 0):
        raise ValueError("leading coefficient must be nonzero")
    P, n1 = a.shape
    n = n1 - 1
    c = a / a[:, :1]  # monic; a0 < 0 is handled by the division
    w = _frequency_scale(c)
    c = c / w[:, None] ** np.arange(n1)
    m = n // 2 + 1
    r0 = np.zeros((P, m + 1))
    r1 = np.zeros((P, m + 1))
    r0[:, : len(range(0, n1, 2))] = c[:, 0::2]
    r1[:, : len(range(1, n1, 2))] = c[:, 1::2]
    coef_tol = ROUTH_ZERO_REL * np.max(np.abs(c), axis=1)
    first = np.empty((P, n1))
    tol = np.empty((P, n1))
    first[:, 0], tol[:, 0] = r0[:, 0], coef_tol
    if n >= 1:
        first[:, 1], tol[:, 1] = r1[:, 0], coef_tol
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i in range(2, n1):
            piv = r1[:, :1]
            prod_a = piv * r0[:, 1:]
            prod_b = r0[:, :1] * r1[:, 1:]
            new = (prod_a - prod_b) / piv
            new_tol = ROUTH_ZERO_REL * (np.abs(prod_a[:, 0]) + np.abs(prod_b[:, 0])) / np.abs(piv[:, 0])
            zero_pivot = np.abs(piv[:, 0]) <= tol[:, i - 1]
            new[zero_pivot] = np.nan
            new_tol[zero_pivot] = np.nan
            r0 = r1
            r1 = np.concatenate([new, np.zeros((P, 1))], axis=1)
            first[:, i], tol[:, i] = new[:, 0], new_tol
    positive = first > tol
    negative = first < -tol
    bad = ~positive
    has_bad = bad.any(axis=1)
    k = np.argmax(bad, axis=1)
    rows = np.arange(P)
    status = np.full(P, STABLE, dtype=np.int8)
    status[has_bad & negative[rows, k]] = UNSTABLE
    status[has_bad & ~negative[rows, k]] = MARGINAL
    # necessary condition: a Hurwitz polynomial has all coefficients of the sign of a0, so a
    # clearly negative coefficient proves instability even where the array met a zero pivot
    status[np.any(c < -coef_tol[:, None], axis=1)] = UNSTABLE
    upto = np.where(has_bad, k, n)
    mask = np.arange(n1)[None, :] <= upto[:, None]
    margin = np.min(np.where(mask, np.nan_to_num(first, nan=0.0), np.inf), axis=1)
    shifted = np.zeros(P, dtype=bool)
    todo = np.flatnonzero(status == MARGINAL)
    if refine and todo.size:
        # p(x + d) has the roots of p moved left by d; p(x - d) moved right by d
        right = routh_batch(taylor_shift(c[todo], ROUTH_SHIFT_REL), refine=False)
        left = routh_batch(taylor_shift(c[todo], -ROUTH_SHIFT_REL), refine=False)
        unstable, stable = right.status == UNSTABLE, left.status == STABLE
        status[todo] = np.where(unstable, UNSTABLE, np.where(stable, STABLE, MARGINAL))
        margin[todo] = np.where(unstable, right.margin, np.where(stable, left.margin, margin[todo]))
        shifted[todo] = unstable | stable
    return RouthBatch(first_column=first, tolerance=tol, status=status, margin=margin, scale=w, shifted=shifted)


@dataclass(frozen=True)
class RouthResult:
    """Routh test of one polynomial.

    Parameters
    ----------
    coefficients : tuple of float
        As given, highest power first.
    scale : float
        Frequency scale ``w`` (unit of ``s``).
    first_column : tuple of float
        Scaled first-column entries (dimensionless); NaN after a zero pivot.
    tolerance : tuple of float
        Zero threshold of each entry.
    status : {"stable", "unstable", "marginal"}
    margin : float
        Smallest scaled first-column entry (up to the first non-positive one).
    sign_changes : int or None
        Number of sign changes of the first column (= number of right-half-plane roots) when
        the array could be completed, else None.
    decided_by_shift : bool
        The array met a zero pivot and the status comes from the shifted re-test.
    """

    coefficients: tuple[float, ...]
    scale: float
    first_column: tuple[float, ...]
    tolerance: tuple[float, ...]
    status: RouthStatus
    margin: float
    sign_changes: int | None
    decided_by_shift: bool = False


def routh_array(coeffs: Sequence[float]) -> RouthResult:
    """Routh test of the real polynomial ``coeffs`` (highest power first).

    Examples
    --------
    >>> routh_array([1.0, 3.0, 3.0, 1.0]).status
    'stable'
    >>> routh_array([1.0, 1.0, 1.0, 1.0]).status   # roots -1, +-j
    'marginal'
    >>> routh_array([1.0, -1.0, 2.0, 1.0]).sign_changes
    2
    """
    b = routh_batch(np.asarray(coeffs, dtype=float)[None, :])
    first = b.first_column[0]
    code = int(b.status[0])
    status: RouthStatus = {STABLE: "stable", UNSTABLE: "unstable", MARGINAL: "marginal"}[code]
    changes = None
    if np.all(np.abs(first) > b.tolerance[0]):
        changes = int(np.count_nonzero(np.diff(np.sign(first)) != 0))
    return RouthResult(
        coefficients=tuple(float(x) for x in coeffs), scale=float(b.scale[0]),
        first_column=tuple(float(x) for x in first), tolerance=tuple(float(x) for x in b.tolerance[0]),
        status=status, margin=float(b.margin[0]), sign_changes=changes, decided_by_shift=bool(b.shifted[0]),
    )


def _passed(status: RouthStatus) -> bool | None:
    return {"stable": True, "unstable": False, "marginal": None}[status]


def _json_floats(xs: Sequence[float]) -> list[float | None]:
    return [None if not np.isfinite(x) else float(x) for x in xs]


def routh_hurwitz(coeffs: Sequence[float], labels: Sequence[str] | None = None) -> Check:
    """Check ``"routh_hurwitz"``: are all roots of ``coeffs`` in the open left half plane?

    Parameters
    ----------
    coeffs : sequence of float
        Polynomial coefficients, highest power first (unit of ``s``: 1/s).
    labels : sequence of str, optional
        Names of the coefficients (e.g. ``"1 + Km K2"``), copied into the certificate.

    Returns
    -------
    Check
        ``passed`` True (stable), False (a negative first-column entry: unstable, with the number
        of right-half-plane roots when the array completes) or None (marginal: a zero entry).
        ``margin`` is the smallest scaled first-column entry (dimensionless).
    """
    r = routh_array(coeffs)
    cert: dict[str, Any] = {
        "coefficients": list(r.coefficients),
        "labels": list(labels) if labels is not None else [f"a{k}" for k in range(len(r.coefficients))],
        "frequency_scale": r.scale,
        "first_column": _json_floats(r.first_column),
        "first_column_tolerance": _json_floats(r.tolerance),
        "status": r.status,
        "right_half_plane_roots": r.sign_changes,
        "decided_by_shift": r.decided_by_shift,
        "shift": ROUTH_SHIFT_REL * r.scale,
    }
    delta = f"{ROUTH_SHIFT_REL * r.scale:.3g}"
    if r.decided_by_shift:
        detail = {
            "stable": f"zero pivot, but p(s - {delta}) is Hurwitz: every root has Re < -{delta}",
            "unstable": f"zero pivot, and p(s + {delta}) is not Hurwitz: a root has Re >= {delta}",
        }[r.status]
    else:
        detail = {
            "stable": "all Routh first-column entries are positive: every root in the open left half plane",
            "unstable": "a Routh first-column entry or a coefficient is negative: "
            + (f"{r.sign_changes} root(s) in the right half plane" if r.sign_changes is not None
               else "at least one root in the right half plane"),
            "marginal": f"a Routh first-column entry is zero within rounding and the shifted re-test is "
            f"inconclusive: a root within {delta} of the imaginary axis; asymptotic stability undecided",
        }[r.status]
    return Check(
        name="routh_hurwitz", passed=_passed(r.status), target="all first-column entries > 0",
        achieved=r.margin, margin=r.margin, unit="1 (scaled)", detail=detail, certificate=cert,
    )
