"""Recursive least squares with forgetting, one sample as CasADi expressions (the standard form; see
docs/families/self_tuning.md)::

    eps = out - phi' theta,  K = P phi / (lambda + phi' P phi)
    theta <- theta + K eps,  P <- (P - K phi' P) / lambda   (then symmetrised)

and, with ``safeguards``, the covariance bound: ``P`` scaled back to ``max_trace`` when its trace exceeds it.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

__all__ = ["rls_step"]


def rls_step(st: Any, theta: ca.SX, P: ca.SX, phi: ca.SX, out: ca.SX, active: ca.SX) -> dict[str, ca.SX]:
    """One update of recursive least squares with forgetting ``st.forgetting`` (and, with ``st.safeguards``, the
    covariance bound ``st.max_trace``) where ``active``; ``theta``, ``P`` unchanged elsewhere."""
    eps = out - ca.dot(phi, theta)
    Pphi = P @ phi
    K = Pphi / (st.forgetting + ca.dot(phi, Pphi))
    theta_n = theta + K * eps
    P_n = (P - K @ Pphi.T) / st.forgetting
    P_n = 0.5 * (P_n + P_n.T)
    bounded = ca.SX(0)
    if st.safeguards:
        tr = ca.trace(P_n)
        bounded = tr > st.max_trace
        P_n = ca.if_else(bounded, P_n * (st.max_trace / tr), P_n)
    return {"theta": ca.if_else(active, theta_n, theta), "P": ca.if_else(active, P_n, P), "eps": eps,
            "bounded": ca.if_else(active, bounded, 0)}
