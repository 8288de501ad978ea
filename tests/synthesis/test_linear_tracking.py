"""The PID tracker of a linear plant (:mod:`designkit.synthesis.linear_tracking`).

Independent routes: the feedforward's transfer ``q0 + q1 s + q2 s^2 + h (sI - F)^-1 g`` against ``D(s)/N(s)`` of
python-control's transfer function of the plant at sample frequencies; the loop's poles against python-control's
``feedback`` of ``C(s) = K1 + K2 s + K3/s`` (relative degree 2: ``c A x = y'``) with the plant's zeros added (the
filter's modes); ``y/xD = 1`` against the closed loop's response to ``(xD, s xD, s^2 xD)`` formed by hand.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from designkit.models.linear_plant import transfer_function_plant
from designkit.synthesis.linear_tracking import linear_tracking_design, plant_inverse

NUM, DEN = [3.0, 6.0], [1.0, 3.0, 7.0, 1.0]  # 3 (s + 2) / (s^3 + 3 s^2 + 7 s + 1): relative degree 2, zero -2
POLES = [-4.0, -5.0, -6.0]


def _sorted(z):
    z = np.asarray(z, complex)
    return z[np.lexsort((z.imag, z.real))]


def test_the_feedforward_is_the_plants_inverse():
    plant = transfer_function_plant(NUM, DEN)
    A, B, C, _ = plant.matrices()
    inv = plant_inverse(A, B[:, 0], C[0])
    F, g, h = np.array(inv.F), np.array(inv.g), np.array(inv.h)
    G = control.tf(NUM, DEN)
    for s in (0.3, 1j, 2.0 + 5j, 40j):
        ff = inv.q[0] + inv.q[1] * s + inv.q[2] * s * s + h @ np.linalg.solve(s * np.eye(len(g)) - F, g)
        assert ff == pytest.approx(1.0 / complex(G(s)), rel=1e-10)
    assert inv.relative_degree == 2 and _sorted(inv.zeros) == pytest.approx([-2.0], rel=1e-12)


def test_the_loop_poles_and_perfect_tracking():
    d = linear_tracking_design(transfer_function_plant(NUM, DEN), POLES, kind="pid_tracking")
    K1, K2, K3 = (float(d.gains[k]) for k in ("K1", "K2", "K3"))
    loop = control.feedback(control.tf([K2, K1, K3], [1.0, 0.0]) * control.tf(NUM, DEN), 1)
    expected = _sorted([*control.poles(loop), -2.0])  # and the filter's mode at the plant's zero
    assert np.allclose(_sorted(d.closed_loop.poles), expected, rtol=1e-7)
    for p in POLES:
        assert np.min(np.abs(expected - p)) < 1e-7 * abs(p)
    cl = d.closed_loop
    for s in (0.5, 3j, 1.0 + 10j):  # y/xD with xD' = s xD, xD'' = s^2 xD
        w = np.zeros(len(cl.inputs), complex)
        w[:3] = [1.0, s, s * s]
        x = np.linalg.solve(s * np.eye(len(cl.A)) - cl.A, cl.B @ w)
        assert complex(cl.C[0] @ x + cl.D[0] @ w) == pytest.approx(1.0, rel=1e-9)
