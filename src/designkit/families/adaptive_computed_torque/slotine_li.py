"""The second scheme, ``scheme: slotine_li``: the Slotine--Li passivity-based law (no acceleration, no ``D^-1``).

With ``e = qD - q``, the reference velocity ``qr' = qD' + Lambda e``, ``qr'' = qD'' + Lambda e'`` and
``s = qr' - qd = e' + Lambda e``::

    Gamma_u = Y(q, qd, qr', qr'') P^ + KD s,          Y P = D(q) qr'' + C(q, qd) qr' + g(q) + F(qd)
    P^_a'   = K Y_a' s

``C`` is the Christoffel-consistent Coriolis matrix (``D' - 2C`` skew), computed here from ``D(q; P)`` (the
Newton--Euler with ``P`` as data, differentiated in ``a``) by ``C(q, qd) v = 1/2 [D'(q, qd) v + (d(D qd)/dq) v -
(d(qd' D v)/dq)']``, and ``Y P = D qr'' + h(q, qd) + C(q, qd)(qr' - qd)`` with ``h = C qd + g + F`` the model
layer's own.  Closed loop: ``D s' + (C + KD) s = Y (P - P^)``; with
``V = 1/2 s' D s + 1/2 (P - P^)' K^-1 (P - P^)``, ``V' = -s' KD s`` (docs/families/adaptive_computed_torque.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["christoffel_torque", "fixed_command", "parts"]


def christoffel_torque(tau_of: Any, n: int, size: int) -> ca.Function:
    """``(q, qd, v, a, P) -> D a + C(q, qd) v + g + F(qd)`` with the Christoffel ``C`` (N*m)."""
    q, qd, v, a, acc = (ca.SX.sym(x, n) for x in ("q", "qd", "v", "a", "acc"))
    P = ca.SX.sym("P", size)
    D = ca.jacobian(tau_of(q, ca.SX.zeros(n), acc, P), acc)
    w = v - qd
    term1 = ca.jacobian(D @ w, q) @ qd
    term2 = ca.jacobian(D @ qd, q) @ w
    term3 = ca.jacobian(ca.dot(qd, D @ w), q).T
    h = tau_of(q, qd, ca.SX.zeros(n), P)
    tau = D @ a + h + 0.5 * (term1 + term2 - term3)
    return ca.Function("slotine_li_torque", [q, qd, v, a, P], [tau], ["q", "qd", "v", "a", "P"], ["tau"])


def parts(s: Any, tau_of: Any, n: int, P_true: np.ndarray, idx: Sequence[int], est: ca.SX, Lambda: ca.DM,
          KD: ca.DM, gain: np.ndarray, estimate: Any) -> dict[str, ca.SX]:
    """The Slotine--Li law's expressions at the symbols ``s`` (command, update rate, ``V`` and its derivative);
    ``gain`` is the adaptation gain ``K`` (m x m, symmetric positive definite)."""
    Y = christoffel_torque(tau_of, n, len(P_true))
    q, qd = s.q, s.qd
    e, ed = s.qD - q, s.qDd - qd
    qr_d, qr_dd = s.qDd + Lambda * e, s.qDdd + Lambda * ed
    sv = ed + Lambda * e
    P_hat = estimate(P_true, idx, est)
    u = Y(q, qd, qr_d, qr_dd, P_hat) + KD * sv
    Pa = ca.SX.sym("Pa", len(idx))
    Ya = ca.jacobian(Y(q, qd, qr_d, qr_dd, estimate(P_true, idx, Pa)), Pa)  # affine in P: free of Pa
    rate = ca.DM(gain) @ (Ya.T @ sv)
    acc = ca.SX.sym("acc", n)
    D_true = ca.jacobian(tau_of(q, ca.SX.zeros(n), acc, ca.DM(P_true)), acc)
    phi = ca.DM(P_true[list(idx)]) - est
    V = 0.5 * ca.dot(sv, D_true @ sv) + 0.5 * ca.dot(phi, ca.DM(np.linalg.inv(gain)) @ phi)
    return {"u": u, "rate": rate, "V": V, "Vdot": -ca.sum1(KD * sv**2), "e1": sv, "vf_dot": None}


def fixed_command(s: Any, tau_of: Any, n: int, P_hat: ca.SX, Lambda: ca.DM, KD: ca.DM) -> ca.SX:
    """``Y(q, qd, qr', qr'') P^ + KD s`` with ``P^`` held."""
    Y = christoffel_torque(tau_of, n, P_hat.numel())
    e, ed = s.qD - s.q, s.qDd - s.qd
    return Y(s.q, s.qd, s.qDd + Lambda * e, s.qDdd + Lambda * ed, P_hat) + KD * (ed + Lambda * e)
