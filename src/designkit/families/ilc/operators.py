"""The learning operators ``Q`` of ``d_{k+1} = d_k + Q e_k`` and their contraction certificate ``||I - Q H||_2``.

On the lifted exact-model error system ``e_k = H (d - d_k)`` (:mod:`~designkit.families.ilc.lifted`) the update
gives ``d - d_{k+1} = (I - Q H)(d - d_k)`` and ``e_{k+1} = (I - H Q) e_k``.  For both operators here ``H Q`` and
``Q H`` have the same 2-norm ``rho``, so ``rho < 1`` proves **monotone** convergence: ``||d - d_k||`` and
``||e_k||`` both fall at least by the factor ``rho`` every trial.  The spectral radius of ``I - Q H`` below 1
proves **asymptotic** convergence only (``||e_k||`` may grow for many trials first).

* ``adjoint`` -- ``Q = alpha H^T`` (the notes' ``alpha H*``; non-causal: the error filtered backwards in time).
  ``I - alpha H^T H`` is symmetric with eigenvalues ``1 - alpha sigma_i^2``, so ``rho = max(|1 - alpha
  sigma_max^2|, |1 - alpha sigma_min^2|)``, equal to the spectral radius.  Since ``H`` is invertible
  (``sigma_min > 0``), ``rho < 1`` exactly when ``0 < alpha < 2 / sigma_max^2`` (the notes' ``||H|| < 1/alpha``
  is not it: ``alpha`` has the unit 1/s^4 and ``H`` s^2, the condition is ``alpha ||H||^2 < 2``).  ``rho`` is
  smallest, ``(kappa^2 - 1)/(kappa^2 + 1)`` with ``kappa = sigma_max/sigma_min``, at ``alpha* = 2 /
  (sigma_max^2 + sigma_min^2)``; with ``kappa`` near 1e7 that minimum is ``1 - 2e-14``: the worst-case rate
  says nothing, and ``alpha*`` leaves the largest singular direction alternating without decay.  The default
  ``alpha = 1 / sigma_max^2`` removes that direction in one trial.
* ``p_type`` -- ``Q = gamma S`` with ``S`` the one-step advance, ``d_{k+1}(t_i) = d_k(t_i) + gamma e_k(t_{i+1})``
  (causal in the trial's record; the shift is the sampled relative degree: one step).  ``I - gamma H`` is
  lower triangular Toeplitz: its spectral radius is ``|1 - gamma h_0|`` (asymptotic convergence for
  ``0 < gamma < 2 / h_0``), its norm is at least the symbol's ``sup |1 - gamma a(w)|``, above 1 wherever
  ``Re a(w) < 0`` (above the error loop's natural frequency): no monotone certificate for any ``gamma``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from designkit.families.ilc.lifted import LiftedModel, Norm, symbol_bound, toeplitz_norm
from designkit.verification.bracket import bracket_verdict

__all__ = ["Adjoint", "Contraction", "Filter", "PType", "contraction", "learning_operator"]


def _margin(x: float) -> float:
    """``1 - |1 - x|`` without cancellation."""
    return x if x <= 1.0 else 2.0 - x


@dataclass(frozen=True)
class Adjoint:
    """``Q = alpha H^T`` (``alpha`` in 1/s^4)."""

    alpha: float
    kind: str = "adjoint"

    def apply(self, lifted: LiftedModel, E: np.ndarray) -> np.ndarray:
        """``Q E`` for the lifted errors ``E`` ``(n, L)`` (rad) -> rad/s^2."""
        return self.alpha * lifted.apply_transpose(E)

    def describe(self) -> str:
        return f"d_(k+1) = d_k + α Hᵀ e_k with α = {self.alpha:.6g} 1/s⁴ (the adjoint of the lifted error system)"


@dataclass(frozen=True)
class PType:
    """``Q = gamma S`` (``gamma`` in 1/s^2 on the robot, input per output unit on a linear plant; ``S`` the advance
    by the relative degree)."""

    gain: float
    kind: str = "p_type"

    def coefficients(self, L: int) -> np.ndarray:
        """The first ``L`` coefficients of ``Q`` as a causal filter of the advanced error: ``[gamma]``."""
        return np.array([self.gain])

    def apply(self, lifted: LiftedModel, E: np.ndarray) -> np.ndarray:
        return self.gain * np.asarray(E, dtype=float)

    def describe(self) -> str:
        return (f"d_(k+1)(t_i) = d_k(t_i) + γ e_k(t_(i+r)) with γ = {self.gain:.6g} (P-type, advance r = relative "
                "degree)")


@dataclass(frozen=True)
class Filter:
    """``Q = F(z) S``: a causal filter ``F(z) = (n_0 + n_1 z^-1 + ...) / (d_0 + d_1 z^-1 + ...)`` of the error
    advanced by the relative degree (the P-type is ``F = gamma``)."""

    num: tuple[float, ...]
    den: tuple[float, ...] = (1.0,)
    kind: str = "filter"

    @property
    def value(self) -> float:
        """``F``'s first coefficient ``n_0 / d_0`` (what the spectral radius reads)."""
        return float(self.num[0] / self.den[0])

    def coefficients(self, L: int) -> np.ndarray:
        """The first ``L`` coefficients of ``F``'s impulse response."""
        from scipy.signal import lfilter

        impulse = np.zeros(max(L, 1))
        impulse[0] = 1.0
        with np.errstate(over="ignore", invalid="ignore"):
            return lfilter(np.asarray(self.num, dtype=float), np.asarray(self.den, dtype=float), impulse)

    def apply(self, lifted: LiftedModel, E: np.ndarray) -> np.ndarray:
        from scipy.signal import lfilter

        return lfilter(np.asarray(self.num, dtype=float), np.asarray(self.den, dtype=float),
                       np.asarray(E, dtype=float), axis=-1)

    def describe(self) -> str:
        return (f"d_(k+1) = d_k + F(z) e_k(· + r) with F(z) = ({_poly(self.num)}) / ({_poly(self.den)}) (a causal "
                "filter of the error advanced by the relative degree r)")


