"""The lifted (finite-horizon) error system of learning on computed torque, per joint, with its structure.

**The sampled error system.**  With an exact model the computed-torque law with a trial's feedforward ``v``
(rad/s^2, entering as ``M^(q) v``) makes every joint's acceleration ``q'' = qD'' + K1 (qD - q) + K2 (qD' - qd)
+ v``: the closed loop is *affine* in ``x = (q, qd)`` per joint, whatever the arm.  The simulator holds ``v_i``
over the step ``[t_i, t_i + dt]`` and integrates with RK4 (the reference enters at the stages, the same in every
trial), so the difference between two trials obeys exactly the RK4 map of ``x' = A x + B v``::

    A = [[0, 1], [-K1, -K2]],  B = [0, 1]^T,  hA = dt A
    Phi   = I + hA + (hA)^2/2 + (hA)^3/6 + (hA)^4/24            (RK4's polynomial of hA)
    Gamma = dt (I + hA/2 + (hA)^2/6 + (hA)^3/24) B              (the same with v held over the step)
    dx_{i+1} = Phi dx_i + Gamma dv_i,   dq_i = C dx_i,  C = [1, 0]

(with CVODES, the exact zero-order hold: ``expm([[A, B], [0, 0]] dt)``).  The error is sampled at the step
starts ``t_0 .. t_{N-1}``: ``e_0`` never depends on ``v`` (the arm starts where it starts) and ``v_{N-1}`` moves no
recorded sample, so the square lifted map is ``v_0 .. v_{N-2} -> e_1 .. e_{N-1}`` (``L = N - 1`` samples): the
lower-triangular Toeplitz matrix of the *shifted* Markov parameters ``h_m = C Phi^m Gamma``, ``m = 0 .. L-1``.
Its diagonal ``h_0 = C Gamma = dt^2/2 - K2 dt^3/6 + ... != 0`` (the sampled relative degree is one step), so
``H`` is invertible, ``det H = h_0^L``.  Between trials ``e_k - e_{k+1} = H (d_{k+1} - d_k)`` per joint
(``e = qD - q``), the notes' ``e_k = H (d - d_k)`` in lifted form.

**Structure.**  ``H`` is never formed: a joint's ``L`` Markov parameters (and those of ``H^-1``, the power
series of ``1/a``) are computed by :func:`scipy.signal.lfilter` on the second-order transfer function, products
by FFT convolution (``H^T = J H J`` with ``J`` the reversal), ``O(L log L)`` per product, ``O(L)`` memory.

**Norms.**  ``sigma_max(H)`` is estimated by Lanczos (ARPACK ``svds`` on a ``LinearOperator``), re-checked by a
power iteration on ``H^T H``, and bracketed rigorously: below by ``||H u||`` for the computed unit vector ``u``,
above by ``min(sum |h_m|, sup |a|)`` where ``a(w) = sum h_m e^{-imw}`` is the symbol (a finite Toeplitz matrix
is a compression of the Laurent operator of its symbol), the supremum taken on an FFT grid of ``G`` points plus
``(pi / G) sum m |h_m|`` (the largest change of ``a`` between grid points).  ``sigma_min(H) = 1 / ||H^-1||``
the same way on ``H^-1`` (also lower triangular Toeplitz).  Up to :data:`DENSE_MAX` samples the norms come from the
dense matrix instead (:func:`toeplitz_norm`).

**Any sampled linear plant** (:func:`sampled_lifted`): a single-input single-output ``x_(i+1) = Phi x_i + Gamma u_i``,
``y_i = C x_i`` -- a discrete-time plant as given, a continuous one under a zero-order hold -- has the Markov
parameters ``C Phi^m Gamma``; the ``s`` leading ones that vanish set the shift ``r = s + 1`` (the relative degree in
samples), and the shifted ones the same structure, through the transfer function ``b(z^-1)/a(z^-1)`` with ``a`` the
characteristic polynomial of ``Phi`` and ``b = (a * h)`` truncated.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any

import numpy as np

__all__ = ["MAX_LIFTED", "MAX_TRIAL_SAMPLES", "LiftedModel", "Norm", "discretization", "lifted_model",
           "markov_parameters", "sampled_lifted", "symbol_bound", "toeplitz_norm", "top_singular"]

MAX_LIFTED = 50_000
"""Most lifted unknowns ``N n`` (samples per trial times joints) a design may ask for: 25 s at 1 kHz on a
two-link arm.  The structured operators need ``O(N n)`` memory (a dense ``nN x nN`` matrix at this size would
need 20 GB); the bound keeps the certificate well under a second."""
MAX_TRIAL_SAMPLES = 2_000_000
"""Most ``trials x N x n`` over a run: every trial's record is kept (about 160 MB at this bound)."""
GRID_FACTOR = 64
"""The symbol is sampled on ``G >= GRID_FACTOR L`` points (a power of two, at most ``2^22``)."""
POWER_ITERATIONS = 300
"""Most iterations of the independent power-iteration re-check."""
POWER_TOL = 1e-10
"""The power iteration stops when its estimate changes by less than this, relatively, in one iteration."""


