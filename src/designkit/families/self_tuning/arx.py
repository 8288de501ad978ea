"""The ARX form of the self-tuner in general orders, and the pole-placement design on it (NumPy, and the same
algebra on CasADi symbols for the law).

**The model** (orders ``na``, ``nb``, delay ``d`` in samples, ``d >= 1``)::

    y(k) = -a1 y(k-1) - ... - a_na y(k-na) + b0 u(k-d) + ... + b_(nb-1) u(k-d-nb+1)

regressor ``phi(k) = [-y(k-1) .. -y(k-na), u(k-d) .. u(k-d-nb+1)]``, ``theta = [a1 .. a_na, b0 .. b_(nb-1)]``.
In the forward shift ``q`` with ``n = max(na, d + nb - 1)``: ``A(q) y = B(q) u``, ``A(q) = q^n + a1 q^(n-1) + ...
+ a_na q^(n-na)``, ``B(q) = b0 q^(n-d) + ... + b_(nb-1) q^(n-d-nb+1)`` (:func:`polynomials`).

**Pole placement** (Astrom and Wittenmark, *Adaptive Control*, 2nd ed., section 3.2, Algorithm 3.1, used at every
sample by the indirect self-tuner of section 3.3): ``R(q) u = T(q) r - S(q) y``.  ``Am`` (degree ``m``, the requested
poles ``z = exp(p h)``) and the observer ``Ao`` (degree ``o``) are given.

* Zeros kept (``B- = B``): ``A R + B S = Am Ao``, ``R`` monic of degree ``m + o - n``, ``S`` of degree ``n - 1``,
  ``T = t0 Ao``, ``t0 = Am(1)/B(1)``: the loop from ``r`` is ``t0 B/Am``.  Causal when ``m >= n`` and
  ``m + o >= 2 n - 1``.
* Zeros cancelled (``B = b0 B+``, ``B+`` monic): ``A R' + b0 S = Am Ao``, ``R = R' B+``, ``T = t0 Ao``,
  ``t0 = Am(1)/b0``: the loop from ``r`` is ``Am(1)/Am`` and ``B+`` is a factor of the characteristic polynomial
  ``A R + B S = B+ Am Ao`` -- the zeros must be well damped.  Causal when ``m >= d`` and ``m + o >= n + d - 1``.

Matching the ``m + o`` coefficients below the leading one gives a square linear system in the coefficients of
``R`` (or ``R'``) and ``S``, the Sylvester matrix of ``A`` and ``B`` (:func:`sylvester`); it is singular exactly when
``A`` and ``B`` (kept zeros) share a root, and its 2-norm condition number says how near they are to it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["EXACT_TOL", "Orders", "Placement", "causality", "controller_degrees", "desired", "link_matrices", "mul",
           "parameter_names", "place", "polynomials", "solve_design", "sylvester", "true_arx", "zoh"]


@dataclass(frozen=True)
class Orders:
    """ARX orders: ``na`` past outputs, ``nb`` input coefficients, delay ``d`` (samples)."""

    na: int
    nb: int
    d: int

    @property
    def n(self) -> int:
        """Degree of ``A(q)`` in the forward shift."""
        return max(self.na, self.d + self.nb - 1)

    @property
    def count(self) -> int:
        """Number of estimated parameters."""
        return self.na + self.nb


def parameter_names(o: Orders) -> tuple[str, ...]:
    """``a1 .. a_na, b0 .. b_(nb-1)``."""
    return (*(f"a{i + 1}" for i in range(o.na)), *(f"b{j}" for j in range(o.nb)))


def mul(p: Sequence[Any], q: Sequence[Any]) -> list[Any]:
    """Product of two polynomials (coefficients highest power first), for numbers or CasADi symbols."""
    out: list[Any] = [0.0] * (len(p) + len(q) - 1)
    for i, a in enumerate(p):
        for j, b in enumerate(q):
            out[i + j] = out[i + j] + a * b
    return out


def polynomials(theta: Sequence[Any], o: Orders) -> tuple[list[Any], list[Any]]:
    """``(A, B)``: ``A(q)`` (length ``n + 1``, monic) and ``B(q)`` (length ``n - d + 1``, leading ``b0``)."""
    n = o.n
    a = list(theta[:o.na])
    b = list(theta[o.na:])
    A = [1.0, *a, *([0.0] * (n - o.na))]
    B = [*b, *([0.0] * (n - o.d - o.nb + 1))]
    return A, B


def desired(poles: Sequence[complex], h: float) -> np.ndarray:
    """``Am(z) = prod (z - exp(p h))`` (highest power first, real), poles in 1/s."""
    return np.real(np.poly([np.exp(complex(p) * h) for p in poles])) if len(poles) else np.array([1.0])


def controller_degrees(o: Orders, m: int, deg_ao: int, cancel: bool) -> tuple[int, int, int]:
    """``(deg R, deg S, deg T)`` of the minimum-degree solution."""
    n = o.n
    rp = m + deg_ao - n
    return (rp + n - o.d if cancel else rp), n - 1, deg_ao


def causality(o: Orders, m: int, deg_ao: int, cancel: bool) -> str | None:
    """Why the requested degrees give no causal controller (None: they do)."""
    n = o.n
    if cancel:
        if m < o.d:
            return f"with the zeros cancelled Am needs at least d = {o.d} poles (deg Am − deg Bm ≥ the delay)"
        if m + deg_ao < n + o.d - 1:
            return (f"with the zeros cancelled deg Am + deg Ao must be at least n + d − 1 = {n + o.d - 1} "
                    f"(n = {n}); give {n + o.d - 1 - m} observer poles or more")
        return None
    if m < n:
        return (f"with the zeros kept Am needs at least n = {n} poles (the loop t0 B/Am must have the plant's pole "
                f"excess); give {n} poles or cancel the zeros")
    if m + deg_ao < 2 * n - 1:
        return (f"with the zeros kept deg Am + deg Ao must be at least 2n − 1 = {2 * n - 1} (n = {n}); give "
                f"{2 * n - 1 - m} observer poles or more")
    return None


def sylvester(A: Sequence[Any], Bm: Sequence[Any], nr: int, ns: int) -> list[list[Any]]:
    """The matrix of ``A R + Bm S`` in the unknowns ``(r1 .. r_nr, s0 .. s_ns)``, rows the coefficients below the
    leading one of a polynomial of degree ``len(A) - 1 + nr`` (``R`` monic of degree ``nr``, ``S`` of degree
    ``ns``)."""
    deg = len(A) - 1 + nr
    N = deg
    rows: list[list[Any]] = [[0.0] * (nr + ns + 1) for _ in range(N)]
    for i in range(1, nr + 1):  # r_i multiplies A q^(nr - i): A[k] lands on the power deg - i - k
        for k, a in enumerate(A):
            row = i + k - 1
            if 0 <= row < N:
                rows[row][i - 1] = a
    lb = len(Bm) - 1
    for j in range(ns + 1):  # s_j multiplies Bm q^(ns - j): Bm[k] lands on the power lb + ns - j - k
        for k, b in enumerate(Bm):
            row = deg - (lb + ns - j - k) - 1
            if 0 <= row < N:
                rows[row][nr + j] = b
    return rows


@dataclass(frozen=True)
class Placement:
    """A controller ``R u = T r - S y`` (coefficients highest power first) and the design's conditioning.

    Attributes
    ----------
    R, S, T : tuple of float
        ``R`` monic.
    condition : float
        2-norm condition number of the Sylvester matrix solved.
    characteristic : tuple of float
        ``A R + B S`` of the model designed on.
    """

    R: tuple[float, ...]
    S: tuple[float, ...]
    T: tuple[float, ...]
    condition: float
    characteristic: tuple[float, ...]


def solve_design(theta: Sequence[Any], o: Orders, am: Sequence[float], ao: Sequence[float], cancel: bool,
                 solve: Callable[[list[list[Any]], list[Any]], Sequence[Any]]) -> tuple[list[Any], list[Any],
                                                                                       list[Any], list[list[Any]]]:
    """``(R, S, T, M)`` for ``theta`` with the linear solver ``solve(M, rhs)`` (NumPy or CasADi)."""
    A, B = polynomials(theta, o)
    n, m, deg_ao = o.n, len(am) - 1, len(ao) - 1
    rp = m + deg_ao - n
    acl = [float(v) for v in np.polymul(am, ao)]
    Bm = [B[0]] if cancel else B
    M = sylvester(A, Bm, rp, n - 1)
    # right side: the coefficients of Acl below its leading one minus those of A q^rp
    Aq = [*A, *([0.0] * rp)]
    rhs = [acl[k] - Aq[k] for k in range(1, len(acl))]
    x = solve(M, rhs)
    Rp = [1.0, *[x[i] for i in range(rp)]]
    S = [x[rp + j] for j in range(n)]
    if cancel:
        Bplus = [b / B[0] for b in B]
        R = mul(Rp, Bplus)
        t0 = sum(am) / B[0]
    else:
        R = Rp
        t0 = sum(am) / sum(B)
    T = [t0 * c for c in ao]
    return R, S, T, M


def place(theta: Sequence[float], o: Orders, am: Sequence[float], ao: Sequence[float], cancel: bool) -> Placement:
    """The pole-placement controller for the model ``theta`` (module docstring), NumPy."""
    def solve(M: list[list[Any]], rhs: list[Any]) -> np.ndarray:
        return np.linalg.solve(np.asarray(M, dtype=float), np.asarray(rhs, dtype=float))

    R, S, T, M = solve_design([float(v) for v in theta], o, am, ao, cancel, solve)
    A, B = polynomials([float(v) for v in theta], o)
    char = np.polyadd(np.polymul(A, R), np.polymul(B, S))
    return Placement(tuple(float(v) for v in R), tuple(float(v) for v in S), tuple(float(v) for v in T),
                     float(np.linalg.cond(np.asarray(M, dtype=float))), tuple(float(v) for v in char))


def zoh(F: np.ndarray, G: np.ndarray, C: np.ndarray, D: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """``(den, num)`` of the first output's pulse transfer function from the (single) input, the continuous plant
    ``x' = F x + G u``, ``y = C x + D u`` sampled at ``h`` with a zero-order hold (``den`` monic, both of length
    ``N + 1``, highest power first)."""
    from scipy.linalg import expm

    N = F.shape[0]
    big = np.zeros((N + 1, N + 1))
    big[:N, :N], big[:N, N:] = F * h, np.asarray(G, dtype=float).reshape(N, 1) * h
    E = expm(big)
    Ad, Bd = E[:N, :N], E[:N, N]
    c = np.asarray(C, dtype=float).reshape(-1)[:N]
    dd = float(np.asarray(D, dtype=float).reshape(-1)[0]) if np.size(D) else 0.0
    den = np.real(np.poly(np.linalg.eigvals(Ad)))
    # num(z) = c adj(zI - Ad) Bd + dd den(z), through Faddeev-LeVerrier on Ad
    num = np.zeros(N + 1)
    Nk = np.eye(N)
    num[1] = c @ Nk @ Bd
    for k in range(1, N):
        Nk = Ad @ Nk + den[k] * np.eye(N)
        num[k + 1] = c @ Nk @ Bd
    return den, num + dd * den


EXACT_TOL = 1e-9
"""Relative size below which a coefficient of the sampled plant counts as zero (orders holding it)."""


def true_arx(F: np.ndarray, G: np.ndarray, C: np.ndarray, D: np.ndarray, h: float, o: Orders) -> np.ndarray | None:
    """The exact ARX parameters of the continuous plant sampled at ``h`` in the orders ``o``, or None when the
    orders do not hold it (``na`` not the plant's order, or a nonzero input coefficient outside the delays
    ``d .. d + nb - 1``)."""
    den, num = zoh(F, G, C, D, h)
    N = len(den) - 1
    if o.na != N:
        return None
    scale = max(float(np.max(np.abs(num))), 1e-300)
    b = []
    for j in range(N + 1):  # num[j] is the coefficient of u(k - j)
        inside = o.d <= j <= o.d + o.nb - 1
        if not inside and abs(num[j]) > EXACT_TOL * scale:
            return None
    for j in range(o.d, o.d + o.nb):
        b.append(float(num[j]) if j <= N else 0.0)
    return np.array([*(float(v) for v in den[1:]), *b])


def link_matrices(Km: float, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(F, G, C, D)`` of the link ``x1' = x2``, ``x2' = -x2/tau + (Km/tau) u``, ``y = x1``."""
    return (np.array([[0.0, 1.0], [0.0, -1.0 / tau]]), np.array([0.0, Km / tau]), np.array([[1.0, 0.0]]),
            np.zeros((1, 1)))
