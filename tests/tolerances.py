"""The one tolerance table of the tests: every bound a test compares against, with why it has its value.

Errors are scaled, ``|x - ref| / (1 + |ref|)`` (cvxpy's convention), unless the entry says
otherwise.  The verification layer's own thresholds (which decide checks) are in
``designkit.verification.tolerances``; this table is for the tests' comparisons with independent
routes.
"""

from __future__ import annotations

TOL = {
    # same arithmetic, e.g. compiled against interpreted evaluation of one CasADi function
    "exact": 0.0,
    # two exact routes in floating point (hand-derived matrices against a CasADi linearization)
    "algebra": 1e-12,
    # eigenvalues of well-conditioned matrices with simple roots
    "eigenvalues": 1e-9,
    # central finite differences of smooth functions (h = 1e-6): truncation ~h^2, rounding ~eps/h
    "finite_difference": 1e-6,
    # fixed-step RK4 at dt |p|max = 0.02..0.05 against an exact (or tightly integrated) solution
    "rk4_vs_exact": 1e-7,
    # RK4 against python-control's first-order-hold forced response on a finer grid
    "rk4_vs_foh": 1e-6,
    # the coupled arm's RK4 (dt = 0.1 ms) against scipy DOP853 at rtol 1e-11 on the printed equations
    "rk4_vs_ivp": 1e-6,
    # CVODES at rtol 1e-10 against the linear solution or a fine RK4
    "cvodes": 1e-6,
    # a transient that has decayed by more than 10 time constants
    "settled": 1e-4,
}