def discretization(K1: float, K2: float, dt: float, integrator: str = "rk4") -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Gamma)`` of one joint's error system over one step, as the simulator integrates it.

    Parameters
    ----------
    K1, K2 : float
        Position (1/s^2) and velocity (1/s) error gains.
    dt : float
        Integration step (s).
    integrator : str
        ``"rk4"``: RK4's polynomial of ``dt A`` with the input held; ``"cvodes"``: the exact zero-order hold.
    """
    A = np.array([[0.0, 1.0], [-K1, -K2]])
    B = np.array([0.0, 1.0])
    if integrator == "cvodes":
        from scipy.linalg import expm

        E = expm(np.block([[A, B[:, None]], [np.zeros((1, 3))]]) * dt)
        return E[:2, :2], E[:2, 2]
    hA = dt * A
    I2 = np.eye(2)
    hA2 = hA @ hA
    hA3 = hA2 @ hA
    return I2 + hA + hA2 / 2 + hA3 / 6 + hA3 @ hA / 24, dt * (I2 + hA / 2 + hA2 / 6 + hA3 / 24) @ B


def _transfer(Phi: np.ndarray, Gamma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` of ``sum_m C Phi^m Gamma z^-m`` (C = [1, 0]) as a ratio of polynomials in ``z^-1``."""
    b = np.array([Gamma[0], Phi[0, 1] * Gamma[1] - Phi[1, 1] * Gamma[0]])
    a = np.array([1.0, -np.trace(Phi), np.linalg.det(Phi)])
    return b, a


def markov_parameters(Phi: np.ndarray, Gamma: np.ndarray, L: int, inverse: bool = False) -> np.ndarray:
    """The first ``L`` shifted Markov parameters ``h_m = C Phi^m Gamma`` (rad per rad/s^2), or with ``inverse``
    the first ``L`` coefficients of ``1 / a(z)`` (those of ``H^-1``)."""
    from scipy.signal import lfilter

    b, a = _transfer(Phi, Gamma)
    impulse = np.zeros(L)
    impulse[0] = 1.0
    return lfilter(a, b, impulse) if inverse else lfilter(b, a, impulse)


def _nfft(L: int) -> int:
    return 1 << int(np.ceil(np.log2(max(2 * L, 2))))


def symbol_bound(t: np.ndarray, const: float = 0.0, gain: float = 1.0) -> tuple[float, float]:
    """Upper bound of ``sup_w |const - gain a(w)|``, ``a`` the symbol of the lower-triangular Toeplitz ``t``:
    ``(bound, slack)``, the slack ``gain (pi / G) sum m |t_m|`` being what the grid may miss."""
    L = t.size
    G = min(1 << 22, 1 << int(np.ceil(np.log2(GRID_FACTOR * max(L, 1)))))
    a = np.fft.fft(t, G)
    slack = abs(gain) * np.pi / G * float(np.sum(np.arange(L) * np.abs(t)))
    return float(np.max(np.abs(const - gain * a))) + slack, slack


@dataclass(frozen=True)
class Norm:
    """The largest singular value of a structured operator: estimate, independent re-check and a rigorous bracket.

    Attributes
    ----------
    estimate : float
        Lanczos (ARPACK ``svds``).
    power : float
        Power iteration on ``A^T A`` from a fixed smooth start (independent re-check).
    lower : float
        ``||A u||`` for the computed unit vector ``u``: a true lower bound.
    upper : float
        A true upper bound (see the module docstring); ``slack`` the grid's share of it.
    """

    estimate: float
    power: float
    lower: float
    upper: float
    slack: float = 0.0
    routes: str = "lanczos, power iteration"

    def to_dict(self) -> dict[str, Any]:
        return {"lanczos": self.estimate, "power_iteration": self.power, "lower_bound": self.lower,
                "upper_bound": self.upper, "grid_slack": self.slack, "routes": self.routes}


