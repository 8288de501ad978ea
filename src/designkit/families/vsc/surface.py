"""The sliding surface ``sigma = c x`` from requested sliding poles, and the plant's linear model in its parameters.

**Linear model.**  ``x' = A(p) x + B(p) u + D(p) d`` is the plant's ODE linearised at the rest state ``x = 0``,
``u = 0``, ``d = 0`` by CasADi, kept symbolic in the plant parameters ``p`` (:func:`linear_model`), so that the
gains' bounds ``l_i(p)`` are CasADi expressions over the uncertainty box.

**c from the sliding poles** (an Ackermann formula for the sliding surface).  Let ``W = [B, AB, ..., A^(n-1) B]``
(controllable: ``W`` invertible), ``e = [0 ... 0 1] W^-1`` (so ``e A^k B = 0`` for ``k < n-1`` and
``e A^(n-1) B = 1``) and ``P(s) = prod (s - p_j)`` the monic polynomial of the ``n - 1`` requested poles.  Then

    c = e P(A)        gives        c B = e A^(n-1) B = 1,

and on ``c x = 0`` the motion under the equivalent control ``u_eq = -(cB)^-1 c A x`` has exactly the poles
``p_j``.  *Proof.*  For any ``lambda`` the state feedback ``u = -(cB)^-1 c (A - lambda I) x`` gives
``sigma' = c A x + c B u = lambda sigma``; it is Ackermann's gain ``e Q(A)`` of the polynomial
``Q(s) = P(s)(s - lambda)`` (``e Q(A) = c (A - lambda I)``), so the closed loop's poles are the roots of ``Q``:
``lambda`` (the motion of ``sigma``) and the ``p_j``.  The subspace ``c x = 0`` is invariant under that loop and
the loop equals ``x' = (I - B c/(cB)) A x`` on it, the sliding motion; so its poles are the ``p_j``.  (The tests
check it independently: the eigenvalues of ``N^+ (I - B c/(cB)) A N`` with ``N`` a basis of ``ker c``, numpy.)

**Normalisation.**  ``c`` is scaled so that its entry on the state the input drives (the single nonzero entry of
``B``: the motor speed ``x2`` of the elastic joint, the link speed ``x2``) is 1; then ``cB > 0``, the orientation
the gain conditions are written for.  Without such an entry (a general ``B``) ``c`` is scaled to ``cB = 1``.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

__all__ = ["CONTROLLABILITY_TOL", "LinearModel", "controllability_ratio", "linear_model", "reduced_poles",
           "sliding_surface"]

CONTROLLABILITY_TOL = 1e-10
"""``(A, B)`` is treated as uncontrollable when ``|det W| / prod ||W_k||`` (Hadamard's ratio of the controllability
matrix, 1 for orthogonal columns) is below this: the surface would rest on a numerically singular ``W``."""


@dataclass(frozen=True, eq=False)
class LinearModel:
    """``x' = A(p) x + B(p) u + D(p) d`` at rest, symbolic in the plant parameters.

    Attributes
    ----------
    names : tuple of str
        Parameter names, in the plant's order.
    p : casadi.SX
        Their symbols.
    A, B, D : casadi.SX
        ``n x n``, ``n x 1`` and ``n x n_d`` in ``p`` (units of the plant's states per state, input, disturbance).
    nominal : numpy.ndarray
        The plant's parameter values.
    """

    names: tuple[str, ...]
    p: ca.SX
    A: ca.SX
    B: ca.SX
    D: ca.SX
    nominal: np.ndarray

    @functools.cached_property
    def _numeric(self) -> ca.Function:
        return ca.Function("abd", [self.p], [self.A, self.B, self.D])

    def at(self, values: dict[str, float] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, D)`` as arrays at the nominal parameters with ``values`` replaced."""
        pv = self.nominal.copy()
        for k, v in (values or {}).items():
            pv[self.names.index(k)] = float(v)
        return tuple(np.array(m, dtype=float) for m in self._numeric(pv))  # type: ignore[return-value]


def linear_model(plant: object) -> LinearModel:
    """The plant's ODE linearised at rest (``x = 0``, ``u = 0``, ``d = 0``), symbolic in its parameters."""
    f = plant.ode()  # type: ignore[attr-defined]
    n, nd = f.size1_in(0), f.size1_in(2)
    x, u, d = ca.SX.sym("x", n), ca.SX.sym("u", f.size1_in(1)), ca.SX.sym("d", nd)
    names = tuple(par.name for par in plant.parameters)  # type: ignore[attr-defined]
    p = ca.SX.sym("p", len(names))
    xdot = f(x, u, d, p)
    at_rest = {"x": ca.DM.zeros(n), "u": ca.DM.zeros(u.numel()), "d": ca.DM.zeros(nd)}
    mats = []
    for var in (x, u, d):
        jac = ca.jacobian(xdot, var)
        mats.append(ca.substitute([jac], [x, u, d], [at_rest["x"], at_rest["u"], at_rest["d"]])[0])
    return LinearModel(names, p, *mats, np.asarray(plant.parameter_vector, dtype=float))  # type: ignore[attr-defined]


def controllability_matrix(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``[B, AB, ..., A^(n-1) B]`` (single input)."""
    n = A.shape[0]
    cols = [np.asarray(B, float).reshape(n)]
    for _ in range(n - 1):
        cols.append(A @ cols[-1])
    return np.column_stack(cols)


def controllability_ratio(A: np.ndarray, B: np.ndarray) -> float:
    """Hadamard's ratio ``|det W| / prod ||W_k||`` in ``[0, 1]`` (0: uncontrollable)."""
    W = controllability_matrix(A, B)
    norms = np.linalg.norm(W, axis=0)
    if np.any(norms == 0):
        return 0.0
    return float(abs(np.linalg.det(W / norms)))


def drive_index(B: np.ndarray) -> int | None:
    """The state the input drives, when ``B`` has exactly one nonzero entry; else None."""
    nz = np.flatnonzero(np.asarray(B, float).reshape(-1))
    return int(nz[0]) if nz.size == 1 else None


def sliding_surface(A: np.ndarray, B: np.ndarray, poles: Sequence[complex]) -> np.ndarray:
    """``c`` (row, length ``n``) whose sliding motion on ``c x = 0`` has the ``n - 1`` poles ``poles``.

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (1/s, 1/s^2 by row).
    B : numpy.ndarray
        ``n x 1``.
    poles : sequence of complex
        ``n - 1`` poles (1/s), complex ones in conjugate pairs.

    Returns
    -------
    numpy.ndarray
        ``c`` normalised as the module docstring says (``cB > 0``).

    Raises
    ------
    ValueError
        Wrong number of poles, or ``(A, B)`` uncontrollable (:data:`CONTROLLABILITY_TOL`).
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    B = np.asarray(B, float).reshape(n)
    if len(poles) != n - 1:
        raise ValueError(f"needs {n - 1} sliding poles for {n} states, got {len(poles)}")
    if controllability_ratio(A, B) < CONTROLLABILITY_TOL:
        raise ValueError("(A, B) is not controllable")
    W = controllability_matrix(A, B)
    e = np.linalg.solve(W.T, np.eye(n)[n - 1])
    coeffs = np.real_if_close(np.poly(np.asarray(poles, complex))).real  # monic, degree n-1
    P = np.zeros((n, n))
    for k in coeffs:  # Horner: P(A) = (...((A + a1) A + a2) ...)
        P = P @ A + k * np.eye(n)
    c = e @ P
    k = drive_index(B)
    scale = c[k] if k is not None and c[k] != 0 else c @ B
    c = c / scale
    if c @ B < 0:  # cannot happen with a drive index (c_k = 1, B_k > 0 there); kept for a general B
        c = -c
    return c


def reduced_poles(A: np.ndarray, B: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Poles of the sliding motion on ``c x = 0``: eigenvalues of ``N^+ (I - B c/(cB)) A N``, ``N`` an orthonormal
    basis of ``ker c`` (numpy SVD), sorted by real part."""
    A = np.asarray(A, float)
    n = A.shape[0]
    B = np.asarray(B, float).reshape(n, 1)
    c = np.asarray(c, float).reshape(1, n)
    _, _, vt = np.linalg.svd(c)
    N = vt[1:].T
    proj = np.eye(n) - B @ c / float((c @ B)[0, 0])
    eig = np.linalg.eigvals(N.T @ proj @ A @ N)
    return eig[np.lexsort((eig.imag, eig.real))]
