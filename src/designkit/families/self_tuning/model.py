"""The sampled link and its ARX models, and the pole-placement (Diophantine) design: NumPy.

**Exact zero-order-hold model.**  The link ``x1' = x2``, ``x2' = -x2/tau + (Km/tau) u`` sampled at ``Ts``
with ``u`` held over each period is ``x(k+1) = A x(k) + B u(k)`` with ``A = expm(F Ts)``,
``B = int_0^Ts expm(F s) ds b``; in closed form (``a = exp(-Ts/tau)``)::

    A = [[1, A12], [0, A22]],  A12 = tau (1 - a),  A22 = a
    B = [B1, B2],              B1 = Km (Ts - tau (1 - a)),  B2 = Km (1 - a)

(checked against ``scipy.signal.cont2discrete`` in the tests).

**Speed measured** (notes appendix, fig. 4.1): ``x2(k+1) = A22 x2(k) + B2 u(k)``, the output ``x2(k+1)``,
the regressor ``[x2(k), u(k)]``, ``theta = [A22, B2]``.

**Speed not measured** (fig. 4.2): with ``d(k) = x1(k+1) - x1(k) = A12 x2(k) + B1 u(k)``, eliminating
``x2``: ``d(k+1) = A22 d(k) + B1 u(k+1) + (A12 B2 - A22 B1) u(k)``; the output ``d(k+1)``, the regressor
``[d(k), u(k+1), u(k)]``, ``theta = [A22, B1, B2 A12 - B1 A22]``.

**Position transfer function** (both forms design on it)::

    x1(z)/u(z) = (b0 z + b1) / ((z - 1)(z - A22)),   b0 = B1,  b1 = A12 B2 - A22 B1

With the speed measured ``A12`` and ``B1`` follow from ``(A22, B2)`` through ``tau = -Ts/ln A22`` and
``Km = B2/(1 - A22)`` (:func:`position_model`).

**Pole placement.**  ``R(z) u = T(z) r - S(z) y`` with ``R = z + r1``, ``S = s0 z + s1``,
``T = t0 (z - zo)``: the closed loop's characteristic polynomial is ``A R + B S`` (degree 3), set
equal to ``Am(z) (z - zo)``, ``Am`` the two requested poles mapped by ``z = exp(p Ts)`` and ``zo`` the
observer pole; ``t0 = Am(1)/B(1)`` makes the static gain from ``r`` to ``y`` one.  Matching the
coefficients of ``z^2, z, 1`` gives the Sylvester system (:func:`sylvester`)::

    [[1,  b0, 0 ],   [r1]   [c1 - a1]
     [a1, b1, b0], @ [s0] = [c2 - a2]
     [a2, 0,  b1]]   [s1]   [c3     ]

with ``A = z^2 + a1 z + a2`` and ``Acl = z^3 + c1 z^2 + c2 z + c3``.  Its determinant is
``b1^2 - a1 b0 b1 + a2 b0^2 = b0^2 A(-b1/b0)``, the resultant of ``A`` and ``B``: zero exactly when
they share a root, which is why a near-common factor shows as ill-conditioning.

**One-link PID** (``design: pid``): the estimate is turned into the link's ``(Km, tau)`` and the PID
servo's gains placing the three continuous poles come from
:func:`designkit.synthesis.pid.servo_pid_gains` (bare numbers: an early estimate's ``Km`` may be negative).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["FORMS", "PARAMETER_NAMES", "PARAMETER_UNITS", "desired_polynomial", "diophantine", "discretize",
           "link_of", "position_model", "sylvester", "theta_of"]

FORMS = ("speed", "position")
"""The estimator forms: speed measured (fig. 4.1), speed not measured (fig. 4.2)."""
PARAMETER_NAMES = {"speed": ("A22", "B2"), "position": ("A22", "B1", "B2 A12 − B1 A22")}
"""The estimated parameters of each form, in order."""
PARAMETER_UNITS = {"speed": ("", "rad/(s·N·m)"), "position": ("", "rad/(N·m)", "rad/(N·m)")}
"""Their units (A22 dimensionless)."""


def discretize(Km: float, tau: float, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` of the link sampled at ``Ts`` (s) with a zero-order hold (module docstring)."""
    a = math.exp(-Ts / tau)
    A = np.array([[1.0, tau * (1.0 - a)], [0.0, a]])
    B = np.array([Km * (Ts - tau * (1.0 - a)), Km * (1.0 - a)])
    return A, B


def theta_of(Km: float, tau: float, Ts: float, form: str) -> tuple[float, ...]:
    """The true parameters of the ``form`` estimator for the link ``(Km, tau)`` sampled at ``Ts``."""
    A, B = discretize(Km, tau, Ts)
    if form == "speed":
        return float(A[1, 1]), float(B[1])
    return float(A[1, 1]), float(B[0]), float(B[1] * A[0, 1] - B[0] * A[1, 1])


def link_of(A22: float, B2: float, Ts: float) -> tuple[float, float]:
    """``(Km, tau)`` of the continuous link whose ZOH model has these ``A22`` (in (0, 1)) and ``B2``."""
    tau = -Ts / math.log(A22)
    return B2 / (1.0 - A22), tau


def position_model(theta: Sequence[float], Ts: float, form: str) -> tuple[float, float, float, float]:
    """``(a1, a2, b0, b1)``: ``A(z) = z^2 + a1 z + a2``, ``B(z) = b0 z + b1`` of the position from ``theta``."""
    A22 = float(theta[0])
    if form == "speed":
        B2 = float(theta[1])
        A12 = -Ts * (1.0 - A22) / math.log(A22)
        B1 = B2 / (1.0 - A22) * (Ts - A12)
        b0, b1 = B1, A12 * B2 - A22 * B1
    else:
        b0, b1 = float(theta[1]), float(theta[2])
    return -(1.0 + A22), A22, b0, b1


def desired_polynomial(poles: Sequence[complex], observer: float, Ts: float) -> tuple[float, float, float]:
    """``(c1, c2, c3)`` of ``Acl(z) = prod (z - exp(p Ts)) (z - exp(observer Ts))`` (poles in 1/s)."""
    z = [np.exp(complex(p) * Ts) for p in poles] + [math.exp(observer * Ts)]
    c = np.real(np.poly(z))
    return float(c[1]), float(c[2]), float(c[3])


def sylvester(a1: float, a2: float, b0: float, b1: float) -> np.ndarray:
    """The 3 x 3 Sylvester matrix of the Diophantine equation (module docstring)."""
    return np.array([[1.0, b0, 0.0], [a1, b1, b0], [a2, 0.0, b1]])


def diophantine(model: Sequence[float], c: Sequence[float]) -> tuple[float, float, float]:
    """``(r1, s0, s1)`` solving ``A R + B S = Acl`` for ``model = (a1, a2, b0, b1)`` and ``c = (c1, c2, c3)``."""
    a1, a2, b0, b1 = (float(v) for v in model)
    rhs = np.array([c[0] - a1, c[1] - a2, c[2]])
    r1, s0, s1 = np.linalg.solve(sylvester(a1, a2, b0, b1), rhs)
    return float(r1), float(s0), float(s1)