def top_singular(matvec, rmatvec, L: int, upper: float, slack: float = 0.0) -> Norm:
    """:class:`Norm` of the ``L x L`` operator given by ``matvec`` and ``rmatvec`` (``upper``: its known bound)."""
    from scipy.sparse.linalg import LinearOperator, svds

    op = LinearOperator((L, L), matvec=lambda x: matvec(np.ravel(x)), rmatvec=lambda x: rmatvec(np.ravel(x)),
                        dtype=float)
    v0 = np.random.default_rng(0).standard_normal(L)
    _, s, vt = svds(op, k=1, v0=v0, tol=1e-10)
    u = vt[0] / np.linalg.norm(vt[0])
    lower = float(np.linalg.norm(matvec(u)))
    x = np.ones(L) / np.sqrt(L)  # a smooth start, independent of the Lanczos run
    value = 0.0
    for _ in range(POWER_ITERATIONS):
        y = rmatvec(matvec(x))
        norm = float(np.linalg.norm(y))
        if norm == 0.0:
            break
        new = np.sqrt(norm)
        x = y / norm
        if abs(new - value) <= POWER_TOL * new:
            value = new
            break
        value = new
    return Norm(float(s[0]), value, lower, max(upper, lower), slack)


DENSE_MAX = 256
"""Up to this lifted size a Toeplitz operator's norm is taken from its dense matrix: the estimate and its vector ``u``
from the top eigenpair of ``T^T T`` (LAPACK ``syevr``), the second route from that of ``T T^T``, the lower
bound ``||T u||`` -- cheaper there than Lanczos and the power iteration on FFT products, which serve the larger
sizes."""


def toeplitz_norm(t: np.ndarray, upper: float, slack: float = 0.0, transpose: bool = False) -> Norm:
    """:class:`Norm` of the ``L x L`` lower-triangular Toeplitz matrix of the coefficients ``t`` (``upper``: a
    proved bound of it, ``slack`` the grid's share): dense up to :data:`DENSE_MAX`, else by FFT products."""
    t = np.asarray(t, dtype=float)
    L = t.size
    if not np.all(np.isfinite(t)):  # coefficients beyond the floats (an unstable filter): not computed
        nan = float("nan")
        return Norm(nan, nan, nan, float("inf"), 0.0, "coefficients not finite: not computed")
    if L <= DENSE_MAX:
        from scipy.linalg import eigh, toeplitz

        T = toeplitz(t, np.zeros(L))
        # the top eigenpair alone (LAPACK syevr): the full divide-and-conquer with vectors runs BLAS-3 threads that
        # cost a hundred times more on a loaded machine
        w, V = eigh(T.T @ T, subset_by_index=[L - 1, L - 1], driver="evr")
        second = float(np.sqrt(max(float(np.linalg.eigvalsh(T @ T.T)[-1]), 0.0)))
        lower = float(np.linalg.norm(T @ V[:, -1]))
        return Norm(float(np.sqrt(max(float(w[-1]), 0.0))), second, lower, max(upper, lower), slack,
                    "dense: eigh of TᵀT, eigvalsh of T Tᵀ")
    nfft = _nfft(L)
    spectrum = np.fft.rfft(t, nfft)

    def mv(x: np.ndarray) -> np.ndarray:
        return np.fft.irfft(spectrum * np.fft.rfft(x, nfft), nfft)[:L]

    return top_singular(mv, lambda x: mv(x[::-1])[::-1], L, upper, slack)


