"""The one tolerance table of the verification layer (and of its tests).

Every numerical threshold used to decide a check lives here, with the reason for its value.
Errors are compared *scaled*: ``|x - ref| / (1 + |ref|)`` for a single number (cvxpy's
convention), and ``|p - p_ref| / R`` for a pole or zero of a set whose largest magnitude is ``R``
(eigenvalues are computed with an error proportional to the size of the spectrum, not of each
eigenvalue).
"""

from __future__ import annotations

import numpy as np

# ----------------------------------------------------------------------------- poles and zeros

POLE_REL = 1e-9
"""Relative tolerance (to the pole-set magnitude ``R``) for a computed simple pole or zero to
equal the requested one, and for the scaled characteristic-polynomial coefficients
``c_k / R^k`` to equal the requested ones."""

POLE_CLUSTER_REL = 1e-4
"""Requested poles closer than ``POLE_CLUSTER_REL * R`` form a cluster.  A cluster of ``m`` poles
is an ``m``-fold root to working precision: a perturbation ``d`` of the coefficients moves it by
``d**(1/m)``, so its poles are compared to ``POLE_REL ** (1/m)`` (3.2e-5 for a double pole,
1e-3 for a triple one).  The coefficient comparison stays at ``POLE_REL``."""

ZERO_INFINITE_REL = 1e10
"""A zero returned by the QZ algorithm with ``|z| > ZERO_INFINITE_REL * ||[A B; C D]||`` is an
infinite zero rounded to a finite number (its ``beta`` is of the order of machine epsilon) and
is discarded."""

DC_GAIN_TOL = 1e-9
"""Scaled error allowed between the DC gain of ``x1/xD`` and 1 (servo), and between the
reference transfer of the tracker and 1 at the test frequencies."""

# ----------------------------------------------------------------------------- Routh-Hurwitz

ROUTH_ZERO_REL = 1e-10
"""A Routh first-column entry is "zero" (marginal, undecided) when its magnitude is below
``ROUTH_ZERO_REL`` times the magnitude of the products it was computed from (about 5e5 machine
epsilons: rounding errors of a few rows cannot reach it)."""

ROUTH_SHIFT_REL = 1e-6
"""When the array meets a zero pivot, the polynomial is re-tested with its variable shifted by
``+-ROUTH_SHIFT_REL * w`` (``w`` its frequency scale): a root with ``Re > delta`` proves
instability, all roots with ``Re < -delta`` prove stability; only roots within ``delta`` of the
imaginary axis leave the test marginal."""

# ----------------------------------------------------------------------------- Lyapunov LMI

LMI_EPS = 1e-6
"""Margin of the strict LMIs, on the problem normalised by ``||A||_2`` and by ``P <= I``:
a pass needs ``eig(P) >= LMI_EPS`` and ``eig(Ah'P + P Ah) <= -LMI_EPS`` with ``Ah = A/||A||_2``
(a certificate with condition number at most ``1/LMI_EPS``)."""

EIG_RECHECK_TOL = 1e-9
"""Relative size (to ``||A||_2``) under which the real part of an eigenvalue of ``A`` is
indistinguishable from zero: the "on the imaginary axis within rounding" band used in messages."""

LMI_SOLVER_OK = ("optimal",)
"""cvxpy statuses whose solution is re-checked; any other status (``optimal_inaccurate``,
``infeasible``, ``solver_error``...) leaves the check undecided."""

# ----------------------------------------------------------------------------- time domain

STEADY_STATE_WINDOW = 0.05
"""Fraction of the run (at its end) over which the steady-state error is averaged."""

RISE_LIMITS = (0.1, 0.9)
"""Rise time is measured between these fractions of the commanded step."""

REST_TOL = 1e-9
"""Scaled size under which a step amplitude (or trajectory move) counts as zero."""


def scaled_error(x: np.ndarray | float | complex, ref: np.ndarray | float | complex) -> np.ndarray | float:
    """``|x - ref| / (1 + |ref|)``, elementwise (same unit-free scale as cvxpy's tests).

    Parameters
    ----------
    x, ref : array_like or scalar
        Value and reference (any unit; complex allowed).

    Returns
    -------
    ndarray or float
        Scaled absolute error, dimensionless.

    Examples
    --------
    >>> float(scaled_error(1.0 + 1e-10, 1.0)) < 1e-9
    True
    """
    x, ref = np.asarray(x), np.asarray(ref)
    out = np.abs(x - ref) / (1.0 + np.abs(ref))
    return float(out) if out.ndim == 0 else out


def cluster_tolerance(multiplicity: int) -> float:
    """Tolerance of a pole belonging to a cluster of ``multiplicity`` poles (see :data:`POLE_CLUSTER_REL`)."""
    return POLE_REL ** (1.0 / max(1, int(multiplicity)))
