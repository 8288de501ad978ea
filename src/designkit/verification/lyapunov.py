"""Quadratic Lyapunov functions ``V = x'Px`` as LMIs (cvxpy + Clarabel), re-checked with NumPy.

Problem solved (for one matrix ``A`` or a set of vertex matrices ``A_i``)::

    maximise  t
    subject to  t I <= Pb <= I,     Ah_i' Pb + Pb Ah_i <= -t I   (every i),
    Ah_i = D^-1 A_i D / s,          P = D^-1 Pb D^-1

Normalisation, in three steps that change no feasibility:

- ``D`` is a diagonal of powers of two balancing ``sum_i |A_i|`` (LAPACK ``gebal`` through
  :func:`scipy.linalg.matrix_balance`), so ``D^-1 A D`` is computed *exactly*.  The PID closed
  loops have entries from 1 to ``p^2`` (poles ``p`` in 1/s); without balancing the best margin for
  poles near -100 1/s is below 1e-9 and the check could never pass.
- ``s = max_i ||D^-1 A_i D||_2``: the LMIs are homogeneous in ``A``, so the margin is relative.
- ``Pb <= I`` bounds the problem (any feasible ``Pb`` can be scaled into it).

``t`` is then the best margin: ``t >= eps`` means a certificate of condition number at most
``1/eps`` in the balanced coordinates ``z = D^-1 x``.  ``V(x) = x'Px`` with ``P = D^-1 Pb D^-1``.

Who decides.  The solver's status is only a precondition: the returned ``Pb`` is symmetrised,
divided by its largest eigenvalue, and its eigenvalues and those of ``Ah_i'Pb + Pb Ah_i`` are
recomputed with NumPy.  The check passes iff the status is ``optimal`` and ``eig(Pb) >= eps``
and ``eig(Ah_i'Pb + Pb Ah_i) <= -eps`` for every ``i``.
Anything else is **undecided** (``passed=None``): a failure to find a ``P`` is not a proof that
none exists.  The one exception is proved independently: if a computed eigenvalue of some
``A_i`` has ``Re >= 0``, no ``P > 0`` with ``A_i'P + PA_i < 0`` exists (``V`` would have to
decrease along a non-decaying mode), so the check fails with that eigenvalue as evidence.

:func:`lyapunov_equation` is a second, solver-free route (SciPy's Bartels-Stewart solver of
``A'P + PA = -Q``); :func:`recheck` is the NumPy test both routes' certificates go through.

The balancing, the solve and the re-check are the shared LMI core of
:mod:`designkit.verification.lmi` (also used by the positive-real check); this module adds the
decision rules and the keys of the certificate stored in the :class:`Check`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from designkit.display.numbers import fmt_complex
from designkit.verification.check import Check
from designkit.verification.lmi import (
    Coordinates,
    LmiSolution,
    LyapunovCertificate,
    LyapunovRecheck,
    coordinates,
    lyapunov_recheck,
    solve_lyapunov,
    unstable_eigenvalue,
)
from designkit.verification.tolerances import EIG_RECHECK_TOL, LMI_EPS, LMI_SOLVER_OK


def _lyapunov_equation(a: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``X`` with ``a X + X a' = q`` (scipy); its warning that ``a`` has an eigenvalue pair summing to about zero
    (a marginal loop, solved by perturbing it) is not printed: every solution is judged by its rounding bounds."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return scipy.linalg.solve_continuous_lyapunov(a, q)

__all__ = [
    "Coordinates",
    "CrossCheck",
    "LmiSolution",
    "LyapunovCertificate",
    "Recheck",
    "common_lyapunov",
    "coordinates",
    "cross_check",
    "equation_certificate",
    "lyapunov_equation",
    "lyapunov_lmi",
    "recheck",
    "solve_lmi",
    "unstable_eigenvalue",
]

Recheck = LyapunovRecheck
"""The detailed result of :func:`recheck` (kept under its former name)."""


def recheck(As: Sequence[np.ndarray], P: np.ndarray, *, eps: float = LMI_EPS) -> LyapunovRecheck:
    """Is ``x'Px`` a Lyapunov function of every ``x' = A_i x`` with margin ``eps``?  (NumPy only.)

    ``P`` (original coordinates, any positive scale) is moved to the balanced coordinates,
    ``Pb = D P D``, symmetrised and divided by its largest eigenvalue (the LMI's ``Pb <= I``), so
    certificates from any route (e.g. :func:`lyapunov_equation`) are judged on the same footing:
    ``eig(Pb) >= eps`` and ``eig(Ah_i'Pb + Pb Ah_i) <= -eps``.  The shared re-check of
    :mod:`designkit.verification.lmi` (also behind :class:`LyapunovCertificate`).
    """
    return lyapunov_recheck(As, P, eps=eps)


def solve_lmi(As: Sequence[np.ndarray], *, solver: str = "CLARABEL") -> LmiSolution:
    """Solve the normalised common-Lyapunov LMI of the module docstring with cvxpy (the shared core)."""
    return solve_lyapunov(As, solver=solver)


def _certificate(sol: LmiSolution | None, rc: Recheck | None, As: Sequence[np.ndarray], eps: float) -> dict:
    cert: dict[str, Any] = {
        "eps": eps,
        "normalisation": "t I <= Pb <= I; Ah = D^-1 A D / s; P = D^-1 Pb D^-1",
    }
    if sol is not None:
        cert.update(solver=sol.solver, solver_status=sol.status, t=sol.t)
    if rc is not None:
        c = rc.coords
        P = rc.Pb / c.d[None, :] / c.d[:, None]
        cert["D"] = c.d.tolist()
        cert["A_scale"] = c.scale
        cert["P"] = P.tolist()
        cert["eig_P"] = np.linalg.eigvalsh(P).tolist()
        cert["eig_AtP_PA"] = [np.linalg.eigvalsh(A.T @ P + P @ A).tolist() for A in As]
        cert["Pb"] = rc.Pb.tolist()
        cert["eig_Pb"] = rc.eig_P.tolist()
        cert["eig_AhtPb_PbAh"] = [e.tolist() for e in rc.eig_lyap]
        cert["recheck_margin"] = rc.margin
    cert["eig_A"] = [[[complex(v).real, complex(v).imag] for v in np.linalg.eigvals(A)] for A in As]
    return cert


def _common_check(name: str, As: Sequence[np.ndarray], eps: float, solver: str, what: str) -> Check:
    As = [np.asarray(A, dtype=float) for A in As]
    target = f"eig(Pb) >= {eps:g}, eig(Ah'Pb + Pb Ah) <= -{eps:g} (Pb <= I, balanced and scaled)"
    for i, A in enumerate(As):
        lam = unstable_eigenvalue(A)
        if lam is not None:
            band = EIG_RECHECK_TOL * float(np.linalg.norm(A, 2))
            where = "" if len(As) == 1 else f" of vertex {i}"
            kind = "on the imaginary axis within rounding" if lam.real <= band else "in the right half plane"
            cert = _certificate(None, None, As, eps)
            cert["evidence"] = {"vertex": i, "eigenvalue": [lam.real, lam.imag]}
            return Check(
                name=name, passed=False, target=target, achieved=lam.real, margin=-lam.real, unit="1/s",
                detail=f"no {what} exists: eigenvalue {fmt_complex(lam, 6)}{where} is {kind} (Re >= 0)",
                certificate=cert,
            )
    sol = solve_lmi(As, solver=solver)
    rc = recheck(As, sol.P, eps=eps) if sol.P is not None else None
    cert = _certificate(sol, rc, As, eps)
    if sol.status not in LMI_SOLVER_OK or rc is None:
        return Check(
            name=name, passed=None, target=target, achieved=sol.t, margin=None, unit="1 (normalised)",
            detail=f"undecided: solver status {sol.status!r} (no {what} certified; not a proof that none exists)",
            certificate=cert,
        )
    if not rc.ok and sol.t is not None and sol.t < eps and len(As) == 1:
        eq = equation_certificate(As[0])
        if eq is not None:  # a stiff loop: the relative margin is small, the certificate is not
            cert["equation_route"] = eq
            return Check(
                name=name, passed=True, target="P > 0 and A'P + PA < 0 beyond their rounding bounds",
                achieved=eq["min_eig_Q_minus_bound"], margin=eq["min_eig_Q_minus_bound"], unit="1 (Q = I scale)",
                detail=f"{what} found by the Lyapunov equation and re-checked with rounding bounds: the LMI's relative "
                f"margin t* = {sol.t:.3g} is below eps = {eps:g} because the loop's poles span "
                f"{eq['pole_spread']:.3g} (stiff), but Ab'Pb + Pb Ab = -Q with min eig Q = {eq['min_eig_Q']:.4g} "
                f"(rounding bound {eq['Q_bound']:.2g}) and min eig Pb = {eq['min_eig_P']:.3g} "
                f"(rounding bound {eq['P_bound']:.2g})",
                certificate=cert,
            )
    if not rc.ok and sol.t is not None and sol.t < eps:
        return Check(
            name=name, passed=None, target=target, achieved=sol.t, margin=sol.t - eps, unit="1 (normalised)",
            detail=f"undecided: best LMI margin t* = {sol.t:.3g} < eps = {eps:g}: no {what} with margin eps "
            "(solver's optimum; a failure to find one is not a proof of instability)",
            certificate=cert,
        )
    if not rc.ok:
        return Check(
            name=name, passed=None, target=target, achieved=rc.margin + eps, margin=rc.margin,
            unit="1 (normalised)",
            detail=f"undecided: the solver's P fails the NumPy re-check by {-rc.margin:.3g} "
            f"(no {what} with margin eps found; not a proof that none exists)",
            certificate=cert,
        )
    return Check(
        name=name, passed=True, target=target, achieved=rc.margin + eps, margin=rc.margin, unit="1 (normalised)",
        detail=f"{what} found and re-checked: min eig Pb = {rc.eig_P[0]:.3g}, "
        f"max eig(Ah'Pb + Pb Ah) = {max(float(e[-1]) for e in rc.eig_lyap):.3g}",
        certificate=cert,
    )


ROUNDING_SAFETY = 10.0
"""Factor on the first-order rounding bounds of :func:`equation_certificate`."""


def equation_certificate(A: np.ndarray) -> dict[str, float] | None:
    """A Lyapunov certificate for a stiff ``A`` from the Lyapunov equation, judged by rounding bounds.

    The LMI's margin is relative to ``||A||``: a loop whose poles span six decades can never reach
    ``eps = 1e-6`` there, although it is plainly stable.  Here ``Pb`` solves
    ``Ab'Pb + Pb Ab = -I`` in balanced coordinates (Bartels-Stewart), and the computed
    ``Q = -(Ab'Pb + Pb Ab)`` and ``Pb`` are accepted when their smallest eigenvalues exceed what
    rounding can move: for the product, ``2 n u || |Ab| ||_2 || |Pb| ||_2`` (the elementwise error
    bound of a floating-point matrix product), and for a symmetric eigenvalue ``n u ||M||_2``
    (backward stability of ``eigh``), both times :data:`ROUNDING_SAFETY` (``u`` the unit
    roundoff).  Then ``x'Pb x`` is a Lyapunov function of the exact ``Ab`` (so of ``A``) whatever
    the rounding in its computation.

    Returns
    -------
    dict or None
        The figures of the certificate, or None when the bounds are not met (or ``A`` is not Hurwitz).
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    c = coordinates([A])
    Ab = A * c.d[None, :] / c.d[:, None]
    try:
        Pb = _lyapunov_equation(Ab.T, -np.eye(n))
    except (ValueError, np.linalg.LinAlgError):
        return None
    Pb = 0.5 * (Pb + Pb.T)
    if not np.all(np.isfinite(Pb)):
        return None
    u = np.finfo(float).eps / 2
    Q = -(Ab.T @ Pb + Pb @ Ab)
    Q = 0.5 * (Q + Q.T)
    normP = float(np.linalg.norm(Pb, 2))
    q_bound = ROUNDING_SAFETY * (2 * n * u * float(np.linalg.norm(np.abs(Ab), 2)) * float(np.linalg.norm(np.abs(Pb), 2))
                                 + n * u * float(np.linalg.norm(Q, 2)))
    p_bound = ROUNDING_SAFETY * n * u * normP
    eig_Q, eig_P = float(np.linalg.eigvalsh(Q)[0]), float(np.linalg.eigvalsh(Pb)[0])
    if eig_Q - q_bound <= 0 or eig_P - p_bound <= 0:
        return None
    lam = np.abs(np.linalg.eigvals(A))
    return {"min_eig_Q": eig_Q, "Q_bound": q_bound, "min_eig_Q_minus_bound": eig_Q - q_bound,
            "min_eig_P": eig_P, "P_bound": p_bound, "norm_P": normP,
            "pole_spread": float(np.max(lam) / max(np.min(lam), 1e-300)),
            "P": (Pb / c.d[None, :] / c.d[:, None]).tolist()}


def lyapunov_lmi(A: np.ndarray, *, eps: float = LMI_EPS, solver: str = "CLARABEL") -> Check:
    """Check ``"lyapunov"``: a quadratic Lyapunov function ``x'Px`` for ``x' = A x``.

    Parameters
    ----------
    A : ndarray, shape (n, n)
        State matrix (1/s).
    eps : float
        Margin of the strict inequalities on the normalised problem (see module docstring).
    solver : str
        cvxpy solver name (default Clarabel; ``"SCS"`` also works, with looser accuracy).

    Returns
    -------
    Check
        True: certificate found and re-checked by NumPy.  False: ``A`` has an eigenvalue with
        ``Re >= 0`` (evidence in the certificate).  None: solver failure, inaccurate status, or a
        ``P`` that fails the re-check.
    """
    return _common_check("lyapunov", [A], eps, solver, "Lyapunov function")


def common_lyapunov(As: Sequence[np.ndarray], *, eps: float = LMI_EPS, solver: str = "CLARABEL") -> Check:
    """Check ``"common_lyapunov"``: one ``P`` for every ``A_i`` (quadratic stability of their hull).

    A common ``P`` proves stability of every matrix in the convex hull of the ``A_i``, even under
    arbitrarily fast switching among them.  Failure to find one proves nothing (undecided),
    except when some ``A_i`` is itself not Hurwitz (then False).
    """
    return _common_check("common_lyapunov", list(As), eps, solver, "common Lyapunov function")


def lyapunov_equation(A: np.ndarray, Q: np.ndarray | None = None, *, balanced: bool = True) -> np.ndarray:
    """Solve a Lyapunov equation with SciPy's Bartels-Stewart solver (no optimisation).

    With ``balanced=False``: ``A'P + PA = -Q`` (default ``Q = I``).  With ``balanced=True``
    (default): ``Ab'Pb + Pb Ab = -Q`` in the balanced coordinates of :func:`coordinates`
    (``Ab = D^-1 A D``) and ``P = D^-1 Pb D^-1`` is returned, which satisfies
    ``A'P + PA = -D^-1 Q D^-1``; for badly scaled ``A`` (the PID closed loops) this ``P`` is far
    better conditioned than the one from ``Q = I`` in the original coordinates.

    For Hurwitz ``A`` and ``Q > 0`` the solution is the unique ``P > 0``; judge it with
    :func:`recheck`, the same NumPy test as the LMI's certificate.
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    Q = np.eye(n) if Q is None else np.asarray(Q, dtype=float)
    d = coordinates([A]).d if balanced else np.ones(n)
    Ab = A * d[None, :] / d[:, None]
    # scipy solves a X + X a^H = q; with a = Ab' this is Ab'X + X Ab = q
    Pb = _lyapunov_equation(Ab.T, -Q)
    Pb = 0.5 * (Pb + Pb.T)
    return Pb / d[None, :] / d[:, None]


@dataclass(frozen=True)
class CrossCheck:
    """The LMI route against the Lyapunov-equation route, both judged by :func:`recheck`.

    Parameters
    ----------
    lmi : Recheck or None
        Re-check of the cvxpy certificate (None when the solver returned no ``P``).
    equation : Recheck
        Re-check of ``lyapunov_equation(A)`` (balanced, ``Q = I``).
    reconstruction_error : float or None
        Scaled error between the LMI's ``P`` and SciPy's solution of ``A'X + XA = -Q_lmi`` with
        ``Q_lmi = -(A'P + PA)``: the Lyapunov equation has a unique solution, so a correct LMI
        certificate is reproduced exactly (up to rounding) by the solver-free route.
    status : str
        The LMI solver status.
    """

    lmi: Recheck | None
    equation: Recheck
    reconstruction_error: float | None
    status: str


def cross_check(A: np.ndarray, *, eps: float = LMI_EPS, solver: str = "CLARABEL") -> CrossCheck:
    """Solve for ``P`` both ways (cvxpy LMI, SciPy equation) and re-check both with NumPy."""
    A = np.asarray(A, dtype=float)
    sol = solve_lmi([A], solver=solver)
    eq = recheck([A], lyapunov_equation(A), eps=eps)
    if sol.P is None:
        return CrossCheck(None, eq, None, sol.status)
    c = coordinates([A])
    # compare in balanced coordinates, where both P are of order one
    Ab = A * c.d[None, :] / c.d[:, None]
    Pb = (sol.P * c.d[None, :]) * c.d[:, None]
    Qb = -(Ab.T @ Pb + Pb @ Ab)
    Xb = _lyapunov_equation(Ab.T, -Qb)
    err = float(np.max(np.abs(Xb - Pb)) / (1.0 + np.max(np.abs(Pb))))
    return CrossCheck(recheck([A], sol.P, eps=eps), eq, err, sol.status)
