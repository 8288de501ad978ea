"""Strictly positive real transfers by the Kalman-Yakubovich-Popov lemma, re-checked with NumPy.

``H(s) = C (sI - A)^-1 B`` (square, ``D = 0``; ``A`` in 1/s, ``H`` in the unit of ``C B`` times s)
is strictly positive real (SPR) when it is analytic in ``Re s > -delta`` and
``H(s - delta)`` is positive real for some ``delta > 0``.  For ``D = 0`` this is (Khalil,
*Nonlinear Systems*, 3rd ed., Lemma 6.1) ``A`` Hurwitz, ``H(jw) + H(jw)^* > 0`` for every real
``w`` and ``lim w^2 (H(jw) + H(jw)^*) > 0``.

Certificate (KYP lemma, the direction used here needs no minimality): if ``P > 0``,
``A'P + PA = -Q < 0``, ``P B = C'`` and ``B`` has full column rank, then with
``Phi = (jwI - A)^-1``::

    H(jw) + H(jw)^* = B'P Phi B + B' Phi^* P B = (Phi B)^* Q (Phi B) > 0,
    lim w^2 (H(jw) + H(jw)^*) = -(C A B + (C A B)') = B'QB > 0,

so ``H`` is SPR.  The LMI is solved in the normalised form of :mod:`designkit.verification.lmi`
(balanced ``A``, ``||A|| = ||B|| = ||C|| = 1``, ``t I <= P <= I``, ``P B = alpha C'`` with a free
``alpha >= t``, maximise ``t``).

Who decides.  PASS only when the solver says ``optimal`` *and* the NumPy re-check of
:class:`~designkit.verification.lmi.KypCertificate` holds (eigenvalues of ``P`` and of
``A'P + PA`` with margin ``eps``, full-rank ``B``, relative residual of ``P B = C'`` at most
:data:`~designkit.verification.tolerances.KYP_EQ_TOL`).  FAIL only on an independent fact:

1. ``A`` has an eigenvalue with ``Re >= 0``: no ``P > 0`` with ``A'P + PA < 0`` exists (for the
   realisation; a hidden unstable mode is a failure of the state-space system even if ``H``
   cancels it).
2. ``C B`` is not symmetric positive definite.  Necessity, for ``H`` PR with ``D = 0``: on the
   imaginary axis ``w (H(jw) + H(jw)^*) -> -j (C B - (C B)')``, a Hermitian matrix with
   eigenvalues ``+-sigma`` when ``C B`` is not symmetric, so ``H + H^*`` has a negative eigenvalue
   at large ``w``; on the real axis ``s (H(s) + H(s)') -> C B + (C B)'`` as ``s -> +inf``, and PR
   needs ``H(s) + H(s)^* >= 0`` for ``Re s > 0``, so the symmetric part is ``>= 0``; and if
   ``C B v = 0`` for ``v != 0`` then ``v'H(s)v`` is PR with relative degree at least two, which a
   PR function other than zero cannot have (``k/s^2`` has negative real part on part of every
   large half circle), while ``v'Hv = 0`` contradicts ``H + H^* > 0``.  Only a violation beyond
   rounding (:data:`~designkit.verification.tolerances.SPR_CB_TOL`) is a FAIL; a nearly singular
   ``C B`` is left to the other routes.
3. A frequency ``w`` at which the smallest eigenvalue of ``H(jw) + H(jw)^*`` is negative beyond
   rounding (:data:`~designkit.verification.tolerances.SPR_FREQ_TOL`), found by
   :func:`spr_frequency_sweep`: the frequency and the value are the evidence.

Anything else (solver failure, inaccurate status, margin ``t < eps``, a ``P`` that fails the
re-check) is UNDECIDED: not finding a ``P`` proves nothing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_complex
from designkit.verification.check import Check
from designkit.verification.lmi import KypCertificate, coordinates, solve_kyp, symmetrise, unstable_eigenvalue
from designkit.verification.tolerances import (
    EIG_RECHECK_TOL,
    KYP_EQ_TOL,
    LMI_EPS,
    LMI_SOLVER_OK,
    SPR_CB_TOL,
    SPR_FREQ_TOL,
)

__all__ = ["SprSweep", "default_frequencies", "positive_real", "spr_frequency_sweep"]

_POINTS_PER_DECADE = 40
"""Density of the default frequency grid (log-spaced)."""

_U = float(np.finfo(float).eps) / 2.0
"""Unit roundoff of float64."""


def _realisation(A: Any, B: Any, C: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Float arrays ``A`` (n x n), ``B`` (n x m), ``C`` (m x n); 1-D ``B``/``C`` are a column/row."""
    A = np.atleast_2d(np.asarray(A, dtype=float))
    B = np.asarray(B, dtype=float)
    C = np.asarray(C, dtype=float)
    B = B.reshape(-1, 1) if B.ndim == 1 else B
    C = C.reshape(1, -1) if C.ndim == 1 else C
    n = A.shape[0]
    if A.shape != (n, n) or B.ndim != 2 or B.shape[0] != n or C.shape != (B.shape[1], n):
        raise ValueError(f"need A n x n, B n x m, C m x n; got {A.shape}, {B.shape}, {C.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B)) and np.all(np.isfinite(C))):
        raise ValueError("A, B and C must be finite")
    return A, B, C


@dataclass(frozen=True)
class SprSweep:
    """Frequency-domain view of ``H(s) = C (sI - A)^-1 B`` (the route independent of the LMI).

    Parameters
    ----------
    w : ndarray
        Frequencies (rad/s), ascending, starting at 0 for the default grid.
    min_eig : ndarray
        Smallest eigenvalue of the Hermitian part ``H(jw) + H(jw)^*`` at each ``w`` (unit of ``H``).
    scale : ndarray
        ``||C||_2 ||(jwI - A)^-1 B||_2`` at each ``w`` (balanced coordinates; unit of ``H``): the
        size rounding errors are measured against.
    cond : ndarray
        2-norm condition number of ``jwI - A`` (balanced) at each ``w``.
    cb : ndarray
        ``C B``, the first Markov parameter (``lim s H(s)``).
    cb_asymmetry : float
        ``||C B - (C B)'||_2 / || |C| |B| ||_2``.
    cb_eig : ndarray
        Eigenvalues of the symmetric part of ``C B``, divided by ``|| |C| |B| ||_2``.
    high_frequency : ndarray
        Eigenvalues of ``-(C A B + (C A B)')``, which is ``lim w^2 (H(jw) + H(jw)^*)`` when
        ``C B`` is symmetric (unit of ``H`` times rad/s).
    """

    w: np.ndarray
    min_eig: np.ndarray
    scale: np.ndarray
    cond: np.ndarray
    cb: np.ndarray
    cb_asymmetry: float
    cb_eig: np.ndarray
    high_frequency: np.ndarray

    @property
    def relative(self) -> np.ndarray:
        """``min_eig / scale`` (dimensionless)."""
        return self.min_eig / np.where(self.scale > 0, self.scale, 1.0)

    @property
    def worst(self) -> int:
        """Index of the grid point with the smallest relative Hermitian eigenvalue."""
        return int(np.argmin(self.relative))

    def threshold(self, tol: float = SPR_FREQ_TOL) -> np.ndarray:
        """Relative size below which a negative ``min_eig`` is evidence, per frequency:
        ``max(tol, 1e3 u cond(jwI - A))`` (``u`` the unit roundoff), so that a badly conditioned
        solve can never produce the evidence."""
        return np.maximum(tol, 1e3 * _U * self.cond)

    def violation(self, tol: float = SPR_FREQ_TOL) -> int | None:
        """Index of the most negative relative ``min_eig`` among the points where it is below
        ``-threshold`` (evidence that ``H`` is not positive real), else None."""
        bad = np.flatnonzero(self.relative < -self.threshold(tol))
        return int(bad[np.argmin(self.relative[bad])]) if bad.size else None

    @property
    def positive(self) -> bool:
        """The sweep's verdict on SPR: Hermitian part positive at every grid point, ``C B``
        symmetric (to :data:`SPR_CB_TOL`) and positive definite, and the high-frequency limit positive.

        A finite grid proves nothing about the frequencies between its points; this is the
        independent numerical route, not a certificate.
        """
        return bool(
            np.all(self.min_eig > 0)
            and self.cb_asymmetry <= SPR_CB_TOL
            and self.cb_eig[0] > 0
            and self.high_frequency[0] > 0
        )

    def summary(self) -> dict[str, Any]:
        """JSON-ready numbers of the worst point and the limits."""
        k = self.worst
        return {
            "points": len(self.w),
            "w_range_rad_s": [float(self.w[0]), float(self.w[-1])],
            "w_worst_rad_s": float(self.w[k]),
            "min_eig_worst": float(self.min_eig[k]),
            "relative_min_eig_worst": float(self.relative[k]),
            "high_frequency_eig": self.high_frequency.tolist(),
        }


def default_frequencies(A: np.ndarray) -> np.ndarray:
    """0 and a log grid from ``w_min / 1e3`` to ``1e5 w_max`` (rad/s), plus ``|Im lambda|``.

    ``w_min`` and ``w_max`` are the smallest and largest non-zero ``|lambda(A)|`` (``w_max`` at
    least ``||D^-1 A D||_2``).  The top decades reach the ``1/w^2`` asymptote of the Hermitian part.
    """
    A = np.asarray(A, dtype=float)
    lam = np.linalg.eigvals(A)
    mags = np.abs(lam[np.abs(lam) > 0])
    c = coordinates([A])
    hi = max(float(np.max(mags)) if mags.size else 1.0, c.scale)
    lo = float(np.min(mags)) if mags.size else 1.0
    w_lo, w_hi = lo * 1e-3, hi * 1e5
    num = int(np.ceil(np.log10(w_hi / w_lo) * _POINTS_PER_DECADE)) + 1
    extra = np.abs(lam.imag[lam.imag > 0])
    return np.unique(np.concatenate([[0.0], np.logspace(np.log10(w_lo), np.log10(w_hi), num), extra]))


def spr_frequency_sweep(A: Any, B: Any, C: Any, w: Any = None) -> SprSweep:
    """Hermitian part of ``H(jw)`` on a frequency grid, and the limits at infinity.

    Parameters
    ----------
    A, B, C : array_like
        Realisation (``A`` n x n in 1/s, ``B`` n x m, ``C`` m x n; 1-D ``B``/``C`` for SISO).
    w : array_like, optional
        Frequencies (rad/s); default :func:`default_frequencies`.

    Returns
    -------
    SprSweep
        ``min_eig[k]`` is the smallest eigenvalue of ``H(jw_k) + H(jw_k)^*``.  ``H`` is evaluated in
        the balanced coordinates (``D^-1 A D``, ``D^-1 B``, ``C D``: the same transfer, smaller
        rounding) by a batched linear solve, without any optimisation.
    """
    A, B, C = _realisation(A, B, C)
    w = default_frequencies(A) if w is None else np.sort(np.atleast_1d(np.asarray(w, dtype=float)))
    c = coordinates([A])
    Ab = A * c.d[None, :] / c.d[:, None]
    Bb, Cb = B / c.d[:, None], C * c.d[None, :]
    n = A.shape[0]
    M = 1j * w[:, None, None] * np.eye(n)[None] - Ab[None]
    X = np.linalg.solve(M, np.broadcast_to(Bb.astype(complex), (len(w), *Bb.shape)))
    H = Cb[None] @ X
    herm = H + np.conj(np.swapaxes(H, 1, 2))
    min_eig = np.linalg.eigvalsh(herm)[:, 0]
    scale = float(np.linalg.norm(Cb, 2)) * np.linalg.norm(X, ord=2, axis=(1, 2))
    cond = np.linalg.cond(M)
    cb = C @ B
    size = float(np.linalg.norm(np.abs(C) @ np.abs(B), 2))
    size = size if size > 0 else 1.0
    cab = Cb @ Ab @ Bb
    return SprSweep(
        w=w,
        min_eig=min_eig,
        scale=scale,
        cond=cond,
        cb=cb,
        cb_asymmetry=float(np.linalg.norm(cb - cb.T, 2)) / size,
        cb_eig=np.linalg.eigvalsh(symmetrise(cb)) / size,
        high_frequency=np.linalg.eigvalsh(-symmetrise(2.0 * cab)),
    )


def _fail(target: str, achieved: float, unit: str, detail: str, cert: dict[str, Any], evidence: dict) -> Check:
    cert["evidence"] = evidence
    return Check(
        name="positive_real", passed=False, target=target, achieved=achieved, margin=achieved, unit=unit,
        detail=detail, certificate=cert,
    )


def _undecided(target: str, achieved: float | None, margin: float | None, detail: str, cert: dict) -> Check:
    return Check(
        name="positive_real", passed=None, target=target, achieved=achieved, margin=margin,
        unit="1 (normalised)", detail=f"undecided: {detail}", certificate=cert,
    )


def positive_real(A: Any, B: Any, C: Any, *, eps: float = LMI_EPS, solver: str = "CLARABEL") -> Check:
    """Check ``"positive_real"``: is ``H(s) = C (sI - A)^-1 B`` strictly positive real?

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix (1/s).
    B : array_like, shape (n, m) or (n,)
        Input matrix.
    C : array_like, shape (m, n) or (n,)
        Output matrix (``H`` is square, ``D = 0``).
    eps : float
        Margin of the strict inequalities in the normalised problem (module docstring).
    solver : str
        cvxpy solver name.

    Returns
    -------
    Check
        True: KYP certificate found and re-checked by NumPy.  False: ``A`` not Hurwitz, ``C B``
        not symmetric positive definite, or a frequency with ``H + H^*`` not positive
        semidefinite (evidence under ``"evidence"``).  None: anything else.

        Certificate keys: ``eps``, ``eq_tol``, ``normalisation``, ``eig_A`` (``[re, im]`` pairs),
        ``CB``, ``CB_asymmetry``, ``eig_CB_sym`` (relative); after the sweep ``sweep`` (worst
        frequency, its eigenvalue, high-frequency limit); after the solve ``solver``,
        ``solver_status``, ``t``, ``alpha``; with a ``P``: ``P`` (original coordinates,
        ``P B = C'``), ``eig_P``, ``eig_AtP_PA``, ``PB_minus_Ct`` (``||P B - C'|| / (||P|| ||B|| + ||C||)``),
        ``D``, ``A_scale``, ``Pb``, ``eig_Pb``, ``eig_AhtPb_PbAh``, ``alpha_recheck``,
        ``equality_residual``, ``sigma_min_B``, ``recheck_margin``.
    """
    A, B, C = _realisation(A, B, C)
    target = f"P > 0, A'P + PA < 0, P B = C' (margin {eps:g} normalised, residual <= {KYP_EQ_TOL:g})"
    cert: dict[str, Any] = {
        "eps": eps,
        "eq_tol": KYP_EQ_TOL,
        "normalisation": "t I <= Pn <= I; Ah = D^-1 A D / s; Pn Bn = alpha Cn'; P = P_user with P B = C'",
        "eig_A": [[v.real, v.imag] for v in np.linalg.eigvals(A).astype(complex)],
    }

    lam = unstable_eigenvalue(A)
    if lam is not None:
        band = EIG_RECHECK_TOL * float(np.linalg.norm(A, 2))
        kind = "on the imaginary axis within rounding" if lam.real <= band else "in the right half plane"
        return _fail(
            target, lam.real, "1/s", f"not SPR: eigenvalue {fmt_complex(lam, 6)} of A is {kind} (Re >= 0)", cert,
            {"eigenvalue": [lam.real, lam.imag]},
        )

    sweep = spr_frequency_sweep(A, B, C)
    cert.update(CB=sweep.cb.tolist(), CB_asymmetry=sweep.cb_asymmetry, eig_CB_sym=sweep.cb_eig.tolist())
    if sweep.cb_asymmetry > SPR_CB_TOL:
        return _fail(
            target, -sweep.cb_asymmetry, "1 (relative)",
            f"not SPR: C B is not symmetric (relative asymmetry {sweep.cb_asymmetry:.3g}); "
            "w (H + H^*) tends to a matrix with a negative eigenvalue", cert,
            {"CB": sweep.cb.tolist(), "CB_asymmetry": sweep.cb_asymmetry},
        )
    if sweep.cb_eig[0] < -SPR_CB_TOL:
        return _fail(
            target, float(sweep.cb_eig[0]), "1 (relative)",
            f"not SPR: C B has the negative eigenvalue {sweep.cb_eig[0]:.3g} (relative); "
            "s (H(s) + H(s)') tends to C B + (C B)' on the positive real axis", cert,
            {"CB": sweep.cb.tolist(), "eig_CB_sym": sweep.cb_eig.tolist()},
        )
    cert["sweep"] = sweep.summary()
    k = sweep.violation()
    if k is not None:
        wk = float(sweep.w[k])
        Hk = _transfer(A, B, C, wk)
        return _fail(
            target, float(sweep.min_eig[k]), "unit of H",
            f"not SPR: H(jw) + H(jw)^* has the eigenvalue {sweep.min_eig[k]:.4g} < 0 at w = {wk:.4g} rad/s", cert,
            {
                "frequency_rad_s": wk,
                "min_eig_hermitian": float(sweep.min_eig[k]),
                "relative": float(sweep.relative[k]),
                "H": [[[z.real, z.imag] for z in row] for row in Hk],
            },
        )

    sol = solve_kyp(A, B, C, solver=solver)
    cert.update(solver=sol.solver, solver_status=sol.status, t=sol.t, alpha=sol.alpha)
    rc = None
    if sol.P is not None:
        P = sol.P
        rc = KypCertificate(A, B, C, P, eps=eps).recheck()
        res = np.linalg.norm(P @ B - C.T, 2) / (np.linalg.norm(P, 2) * np.linalg.norm(B, 2) + np.linalg.norm(C, 2))
        cert.update(
            P=P.tolist(),
            eig_P=np.linalg.eigvalsh(P).tolist(),
            eig_AtP_PA=np.linalg.eigvalsh(symmetrise(A.T @ P + P @ A)).tolist(),
            PB_minus_Ct=float(res),
        )
        v = dict(rc.values)
        cert.update(
            D=v["D"], A_scale=v["A_scale"], Pb=v["Pb"], eig_Pb=v["eig_Pb"], eig_AhtPb_PbAh=v["eig_AhtPb_PbAh"],
            alpha_recheck=v.get("alpha"), equality_residual=v.get("equality_residual"),
            sigma_min_B=v.get("sigma_min_B"), recheck_margin=rc.margin,
        )
    if sol.status not in LMI_SOLVER_OK:
        return _undecided(
            target, sol.t, None,
            f"solver status {sol.status!r} (no KYP certificate; not a proof that H is not SPR)", cert,
        )
    if rc is None:
        return _undecided(target, sol.t, None, "the solver returned no P", cert)
    if not rc.ok and sol.t is not None and sol.t < eps:
        return _undecided(
            target, sol.t, sol.t - eps,
            f"best LMI margin t* = {sol.t:.3g} < eps = {eps:g}: no KYP certificate with margin eps "
            "(not a proof that H is not SPR)", cert,
        )
    if not rc.ok:
        return _undecided(
            target, rc.margin + eps, rc.margin,
            f"the solver's P fails the NumPy re-check: {rc.detail} (not a proof that H is not SPR)", cert,
        )
    return Check(
        name="positive_real", passed=True, target=target, achieved=rc.margin + eps, margin=rc.margin,
        unit="1 (normalised)", detail=f"KYP certificate found and re-checked: {rc.detail}", certificate=cert,
    )


def _transfer(A: np.ndarray, B: np.ndarray, C: np.ndarray, w: float) -> np.ndarray:
    """``H(jw)`` (balanced coordinates for the solve)."""
    c = coordinates([A])
    Ab = A * c.d[None, :] / c.d[:, None]
    X = np.linalg.solve(1j * w * np.eye(A.shape[0]) - Ab, (B / c.d[:, None]).astype(complex))
    return (C * c.d[None, :]) @ X