def _transfer_of(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...],
                                                                           int]:
    """``(b, a, s)`` of a sampled single-input single-output system ``x_(i+1) = Phi x_i + Gamma u_i``, ``y_i = C x_i``:
    ``s`` leading Markov parameters ``C Phi^m Gamma`` vanish (relative degree ``s + 1`` in steps), and ``sum_m C
    Phi^(m+s) Gamma z^-m = b(z^-1) / a(z^-1)`` with ``a`` the characteristic polynomial of ``Phi``."""
    n = Phi.shape[0]
    a = np.real(np.poly(Phi)) if n else np.array([1.0])
    h, x = np.empty(n + 1), np.asarray(Gamma, dtype=float).reshape(-1)
    for m in range(n + 1):
        h[m] = float(C @ x)
        x = Phi @ x
    scale = float(np.max(np.abs(h))) if np.any(h != 0) else 0.0
    if scale == 0.0:
        raise ValueError("the input does not reach the output (every Markov parameter C Phi^m Gamma is zero)")
    s = int(np.flatnonzero(np.abs(h) > RELATIVE_DEGREE_TOL * scale)[0])
    b = np.convolve(a, h)[:n]  # C (zI - Phi)^-1 Gamma = z^-1 b(z^-1) / a(z^-1): b_k = sum_j a_j h_(k-j), k < n
    b = b[s:]
    b = b[:max(1, len(b) - int(np.argmax(np.abs(b[::-1]) > 0)))] if np.any(b != 0) else b[:1]
    return tuple(float(v) for v in b), tuple(float(v) for v in a), s


RELATIVE_DEGREE_TOL = 1e-12
"""A Markov parameter below this fraction of the largest of the first ``n + 1`` counts as zero when the relative
degree of a sampled linear plant is read from them (a state-space model whose ``C B`` vanishes structurally)."""


@dataclass(frozen=True)
class LiftedModel:
    """The lifted error system of every channel (joint) over one trial (module docstring).

    Parameters
    ----------
    systems : tuple of (b, a)
        Per channel, the shifted sampled transfer function ``sum_m h_m z^-m = b(z^-1)/a(z^-1)`` (``b[0] = h_0 !=
        0``), coefficients in powers of ``z^-1``.
    dt : float
        The trial's sample period (s).
    samples : int
        Recorded instants ``N`` of a trial; the lifted size per channel is ``L = N - shift``.
    integrator : str
        How the sampled system was obtained: ``"rk4"`` or ``"cvodes"`` (:func:`discretization`), ``"zoh"`` (a
        continuous linear plant under a zero-order hold), ``"discrete"`` (a discrete-time plant as given).
    shift : int
        The relative degree in samples: the input at ``t_i`` first moves the output at ``t_(i+shift)``.
    """

    systems: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...]
    dt: float
    samples: int
    integrator: str = "rk4"
    shift: int = 1

    @property
    def n(self) -> int:
        """Number of channels (joints)."""
        return len(self.systems)

    @property
    def L(self) -> int:
        """Lifted samples per channel, ``N - shift``."""
        return self.samples - self.shift

    def _series(self, j: int, inverse: bool) -> np.ndarray:
        from scipy.signal import lfilter

        b, a = (np.asarray(c, dtype=float) for c in self.systems[j])
        impulse = np.zeros(self.L)
        impulse[0] = 1.0
        return lfilter(a, b, impulse) if inverse else lfilter(b, a, impulse)

    @cached_property
    def markov(self) -> np.ndarray:
        """Shifted Markov parameters ``(n, L)``: ``markov[j, m] = d y_(i+m+shift) / d u_i`` of channel ``j``."""
        return np.array([self._series(j, False) for j in range(self.n)])

    @cached_property
    def inverse_markov(self) -> np.ndarray:
        """Coefficients ``(n, L)`` of ``H^-1`` per channel (the power series of ``a/b``)."""
        with np.errstate(over="ignore", invalid="ignore"):
            return np.array([self._series(j, True) for j in range(self.n)])

    @cached_property
    def _spectra(self) -> tuple[int, np.ndarray, np.ndarray]:
        nfft = _nfft(self.L)
        with np.errstate(over="ignore", invalid="ignore"):
            return nfft, np.fft.rfft(self.markov, nfft, axis=1), np.fft.rfft(self.inverse_markov, nfft, axis=1)

    def _convolve(self, spectrum: np.ndarray, X: np.ndarray) -> np.ndarray:
        nfft = self._spectra[0]
        X = np.asarray(X, dtype=float)
        return np.fft.irfft(spectrum * np.fft.rfft(X, nfft, axis=-1), nfft, axis=-1)[..., :self.L]

    def apply(self, X: np.ndarray) -> np.ndarray:
        """``H X`` for ``X`` of shape ``(n, L)`` (rad/s^2 -> rad)."""
        return self._convolve(self._spectra[1], X)

    def apply_transpose(self, X: np.ndarray) -> np.ndarray:
        """``H^T X`` (the adjoint: time-reversed filtering), ``X`` of shape ``(n, L)``."""
        return self._convolve(self._spectra[1], np.asarray(X, dtype=float)[..., ::-1])[..., ::-1]

    def apply_inverse(self, X: np.ndarray) -> np.ndarray:
        """``H^-1 X``, ``X`` of shape ``(n, L)`` (rad -> rad/s^2)."""
        return self._convolve(self._spectra[2], X)

    def _unique(self) -> dict[Any, int]:
        """One channel index per distinct system (identical joints share their norms)."""
        out: dict[Any, int] = {}
        for j, key in enumerate(self.systems):
            out.setdefault(key, j)
        return out

    @cached_property
    def sigma_max(self) -> tuple[Norm, ...]:
        """:class:`Norm` of ``H`` per joint (s^2)."""
        found = {}
        for key, j in self._unique().items():
            h = self.markov[j]
            sym, slack = symbol_bound(h)
            l1 = float(np.sum(np.abs(h)))
            found[key] = toeplitz_norm(h, min(l1, sym), slack if sym < l1 else 0.0)
        return tuple(found[key] for key in self.systems)

    @cached_property
    def sigma_min(self) -> tuple[Norm, ...]:
        """``sigma_min(H)`` per joint as a :class:`Norm` of ``1/||H^-1||``: ``estimate``, ``power``, and the
        bracket ``lower`` (from the upper bound of ``||H^-1||``) and ``upper`` (from ``||H^-1 u||``)."""
        found = {}
        for key, j in self._unique().items():
            c = self.inverse_markov[j]
            if not np.all(np.isfinite(c)):
                found[key] = Norm(0.0, 0.0, 0.0, float("inf"))
                continue
            sym, slack = symbol_bound(c)
            l1 = float(np.sum(np.abs(c)))
            inv = toeplitz_norm(c, min(l1, sym), slack if sym < l1 else 0.0)
            found[key] = Norm(1.0 / inv.estimate, 1.0 / inv.power, 1.0 / inv.upper, 1.0 / inv.lower,
                              inv.slack, inv.routes)
        return tuple(found[key] for key in self.systems)

    def zeros(self, j: int = 0) -> np.ndarray:
        """Finite nonzero zeros of channel ``j``'s shifted transfer function ``b(z^-1)/a(z^-1)`` (on the robot: the
        sampling zero near -1)."""
        b = np.asarray(self.systems[j][0], dtype=float)
        return np.roots(b) if b.size > 1 else np.zeros(0)