def _poly(c: tuple[float, ...]) -> str:
    terms = [f"{v:.6g}" + ("" if k == 0 else " z⁻¹" if k == 1 else f" z^-{k}") for k, v in enumerate(c) if v != 0]
    return " + ".join(terms).replace("+ -", "− ") or "0"


def learning_operator(kind: str, value: Any) -> Adjoint | PType | Filter:
    """The operator of ``kind`` (``adjoint``: ``alpha``; ``p_type``: ``gamma``; ``filter``: ``(num, den)``)."""
    if kind == "adjoint":
        return Adjoint(float(value))
    if kind == "filter":
        num, den = value
        return Filter(tuple(float(v) for v in num), tuple(float(v) for v in den))
    return PType(float(value))


@dataclass(frozen=True)
class Contraction:
    """``rho = ||I - Q H||_2`` of a learning operator on a lifted model, with a rigorous bracket.

    Attributes
    ----------
    rho : float
        Estimate (Lanczos-based); ``rho_power`` the same from the power-iteration route.
    lower, upper : float
        ``lower <= rho <= upper``, both proved (Rayleigh quotients below, norm bounds above).
    margin : float
        ``1 - upper``, computed without cancellation (positive: monotone convergence proved).
    excess : float
        ``lower - 1`` (positive: ``rho > 1`` proved).
    spectral_radius : float
        Of ``I - Q H`` (exact for ``p_type``; equal to ``rho`` for ``adjoint``); ``spectral_margin`` is
        ``1 - spectral_radius`` without cancellation.
    per_joint : tuple of dict
        Each joint's numbers.
    alpha_range : dict
        ``adjoint``: the admissible ``alpha`` (``0 < alpha < 2/sigma_max^2``: estimate and proved), ``alpha*``
        minimising ``rho`` and that minimum, and ``1/sigma_max^2``.  ``p_type``: the ``gamma`` range of
        asymptotic convergence.
    """

    kind: str
    value: float
    rho: float
    rho_power: float
    lower: float
    upper: float
    margin: float
    excess: float
    spectral_radius: float
    spectral_margin: float
    per_joint: tuple[dict[str, Any], ...] = ()
    alpha_range: dict[str, Any] = field(default_factory=dict)

    @property
    def monotone(self) -> bool | None:
        """True: ``rho < 1`` proved; False: ``rho > 1`` proved; None: undecided (the bracket contains 1, or an end
        of it lies within the boundary tolerance of 1: :func:`~designkit.verification.bracket.bracket_verdict`)."""
        return bracket_verdict(self.margin, self.excess).passed

    @property
    def asymptotic(self) -> bool:
        """Spectral radius below 1."""
        return self.spectral_margin > 0

    def to_dict(self) -> dict[str, Any]:
        return {"learning": self.kind, "value": self.value, "rho": self.rho, "rho_power_iteration": self.rho_power,
                "rho_lower_bound": self.lower, "rho_upper_bound": self.upper, "margin": self.margin,
                "spectral_radius": self.spectral_radius, "spectral_margin": self.spectral_margin,
                "joints": [dict(j) for j in self.per_joint], "range": dict(self.alpha_range)}


