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

ERROR_DYNAMICS_REL = 1e-8
"""Largest entry-wise deviation, relative to the largest entry, of a linearized error-dynamics matrix
from the decoupled companion form ``[[0, I], [-K1, -K2]]`` (check ``error_poles``).  The matrix is
the automatic derivative of an exactly cancelling composition (the model's inverse dynamics fed to
its forward dynamics, through ``J^-1`` for task space): rounding leaves ~1e-13 of the entries, times
the condition number of ``J`` (up to ~1e3 on a path the ``singularity`` check accepts)."""

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

# ----------------------------------------------------------------------------- proved brackets

BOUNDARY_REL = 1e-9
"""A statement ``value < bound`` judged on a proved bracket (:mod:`designkit.verification.bracket`) is undecided when
the bracket's end lies within this fraction of ``|bound|`` of the bound: a certificate that holds by less than the
precision its bounds are computed to is not a proof either way (a contraction at ``rho = 1 - 4.5e-13``)."""

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


# ----------------------------------------------------------------------------- positive real (KYP)

KYP_EQ_TOL = 1e-7
"""Largest accepted relative residual ``||P B - alpha C'|| / (||P|| ||B|| + alpha ||C||)`` of the
KYP equality, in the normalised problem (``||P|| = ||B|| = ||C|| = 1``).  The residual is the
relative backward error of the linear equation: ``P`` and ``alpha C'`` need relative changes of at
most this size to satisfy it exactly (the change of ``P`` is not necessarily symmetric: with
``D = 0`` the equality can only ever be checked to a tolerance).  Clarabel's feasibility tolerance
is 1e-8 (``tol_feas``, on its internally scaled problem); the residuals measured on 150 random SPR
systems of order 1 to 5 (``A`` scaled over four decades) were 1e-16 to 2e-11.  1e-7 therefore
accepts every solution the solver calls optimal with a wide margin, and it stays ten times below
``LMI_EPS``: a change of ``P`` by that fraction cannot undo the strict inequalities, which hold
with margin ``LMI_EPS``."""

SPR_CB_TOL = 1e-9
"""Relative size (to ``|| |C| |B| ||_2``) beyond which an asymmetry of ``C B`` or a negative
eigenvalue of its symmetric part is a fact and not rounding: each entry of the computed ``C B``
is within ``n u (|C| |B|)`` of the exact one (``u = 1.1e-16``), far below 1e-9 for any state
dimension in use.  Inside the band the necessary condition ``C B = (C B)' > 0`` is undecided."""

SPR_FREQ_TOL = 1e-8
"""A smallest eigenvalue of ``H(jw) + H(jw)^*`` counts as negative (evidence that ``H`` is not
positive real) only below ``-SPR_FREQ_TOL * ||C||_2 ||(jwI - A)^-1 B||_2``: the rounding error of
``H(jw)`` computed by a linear solve is about ``u cond(jwI - A)`` times that product
(``u = 1.1e-16``), so 1e-8 is safe up to ``cond(jwI - A)`` of about 1e5; beyond that the threshold
grows with the condition number (``1e3 u cond``, see :meth:`designkit.verification.kyp.SprSweep.threshold`)."""

# ----------------------------------------------------------------------------- linear programs

LP_EPS = 1e-6
"""Relative margin of a strict linear condition ``c0 + c . theta > 0``: it is certified when its
rigorous lower bound over the polytope is at least ``LP_EPS * (|c0| + sum_j |c_j| max|theta_j|)``
(the size of its terms over the bounding box).  Clarabel solves LPs to about 1e-8 relative; a
smaller certified minimum is at the level of the solver's accuracy and is left undecided."""

LP_SOLVER_OK = ("optimal",)
"""cvxpy statuses whose LP solution (point and dual multipliers) is re-checked; any other status
leaves the condition undecided unless NumPy finds a counterexample on its own."""

FARKAS_TOL = 1e-9
"""Largest accepted ``||G'y||_2 / sum_i y_i ||G_i||_2`` for a Farkas vector ``y >= 0`` proving that
``G x <= h`` has no solution: with ``h . y < 0`` it excludes every ``x`` with
``||x||_2 < -h . y / ||G'y||_2`` (reported as the radius).  The solver's dual is first polished in
NumPy (projected onto ``null(G')`` by least squares on its support), because the raw Clarabel dual
has ratios up to 1e-8 (measured on 400 random infeasible systems); polished, the ratio was at most
5e-16.  1e-9 is far above that, and it guarantees a radius of at least 1e9 times the problem's
length scale ``-h . y / sum_i y_i ||G_i||``."""