@lru_cache(maxsize=32)
def lifted_model(K1: tuple[float, ...], K2: tuple[float, ...], dt: float, samples: int,
                 integrator: str = "rk4") -> LiftedModel:
    """The :class:`LiftedModel` of these gains and grid, shared by the update, the checks and the figures."""
    systems = []
    for k1, k2 in zip(K1, K2, strict=True):
        b, a = _transfer(*discretization(float(k1), float(k2), float(dt), integrator))
        systems.append((tuple(float(v) for v in b), tuple(float(v) for v in a)))
    return LiftedModel(tuple(systems), float(dt), int(samples), integrator)


@lru_cache(maxsize=32)
def sampled_lifted(Phi: tuple[tuple[float, ...], ...], Gamma: tuple[float, ...], C: tuple[float, ...], dt: float,
                   samples: int, integrator: str) -> LiftedModel:
    """The :class:`LiftedModel` of a sampled single-input single-output plant ``x_(i+1) = Phi x_i + Gamma u_i``,
    ``y_i = C x_i`` over ``samples`` instants (its shift the relative degree read from the Markov parameters).

    Raises
    ------
    ValueError
        When the input reaches no output sample within the trial.
    """
    b, a, s = _transfer_of(np.array(Phi, dtype=float), np.array(Gamma, dtype=float), np.array(C, dtype=float))
    if samples - 1 - s < 1:
        raise ValueError(f"the input first moves the output {s + 1} samples later; a trial of {samples} samples "
                         "leaves nothing to learn")
    return LiftedModel(((b, a),), float(dt), int(samples), integrator, shift=s + 1)
