"""The one LMI core: balanced coordinates, the normalised max-margin LMI, and its NumPy re-check.

Both the Lyapunov checks (:mod:`designkit.verification.lyapunov`) and the positive-real check
(:mod:`designkit.verification.kyp`) solve the same problem, optionally with one equality::

    maximise    t
    subject to  t I <= Pb <= I,
                Ah_i' Pb + Pb Ah_i <= -t I            (every i),
                Pb Bn = alpha Cn',  alpha >= t         (KYP only)

Normalisation, in steps that change no feasibility:

- ``D`` is a diagonal of powers of two balancing ``sum_i |A_i|`` (LAPACK ``gebal`` through
  :func:`scipy.linalg.matrix_balance`), so ``D^-1 A D`` is computed *exactly*.  With ``x = D z``,
  ``A -> D^-1 A D``, ``B -> D^-1 B``, ``C -> C D`` and ``P -> Pb = D P D``.  The PID closed loops
  have entries from 1 to ``p^2`` (poles ``p`` in 1/s); without balancing the best margin for poles
  near -100 1/s is below 1e-9 and no check could pass.
- ``s = max_i ||D^-1 A_i D||_2`` (1/s): the inequalities are homogeneous in ``A``, so the margin
  becomes dimensionless, ``Ah_i = D^-1 A_i D / s``.
- ``Pb <= I`` bounds the problem: every constraint is homogeneous in ``(Pb, alpha, t)``.
- KYP only: ``Bn = D^-1 B / ||D^-1 B||_2`` and ``Cn = C D / ||C D||_2``, and the equality
  ``P B = C'`` is made homogeneous with a free ``alpha``: ``H`` is strictly positive real iff
  ``alpha H`` is, for any ``alpha > 0``.  The user's ``P`` (with ``P B = C'`` exactly) is
  ``D^-1 Pb D^-1 * ||C D|| / (alpha ||D^-1 B||)``.

``t >= eps`` then means a certificate whose condition number is at most ``1/eps`` in the
balanced coordinates.

Who decides.  The solver's status is only a precondition.  A certificate is re-checked with
NumPy from the *original* data: ``P`` is moved to the balanced coordinates, symmetrised and
divided by its largest eigenvalue, and the eigenvalues of ``Pb`` and of
``Ah_i'Pb + Pb Ah_i`` are recomputed; the statement holds iff ``eig(Pb) >= eps`` and
``eig(Ah_i'Pb + Pb Ah_i) <= -eps`` (plus, for KYP, the equality to :data:`KYP_EQ_TOL` and a
full-column-rank ``B``).  :class:`LyapunovCertificate` and :class:`KypCertificate` carry that
re-check (:mod:`designkit.verification.certificate`).

cvxpy is imported inside the solving functions only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import scipy.linalg

from designkit.verification.certificate import Recheck, array_from_json, to_json
from designkit.verification.tolerances import KYP_EQ_TOL, LMI_EPS

# ----------------------------------------------------------------------------- coordinates


@dataclass(frozen=True)
class Coordinates:
    """Balanced, scaled coordinates shared by the LMI and its re-check.

    Parameters
    ----------
    d : ndarray, shape (n,)
        Diagonal of ``D`` (powers of two); ``x = D z``.
    scale : float
        ``s = max_i ||D^-1 A_i D||_2`` (1/s).
    Ah : tuple of ndarray
        ``D^-1 A_i D / s`` (dimensionless).
    """

    d: np.ndarray
    scale: float
    Ah: tuple[np.ndarray, ...]

    def to_balanced(self, P: np.ndarray) -> np.ndarray:
        """``D P D`` (exact: ``d`` holds powers of two)."""
        return (np.asarray(P, dtype=float) * self.d[None, :]) * self.d[:, None]

    def from_balanced(self, Pb: np.ndarray) -> np.ndarray:
        """``D^-1 Pb D^-1``."""
        return np.asarray(Pb, dtype=float) / self.d[None, :] / self.d[:, None]


def coordinates(As: Sequence[np.ndarray]) -> Coordinates:
    """The common balancing ``D`` and scale ``s`` of the matrices ``A_i`` (see module docstring)."""
    As = [np.asarray(A, dtype=float) for A in As]
    _, T = scipy.linalg.matrix_balance(sum(np.abs(A) for A in As), permute=False, separate=True)
    d = np.asarray(T[0], dtype=float) if isinstance(T, tuple) else np.diag(T)
    Ab = [A * d[None, :] / d[:, None] for A in As]  # exact: d holds powers of two
    s = max(float(np.linalg.norm(A, 2)) for A in Ab)
    s = s if s > 0 else 1.0
    return Coordinates(d=d, scale=s, Ah=tuple(A / s for A in Ab))


def symmetrise(M: np.ndarray) -> np.ndarray:
    """``(M + M') / 2``."""
    M = np.asarray(M, dtype=float)
    return 0.5 * (M + M.T)


def unstable_eigenvalue(A: np.ndarray) -> complex | None:
    """The eigenvalue of ``A`` with the largest real part if that part is ``>= 0``, else None."""
    ev = np.linalg.eigvals(np.asarray(A, dtype=float))
    k = int(np.argmax(ev.real))
    return complex(ev[k]) if ev[k].real >= 0 else None


# ----------------------------------------------------------------------------- NumPy re-check


@dataclass(frozen=True)
class LyapunovRecheck:
    """NumPy re-check of a candidate ``P`` for matrices ``A_i``.

    Parameters
    ----------
    Pb : ndarray
        ``D P D`` symmetrised and divided by its largest eigenvalue (balanced coordinates).
    eig_P : ndarray
        Eigenvalues of ``Pb`` (ascending; the largest is 1).
    eig_lyap : tuple of ndarray
        Eigenvalues of ``Ah_i'Pb + Pb Ah_i`` for each ``i`` (ascending, dimensionless).
    coords : Coordinates
    margin : float
        ``min(min eig_P, -max eig_lyap) - eps``: non-negative iff the certificate holds with margin eps.
    ok : bool
        ``margin >= 0``.
    top : float
        Largest eigenvalue of ``D P D`` before the division (the normalising factor; NaN when
        ``P`` is not finite).
    """

    Pb: np.ndarray
    eig_P: np.ndarray
    eig_lyap: tuple[np.ndarray, ...]
    coords: Coordinates
    margin: float
    ok: bool
    top: float = float("nan")


def lyapunov_recheck(As: Sequence[np.ndarray], P: np.ndarray, *, eps: float = LMI_EPS) -> LyapunovRecheck:
    """Is ``x'Px`` a Lyapunov function of every ``x' = A_i x`` with margin ``eps``?  (NumPy only.)

    ``P`` (original coordinates, any positive scale) is moved to the balanced coordinates,
    ``Pb = D P D``, symmetrised and divided by its largest eigenvalue (the LMI's ``Pb <= I``), so
    certificates from any route (solver, Lyapunov equation, a file) are judged on the same
    footing: ``eig(Pb) >= eps`` and ``eig(Ah_i'Pb + Pb Ah_i) <= -eps``.
    """
    c = coordinates(As)
    P = np.asarray(P, dtype=float)
    Pb = symmetrise(c.to_balanced(P))
    top = float(np.max(np.linalg.eigvalsh(Pb))) if np.all(np.isfinite(Pb)) else float("nan")
    if not np.isfinite(top) or top <= 0:
        nan = np.full(len(P), np.nan)
        return LyapunovRecheck(Pb, nan, tuple(nan for _ in c.Ah), c, -np.inf, False, top)
    Pb = Pb / top
    eig_P = np.linalg.eigvalsh(Pb)
    eig_l = [np.linalg.eigvalsh(symmetrise(Ah.T @ Pb + Pb @ Ah)) for Ah in c.Ah]
    worst = min(float(eig_P[0]), min(-float(e[-1]) for e in eig_l))
    margin = worst - eps
    return LyapunovRecheck(Pb, eig_P, tuple(eig_l), c, margin, bool(margin >= 0), top)


# ----------------------------------------------------------------------------- the solve


@dataclass(frozen=True)
class MarginSolution:
    """Raw outcome of the normalised max-margin LMI (balanced coordinates, before any re-check).

    Parameters
    ----------
    Pb : ndarray or None
        Symmetrised ``Pb`` (balanced, ``Pb <= I``); None when the solver returned none.
    t : float or None
        Optimal margin ``t`` (dimensionless).
    alpha : float or None
        Multiplier of the homogeneous equality (KYP only).
    status : str
        cvxpy status (``"optimal"``, ``"optimal_inaccurate"``, ``"infeasible"``, ``"solver_error: ..."``).
    solver : str
    """

    Pb: np.ndarray | None
    t: float | None
    alpha: float | None
    status: str
    solver: str


def solve_margin_lmi(
    Ah: Sequence[np.ndarray],
    *,
    solver: str = "CLARABEL",
    equality: tuple[np.ndarray, np.ndarray] | None = None,
) -> MarginSolution:
    """Solve the normalised LMI of the module docstring with cvxpy.

    Parameters
    ----------
    Ah : sequence of ndarray, shape (n, n)
        Balanced, scaled state matrices (dimensionless).
    solver : str
        cvxpy solver name.
    equality : (Bn, Cn) or None
        Adds ``Pb Bn = alpha Cn'`` with ``alpha >= t`` (``Bn`` n x m, ``Cn`` m x n).

    Notes
    -----
    Solved in the solver process when the command line started one
    (:mod:`designkit.verification.solver_process`: the same function, run where cvxpy was imported
    ahead of time), else here.
    """
    from designkit.verification import solver_process

    done, remote = solver_process.call("margin_lmi", Ah, solver=solver, equality=equality)
    if done:
        return remote
    cp = solver_process.cvxpy()

    n = Ah[0].shape[0]
    eye = np.eye(n)
    Pb = cp.Variable((n, n), symmetric=True)
    t = cp.Variable()
    cons = [Pb >> t * eye, Pb << eye]
    for M in Ah:
        L = M.T @ Pb + Pb @ M
        cons.append(0.5 * (L + L.T) << -t * eye)
    alpha = None
    if equality is not None:
        Bn, Cn = equality
        alpha = cp.Variable()
        cons += [Pb @ Bn == alpha * Cn.T, alpha >= t]
    prob = cp.Problem(cp.Maximize(t), cons)
    try:
        prob.solve(solver=solver)
    except cp.error.SolverError as exc:
        return MarginSolution(None, None, None, f"solver_error: {exc}", solver)
    P = None if Pb.value is None else symmetrise(np.array(Pb.value, dtype=float))
    tv = None if t.value is None else float(t.value)
    av = None if alpha is None or alpha.value is None else float(alpha.value)
    return MarginSolution(P, tv, av, str(prob.status), solver)


@dataclass(frozen=True)
class LmiSolution:
    """Raw outcome of the Lyapunov LMI (before the NumPy re-check).

    Parameters
    ----------
    P : ndarray or None
        Solution in the *original* coordinates, ``P = D^-1 Pb D^-1``; None when the solver
        returned none.
    t : float or None
        Optimal margin ``t`` reported by the solver (dimensionless).
    status : str
        cvxpy status (``"optimal"``, ``"optimal_inaccurate"``, ``"infeasible"``, ``"solver_error: ..."``).
    solver : str
    """

    P: np.ndarray | None
    t: float | None
    status: str
    solver: str


def solve_lyapunov(As: Sequence[np.ndarray], *, solver: str = "CLARABEL") -> LmiSolution:
    """Common-Lyapunov LMI for the ``A_i`` (no equality); ``P`` returned in original coordinates."""
    c = coordinates(As)
    sol = solve_margin_lmi(c.Ah, solver=solver)
    P = None if sol.Pb is None else c.from_balanced(sol.Pb)
    return LmiSolution(P, sol.t, sol.status, solver)


@dataclass(frozen=True)
class KypScaling:
    """Balanced, normalised data of a KYP problem (see module docstring).

    Parameters
    ----------
    coords : Coordinates
        Balancing of ``A`` (``Ah = D^-1 A D / s``).
    Bn, Cn : ndarray
        ``D^-1 B / beta`` and ``C D / gamma``.
    beta, gamma : float
        ``||D^-1 B||_2`` and ``||C D||_2`` (units of ``B`` and ``C``).
    """

    coords: Coordinates
    Bn: np.ndarray
    Cn: np.ndarray
    beta: float
    gamma: float


def kyp_scaling(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> KypScaling:
    """The coordinates shared by the KYP LMI and its re-check."""
    c = coordinates([A])
    Bb = np.asarray(B, dtype=float) / c.d[:, None]
    Cb = np.asarray(C, dtype=float) * c.d[None, :]
    beta, gamma = float(np.linalg.norm(Bb, 2)), float(np.linalg.norm(Cb, 2))
    beta, gamma = (beta if beta > 0 else 1.0), (gamma if gamma > 0 else 1.0)
    return KypScaling(c, Bb / beta, Cb / gamma, beta, gamma)


@dataclass(frozen=True)
class KypSolution:
    """Raw outcome of the KYP LMI (before the NumPy re-check).

    Parameters
    ----------
    P : ndarray or None
        Original coordinates, scaled so that ``P B = C'`` (up to the solver's accuracy).
    t : float or None
        Optimal margin (dimensionless).
    alpha : float or None
        Multiplier of ``Pb Bn = alpha Cn'`` in the normalised problem.
    status : str
    solver : str
    """

    P: np.ndarray | None
    t: float | None
    alpha: float | None
    status: str
    solver: str


def solve_kyp(A: np.ndarray, B: np.ndarray, C: np.ndarray, *, solver: str = "CLARABEL") -> KypSolution:
    """The normalised KYP LMI (``Pb Bn = alpha Cn'``, ``alpha >= t``) of the module docstring."""
    k = kyp_scaling(A, B, C)
    sol = solve_margin_lmi(k.coords.Ah, solver=solver, equality=(k.Bn, k.Cn))
    P = None
    if sol.Pb is not None and sol.alpha is not None and sol.alpha > 0:
        P = k.coords.from_balanced(sol.Pb) * (k.gamma / (sol.alpha * k.beta))
    return KypSolution(P, sol.t, sol.alpha, sol.status, solver)


# ----------------------------------------------------------------------------- certificates


def _readonly(x: Any) -> np.ndarray:
    a = np.array(x, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class LyapunovCertificate:
    """``x'Px`` is a common Lyapunov function of ``x' = A_i x`` (every ``i``).

    Parameters
    ----------
    As : tuple of ndarray, shape (n, n)
        State matrices (1/s).
    P : ndarray, shape (n, n)
        Candidate (original coordinates, any positive scale).
    eps : float
        Margin of the strict inequalities in the normalised problem (module docstring).
    """

    kind: ClassVar[str] = "lyapunov"
    As: tuple[np.ndarray, ...]
    P: np.ndarray
    eps: float = LMI_EPS

    def __post_init__(self) -> None:
        object.__setattr__(self, "As", tuple(_readonly(A) for A in self.As))
        object.__setattr__(self, "P", _readonly(self.P))
        object.__setattr__(self, "eps", float(self.eps))

    def details(self) -> LyapunovRecheck:
        """The full NumPy re-check (balanced ``Pb`` and all eigenvalues)."""
        return lyapunov_recheck(self.As, self.P, eps=self.eps)

    def recheck(self) -> Recheck:
        """``eig(Pb) >= eps`` and ``eig(Ah_i'Pb + Pb Ah_i) <= -eps`` for every ``i`` (NumPy)."""
        rc = self.details()
        values = {
            "D": rc.coords.d,
            "A_scale": rc.coords.scale,
            "Pb": rc.Pb,
            "eig_Pb": rc.eig_P,
            "eig_AhtPb_PbAh": list(rc.eig_lyap),
            "recheck_margin": rc.margin,
        }
        if not np.isfinite(rc.top) or rc.top <= 0:
            detail = "P is not finite or has no positive eigenvalue"
        else:
            which = f"hold with margin {rc.margin:.3g}" if rc.ok else f"fail by {-rc.margin:.3g}"
            detail = (
                f"Lyapunov inequalities {which} (eps = {self.eps:g}): min eig Pb = {rc.eig_P[0]:.3g}, "
                f"max eig(Ah'Pb + Pb Ah) = {max(float(e[-1]) for e in rc.eig_lyap):.3g}"
            )
        return Recheck(rc.ok, rc.margin, detail, values)

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable data (``kind``, ``A``, ``P``, ``eps``)."""
        return {"kind": self.kind, "A": to_json(list(self.As)), "P": to_json(self.P), "eps": self.eps}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> LyapunovCertificate:
        """Inverse of :meth:`to_dict`."""
        return cls(tuple(array_from_json(A) for A in data["A"]), array_from_json(data["P"]), float(data["eps"]))


@dataclass(frozen=True)
class KypCertificate:
    """``H(s) = C (sI - A)^-1 B`` is strictly positive real, by the KYP lemma.

    Statement re-checked (NumPy, normalised problem of the module docstring, ``Pn`` the balanced
    ``D P D`` divided by its largest eigenvalue, ``alpha = ||C D|| / (lambda_max ||D^-1 B||)``
    the multiplier that ``P B = C'`` implies):

    - ``eig(Pn) >= eps`` and ``eig(Ah'Pn + Pn Ah) <= -eps`` (``P > 0``, ``A'P + PA < 0``);
    - ``sigma_min(Bn) >= eps`` (``B`` has full column rank; otherwise ``H v = 0`` for some ``v``);
    - ``alpha >= eps`` and ``||Pn Bn - alpha Cn'|| / (||Pn|| ||Bn|| + alpha ||Cn||) <= eq_tol``
      (``P B = C'``; the relative residual is the backward error of the equation).

    The re-check's margin is the smallest slack of the three inequalities (dimensionless); the
    equality's slack ``eq_tol - residual`` replaces it only when negative.

    Then ``H(jw) + H(jw)^* = (Phi B)^* Q (Phi B) > 0`` with ``Phi = (jwI - A)^-1`` and
    ``Q = -(A'P + PA) > 0``, and ``lim w^2 (H + H^*) = B'QB > 0``: ``H`` is SPR.

    Parameters
    ----------
    A, B, C : ndarray
        Realisation (``A`` n x n in 1/s, ``B`` n x m, ``C`` m x n).
    P : ndarray, shape (n, n)
        Candidate with ``P B = C'``.
    eps : float
        Margin of the strict inequalities (normalised problem).
    eq_tol : float
        Tolerance of the relative residual of ``P B = C'``.
    """

    kind: ClassVar[str] = "kyp"
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    P: np.ndarray
    eps: float = LMI_EPS
    eq_tol: float = KYP_EQ_TOL

    def __post_init__(self) -> None:
        for name in ("A", "B", "C", "P"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))
        object.__setattr__(self, "eps", float(self.eps))
        object.__setattr__(self, "eq_tol", float(self.eq_tol))

    def recheck(self) -> Recheck:
        """The four conditions of the class docstring, with NumPy only."""
        lyap = lyapunov_recheck([self.A], self.P, eps=self.eps)
        k = kyp_scaling(self.A, self.B, self.C)
        values: dict[str, Any] = {
            "D": k.coords.d,
            "A_scale": k.coords.scale,
            "Pb": lyap.Pb,
            "eig_Pb": lyap.eig_P,
            "eig_AhtPb_PbAh": lyap.eig_lyap[0],
        }
        if not np.isfinite(lyap.top) or lyap.top <= 0:
            return Recheck(False, -np.inf, "P is not finite or has no positive eigenvalue", values)
        alpha = k.gamma / (lyap.top * k.beta)
        E = lyap.Pb @ k.Bn - alpha * k.Cn.T
        scale = float(np.linalg.norm(lyap.Pb, 2) * np.linalg.norm(k.Bn, 2) + alpha * np.linalg.norm(k.Cn, 2))
        residual = float(np.linalg.norm(E, 2) / scale)
        sigma_b = float(np.linalg.svd(k.Bn, compute_uv=False)[-1])
        slacks = {
            "lyapunov": lyap.margin,
            "rank_B": sigma_b - self.eps,
            "alpha": alpha - self.eps,
            "equality": self.eq_tol - residual,
        }
        # the margin is that of the inequalities (dimensionless, comparable); the equality is a
        # gate that only enters when it fails, so the margin stays non-negative iff all hold
        gates = ["lyapunov", "rank_B", "alpha"] + ([] if slacks["equality"] >= 0 else ["equality"])
        margin = float(np.min([slacks[key] for key in gates]))  # NaN propagates: never ok
        worst = min(gates, key=lambda key: slacks[key] if np.isfinite(slacks[key]) else -np.inf)
        values.update(
            alpha=alpha, equality_residual=residual, sigma_min_B=sigma_b, slacks=slacks, recheck_margin=margin
        )
        ok = bool(margin >= 0)
        detail = (
            f"KYP conditions hold: margin {margin:.3g} (tightest: {worst}), residual of P B = C' {residual:.2g}"
            if ok
            else f"KYP condition {worst!r} fails by {-slacks[worst]:.3g} (residual of P B = C' {residual:.2g})"
        )
        return Recheck(ok, margin, detail, values)

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable data (``kind``, ``A``, ``B``, ``C``, ``P``, ``eps``, ``eq_tol``)."""
        out: dict[str, Any] = {"kind": self.kind}
        out.update({name: to_json(getattr(self, name)) for name in ("A", "B", "C", "P")})
        out.update(eps=self.eps, eq_tol=self.eq_tol)
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> KypCertificate:
        """Inverse of :meth:`to_dict`."""
        mats = [array_from_json(data[name]) for name in ("A", "B", "C", "P")]
        return cls(*mats, eps=float(data["eps"]), eq_tol=float(data["eq_tol"]))
