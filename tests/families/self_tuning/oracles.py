"""Independent references for the self-tuning tests: scipy's ZOH discretization, python-control's discrete loops."""

from __future__ import annotations

import control
import numpy as np
from scipy.signal import cont2discrete


def zoh(Km: float, tau: float, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` of the link sampled at ``Ts`` by ``scipy.signal.cont2discrete`` (zero-order hold)."""
    F = np.array([[0.0, 1.0], [0.0, -1.0 / tau]])
    b = np.array([[0.0], [Km / tau]])
    Ad, Bd, *_ = cont2discrete((F, b, np.eye(2), np.zeros((2, 1))), Ts, method="zoh")
    return Ad, Bd.ravel()


def theta_scipy(Km: float, tau: float, Ts: float, form: str) -> np.ndarray:
    """The estimator's parameters read off scipy's ``(A, B)``: ``[A22, B2]`` or ``[A22, B1, B2 A12 - B1 A22]``."""
    A, B = zoh(Km, tau, Ts)
    if form == "speed":
        return np.array([A[1, 1], B[1]])
    return np.array([A[1, 1], B[0], B[1] * A[0, 1] - B[0] * A[1, 1]])


def closed_loop_poles(num: np.ndarray, den: np.ndarray, R: np.ndarray, S: np.ndarray, Ts: float) -> np.ndarray:
    """Poles of the discrete loop ``y = B/A u``, ``R u = -S y`` by python-control (feedback of ``G S/R``)."""
    G = control.tf(num, den, Ts)
    C = control.tf(S, R, Ts)
    return np.sort_complex(control.poles(control.feedback(G * C, 1)))


def position_tf(Km: float, tau: float, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """``x1(z)/u(z)`` of the sampled link by python-control (``c2d`` of the continuous transfer function)."""
    G = control.c2d(control.tf([Km], [tau, 1.0, 0.0]), Ts, method="zoh")
    num, den = control.tfdata(G)
    return np.asarray(num[0][0], dtype=float), np.asarray(den[0][0], dtype=float)
