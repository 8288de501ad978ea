"""Arithmetic that keeps numeric zeros and ones exact, so CasADi sees no structural zeros."""

from __future__ import annotations

import casadi as ca

from designkit.models.exact_arithmetic import add, add_all, cross, mul, rot_t, rz, scalar, sub, vadd


def test_numeric_zeros_and_ones_never_reach_the_graph():
    x = ca.SX.sym("x")
    assert mul(0.0, x) == 0.0 and isinstance(mul(x, 0.0), float)
    assert mul(1.0, x) is x and mul(x, 1.0) is x
    assert ca.is_equal(mul(-1.0, x), -x, 1)
    assert add(0.0, x) is x and add(x, 0.0) is x
    assert sub(x, 0.0) is x and ca.is_equal(sub(0.0, x), -x, 1)
    assert add_all() == 0.0 and add_all(0.0, x, 0.0) is x
    assert ca.is_equal(mul(2.0, x), 2.0 * x, 1)


def test_vectors_match_numpy_on_numbers():
    a, b = [1.0, 2.0, 3.0], [-1.0, 0.5, 2.0]
    assert cross(a, b) == [2.0 * 2.0 - 3.0 * 0.5, 3.0 * -1.0 - 1.0 * 2.0, 1.0 * 0.5 - 2.0 * -1.0]
    assert vadd(a, b, a) == [1.0, 4.5, 8.0]
    R = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]  # Rz(90 deg)
    assert rot_t(R, [0.0, 1.0, 0.0]) == [1.0, 0.0, 0.0]
    assert rz(0.0, 1.0, [1.0, 0.0, 5.0]) == [0.0, 1.0, 5.0]


def test_scalar_unwraps_constant_sx():
    x = ca.SX.sym("x")
    assert scalar(ca.SX(2.5)) == 2.5 and isinstance(scalar(ca.SX(2.5)), float)
    assert scalar(x) is x
