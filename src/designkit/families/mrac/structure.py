"""The feedforward/feedback MRAC structure on a linear plant: the regressor, the ideal parameters, the filters.

**Plant and model.**  The nominal plant ``G(s) = kp Z(s)/R(s)`` (``R`` monic of degree ``n``, ``Z`` monic of degree
``m``) and the reference model ``Gm(s) = km Zm(s)/Rm(s)`` (``Rm`` monic of degree ``nm``, ``Zm`` monic of degree
``mm``), both with the same relative degree ``n - m = nm - mm``.

**Controller** (the model-reference structure of Astrom and Wittenmark, *Adaptive Control*, 2nd ed., ch. 5: the
first-order ``u = theta1 uc - theta2 y`` of their Example 5.2, and its output-feedback generalisation)::

    u = theta' omega,   omega = (uc, -y, -(alpha/Lambda) y, -(alpha/Lambda) u)

with ``alpha(s) = (s^(n-2), ..., s, 1)`` and ``Lambda = Lambda0 Zm`` monic of degree ``n - 1`` (``Lambda0`` of degree
``n - 1 - mm``, the filter poles): ``2 n`` parameters, ``(theta1, theta2)`` when ``n = 1``.  With
``L = Lambda + theta_u' alpha`` and ``M = theta2 Lambda + theta_y' alpha`` the loop is
``y = theta1 kp Z Lambda / (L R + kp Z M) uc``.

**Matching** (:func:`matching`): ``theta1 = km/kp``, ``L = Z Lbar`` and ``kp M`` the quotient and the remainder
of ``Lambda0 Rm`` divided by ``R`` (``Lbar R + kp M = Lambda0 Rm``), so that ``L R + kp Z M = Z Lambda0 Rm`` and the
loop is ``km Zm/Rm``: the plant's zeros ``Z`` are cancelled (they must be stable: a minimum-phase plant).
For ``n = 1``: ``theta1 = bm/b``, ``theta2 = (am - a)/b`` (``G = b/(s + a)``, ``Gm = bm/(s + am)``).

Coefficients are lists, highest power first (NumPy's ``polyval`` order).  Pure NumPy; no CasADi here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Structure", "closed_loop_polynomials", "matching", "monic", "parameter_names", "plant_transfer"]

ZERO = 1e-12
"""A leading coefficient below this times the largest is taken as zero (the polynomial's degree drops)."""


def monic(coefficients: Sequence[float]) -> tuple[float, np.ndarray]:
    """``(leading coefficient, the monic polynomial)`` with leading (near-)zeros removed."""
    c = np.atleast_1d(np.asarray(coefficients, dtype=float))
    scale = float(np.max(np.abs(c))) if c.size else 0.0
    if scale == 0.0:
        raise ValueError("the polynomial is zero")
    k = int(np.argmax(np.abs(c) > ZERO * scale))
    c = c[k:]
    return float(c[0]), c / c[0]


def parameter_names(n: int) -> tuple[str, ...]:
    """``theta1 .. theta(2n)``: 2 for a first-order plant, ``2n`` for order ``n``."""
    return tuple(f"theta{k + 1}" for k in range(2 * n))


def plant_transfer(plant: object) -> tuple[np.ndarray, np.ndarray]:
    """``(num, den)`` of the plant's first output over its first input, at its nominal parameters.

    A ``link`` is ``Km/(tau s^2 + s)``; a linear plant is read from its realised ``A, B, C, D`` (its first output,
    which must have no direct feedthrough).
    """
    if getattr(plant, "kind", "") == "link":
        Km, tau = float(plant.parameter("Km").value), float(plant.parameter("tau").value)  # type: ignore[attr-defined]
        return np.array([Km]), np.array([tau, 1.0, 0.0])
    A, B, C, D = (np.asarray(M, dtype=float) for M in plant.matrices())  # type: ignore[attr-defined]
    n = A.shape[0]
    den = np.poly(A) if n else np.array([1.0])
    b, c = B[:, :1], C[:1, :]
    # num(s) = c adj(sI - A) b = det(sI - A + b c) - det(sI - A)  (rank-one update), plus D den
    num = np.poly(A - b @ c) - den
    num = num + float(D[0, 0]) * den if D.size else num
    return num, den


@dataclass(frozen=True)
class Structure:
    """The feedforward/feedback structure on a nominal plant (module docstring).

    Attributes
    ----------
    plant_num, plant_den : tuple of float
        The nominal plant, ``den`` monic (highest power first).
    model_num, model_den : tuple of float
        The reference model, ``den`` monic.
    lam : tuple of float
        ``Lambda`` (monic, degree ``n - 1``): the regressor filters' denominator.
    ideal : tuple of float
        The parameters that make the nominal loop the model (:func:`matching`).
    """

    plant_num: tuple[float, ...]
    plant_den: tuple[float, ...]
    model_num: tuple[float, ...]
    model_den: tuple[float, ...]
    lam: tuple[float, ...]
    ideal: tuple[float, ...]

    @property
    def order(self) -> int:
        """``n``, the plant's order."""
        return len(self.plant_den) - 1

    @property
    def names(self) -> tuple[str, ...]:
        """The adapted parameters' names."""
        return parameter_names(self.order)

    @property
    def high_frequency_sign(self) -> float:
        """``sign(kp/km)``: the sign the rules need (the plant's high-frequency gain's against the model's)."""
        return float(np.sign(self.plant_num[0] * self.model_num[0]))

    @property
    def static_gain(self) -> float:
        """``Gm(0)``, the model's static gain."""
        return float(self.model_num[-1] / self.model_den[-1])


def matching(num: Sequence[float], den: Sequence[float], model_num: Sequence[float], model_den: Sequence[float],
             lam0: Sequence[float] = (1.0,)) -> tuple[tuple[float, ...], np.ndarray]:
    """The ideal parameters ``theta*`` and ``Lambda`` for plant ``num/den`` and model ``model_num/model_den``.

    ``lam0`` is ``Lambda0`` (monic, degree ``n - 1 - mm``), so ``Lambda = lam0 Zm``.

    Examples
    --------
    Astrom and Wittenmark's Example 5.2, ``G = 0.5/(s + 1)``, ``Gm = 2/(s + 2)``:

    >>> theta, lam = matching([0.5], [1, 1], [2], [1, 2])
    >>> [round(t, 12) for t in theta], lam.tolist()
    ([4.0, 2.0], [1.0])
    """
    kp, Z = monic(num)
    a0, R = monic(den)
    kp /= a0
    km, Zm = monic(model_num)
    b0, Rm = monic(model_den)
    km /= b0
    n = len(R) - 1
    lam = np.polymul(np.asarray(lam0, dtype=float), Zm)
    if len(lam) != n:
        raise ValueError(f"Lambda has degree {len(lam) - 1}, the plant's order less one is {n - 1}")
    q, r = np.polydiv(np.polymul(np.asarray(lam0, dtype=float), Rm), R)
    M = np.zeros(n)
    r = np.atleast_1d(r)[-n:] if n else np.zeros(0)
    M[n - len(r):] = r / kp
    L = np.polymul(Z, q)
    theta_u = (L - lam)[1:] if n > 1 else np.zeros(0)
    theta2 = float(M[0])
    theta_y = (M - theta2 * lam)[1:] if n > 1 else np.zeros(0)
    theta = (km / kp, theta2, *theta_y.tolist(), *theta_u.tolist())
    return tuple(float(t) for t in theta), lam


def closed_loop_polynomials(s: Structure, theta: Sequence[float], num: Sequence[float] | None = None,
                            den: Sequence[float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(numerator, characteristic polynomial)`` of the loop from ``uc`` to ``y`` with the parameters ``theta`` held,
    on the plant ``num/den`` (default the nominal plant); the characteristic polynomial includes ``Lambda`` (the
    regressor filters' own poles: the loop has ``n + 2 (n - 1)`` states)."""
    num = np.asarray(s.plant_num if num is None else num, dtype=float)
    den = np.asarray(s.plant_den if den is None else den, dtype=float)
    n = s.order
    lam = np.asarray(s.lam, dtype=float)
    th = np.asarray(theta, dtype=float)
    theta_y, theta_u = th[2:2 + n - 1], th[2 + n - 1:]
    L = lam + np.r_[0.0, theta_u] if n > 1 else lam
    M = th[1] * lam + (np.r_[0.0, theta_y] if n > 1 else 0.0)
    char = np.polyadd(np.polymul(L, den), np.polymul(num, M))
    return np.polymul(th[0] * num, lam), np.polymul(lam, char) if n > 1 else char