def _adjoint(lifted: LiftedModel, alpha: float) -> Contraction:
    smax, smin = lifted.sigma_max, lifted.sigma_min
    joints = []
    rho = rho_p = lower = upper = -np.inf
    margin, excess = np.inf, -np.inf
    for j in range(lifted.n):
        hi, lo = smax[j], smin[j]
        est = max(abs(1 - alpha * hi.estimate**2), abs(1 - alpha * lo.estimate**2))
        pw = max(abs(1 - alpha * hi.power**2), abs(1 - alpha * lo.power**2))
        ub = max(abs(1 - alpha * hi.upper**2), abs(1 - alpha * lo.lower**2))
        lb = max(abs(1 - alpha * hi.lower**2), abs(1 - alpha * lo.upper**2))
        m = min(_margin(alpha * hi.upper**2), _margin(alpha * lo.lower**2))
        x = max(max(v - 2.0, -v) for v in (alpha * hi.lower**2, alpha * lo.upper**2))  # lb - 1, no cancellation
        joints.append({"sigma_max": hi.to_dict(), "sigma_min": smin[j].to_dict(), "rho": est, "margin": m})
        rho, rho_p, lower, upper = max(rho, est), max(rho_p, pw), max(lower, lb), max(upper, ub)
        margin, excess = min(margin, m), max(excess, x)
    s_hi = max(s.estimate for s in smax)
    s_lo = min(s.estimate for s in smin)
    proved_hi = max(s.upper for s in smax)
    best = 2.0 / (s_hi**2 + s_lo**2)
    rng = {"alpha_max": 2.0 / s_hi**2, "alpha_max_proved": 2.0 / proved_hi**2, "alpha_optimal": best,
           "rho_optimal": (s_hi**2 - s_lo**2) / (s_hi**2 + s_lo**2), "rho_optimal_margin": 2 * s_lo**2 / (
               s_hi**2 + s_lo**2), "alpha_one_trial": 1.0 / s_hi**2, "sigma_max": s_hi, "sigma_min": s_lo,
           "unit": "1/s^4"}
    decided = margin if margin > 0 else -excess if excess > 0 else 0.0  # symmetric: spectral radius = rho
    return Contraction("adjoint", alpha, float(rho), float(rho_p), float(lower), float(upper), float(margin),
                       float(excess), float(rho), float(decided), tuple(joints), rng)


def _causal(lifted: LiftedModel, operator: PType | Filter) -> Contraction:
    """``I - Q H`` with ``Q`` causal on the advanced error: lower-triangular Toeplitz, coefficients ``delta - q * h``
    (``q`` the filter's impulse response, ``h`` the Markov parameters), so the spectral radius is ``|1 - q_0 h_0|``
    and ``min(sum |t_m|, sup |t(w)|)`` bounds the norm."""
    from scipy.signal import fftconvolve

    joints = []
    rho = rho_p = lower = upper = -np.inf
    spectral, spectral_margin = -np.inf, np.inf
    L = lifted.L
    q = operator.coefficients(L)
    for j in range(lifted.n):
        h = lifted.markov[j]
        t = -fftconvolve(q, h)[:L] if q.size > 1 else -q[0] * h
        t[0] += 1.0
        sym, slack = symbol_bound(t)
        l1 = float(np.sum(np.abs(t)))
        norm: Norm = toeplitz_norm(t, min(l1, sym), slack if sym < l1 else 0.0)
        sr = abs(1.0 - float(q[0] * h[0]))  # the diagonal, whatever the later coefficients
        joints.append({"norm": norm.to_dict(), "spectral_radius": sr, "h0": float(h[0])})
        rho, rho_p = max(rho, norm.estimate), max(rho_p, norm.power)
        lower, upper = max(lower, norm.lower), max(upper, norm.upper)
        spectral = max(spectral, sr)
        spectral_margin = min(spectral_margin, _margin(float(q[0] * h[0])))
    if not all(np.isfinite(j["norm"]["lanczos"]) for j in joints):  # an operator whose norm was not computed
        rho = rho_p = lower = float("nan")
        upper = float("inf")
    h0 = min(float(lifted.markov[j, 0]) for j in range(lifted.n))
    if isinstance(operator, PType):
        rng = {"gamma_asymptotic_max": 2.0 / h0, "h0": h0, "unit": ""}
        value = operator.gain
    else:
        rng = {"q0_asymptotic_max": 2.0 / h0, "h0": h0, "unit": ""}
        value = operator.value
    return Contraction(operator.kind, value, float(rho), float(rho_p), float(lower), float(upper), float(1.0 - upper),
                       float(lower - 1.0), float(spectral), float(spectral_margin), tuple(joints), rng)


@lru_cache(maxsize=32)
def contraction(lifted: LiftedModel, operator: Adjoint | PType | Filter) -> Contraction:
    """The :class:`Contraction` of ``operator`` on ``lifted`` (cached: the checks, figures and JSON share it)."""
    if isinstance(operator, Adjoint):
        return _adjoint(lifted, operator.alpha)
    with np.errstate(all="ignore"):  # an unstable filter's coefficients overflow: its norm is then not computed
        return _causal(lifted, operator)
