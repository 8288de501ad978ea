"""The SIMNOG two-link arm's inverse dynamics by Euler-Lagrange in sympy, independent of the model layer.

The arm of ``designkit.models.robots.planar2r``'s docstring: uniform links of masses ``m1, m2`` and lengths
``d1, d2``, centres of mass at mid-length, inertias ``I1, I2`` about them, joint 2 relative to link 1, gravity ``g``
along the base ``-y`` axis, viscous frictions ``f1, f2`` and no Coulomb friction.  ``L = T - U`` from the centres'
positions, ``tau_i = d/dt dL/dqd_i - dL/dq_i + f_i qd_i``.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

NAMES = ("m1", "m2", "d1", "d2", "I1", "I2", "f1", "f2", "g")


@functools.lru_cache(maxsize=1)
def _torque() -> object:
    t = sp.symbols("t")
    m1, m2, d1, d2, I1, I2, f1, f2, g = sp.symbols(NAMES)
    q1, q2 = sp.Function("q1")(t), sp.Function("q2")(t)
    c1 = sp.Matrix([d1 / 2 * sp.cos(q1), d1 / 2 * sp.sin(q1)])
    c2 = sp.Matrix([d1 * sp.cos(q1) + d2 / 2 * sp.cos(q1 + q2), d1 * sp.sin(q1) + d2 / 2 * sp.sin(q1 + q2)])
    v1, v2 = c1.diff(t), c2.diff(t)
    T = (m1 * v1.dot(v1) + m2 * v2.dot(v2) + I1 * q1.diff(t) ** 2 + I2 * (q1.diff(t) + q2.diff(t)) ** 2) / 2
    U = g * (m1 * c1[1] + m2 * c2[1])
    L = T - U
    tau = []
    for qi, fi in ((q1, f1), (q2, f2)):
        tau.append(sp.diff(L.diff(qi.diff(t)), t) - L.diff(qi) + fi * qi.diff(t))
    a = sp.symbols("q1 q2 qd1 qd2 qdd1 qdd2")
    subs = {q1.diff(t, 2): a[4], q2.diff(t, 2): a[5]}
    subs2 = {q1.diff(t): a[2], q2.diff(t): a[3]}
    subs3 = {q1: a[0], q2: a[1]}
    exprs = [e.subs(subs).subs(subs2).subs(subs3) for e in tau]
    return sp.lambdify((*a, *sp.symbols(NAMES)), exprs, "numpy")


def torque(values: dict[str, float], q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """``tau (N, 2)`` at ``N`` states (arrays ``(N, 2)``) for the arm's ``values`` (SI units)."""
    f = _torque()
    out = f(q[:, 0], q[:, 1], qd[:, 0], qd[:, 1], qdd[:, 0], qdd[:, 1], *(values[k] for k in NAMES))
    return np.stack([np.broadcast_to(np.asarray(x, dtype=float), (len(q),)) for x in out], axis=1)


def states(count: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``count`` random states (seeded): positions in a turn, speeds and accelerations up to 3 and 10."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, (count, 2)), rng.uniform(-3, 3, (count, 2)), rng.uniform(-10, 10, (count, 2))


def base_by_least_squares(values: dict[str, float], Wb: object, count: int = 200) -> tuple[np.ndarray, float]:
    """The base parameters of the arm ``values`` as the coordinates of its Euler-Lagrange torque in the columns of
    the base regressor ``Wb`` (least squares over ``count`` random states) and the fit's largest residual (N*m)."""
    q, qd, qdd = states(count, seed=7)
    tau = torque(values, q, qd, qdd)
    rows = np.stack([np.asarray(Wb(q[k], qd[k], qdd[k]), dtype=float) for k in range(count)])  # (N, 2, b)
    A = rows.reshape(-1, rows.shape[2])
    beta, *_ = np.linalg.lstsq(A, tau.reshape(-1), rcond=None)
    return beta, float(np.max(np.abs(A @ beta - tau.reshape(-1))))
