"""Scalar and 3-vector arithmetic that keeps numeric zeros and ones exact.

The dynamics builders (:mod:`designkit.models.newton_euler`,
:mod:`designkit.models.inertial_parameters`) mix Python floats and CasADi ``SX``
scalars.  These helpers multiply by an exact ``0.0`` to ``0.0``, by ``1.0`` or
``-1.0`` to the other operand (or its negation), and add ``0.0`` to nothing, so
structural zeros of a numeric description never enter the expression graph and
CasADi folds the remaining constants.

Vectors are lists of three scalars, matrices 3x3 nested lists.
"""

from __future__ import annotations

from typing import Any

from designkit.models.chain import numeric_value

Vec = list  # three scalars (float or casadi.SX)
Mat = list  # 3x3 nested list of scalars

__all__ = [
    "Mat",
    "Vec",
    "add",
    "add_all",
    "cross",
    "dot",
    "matmul",
    "mul",
    "rot",
    "rot_t",
    "rz",
    "rz_t",
    "scalar",
    "sub",
    "vadd",
    "vscale",
]


def _is(x: Any, value: float) -> bool:
    """True when ``x`` is a Python number equal to ``value`` (never for an ``SX``)."""
    return isinstance(x, int | float) and x == value


def mul(a: Any, b: Any) -> Any:
    """``a * b``, exactly ``0.0`` when a factor is a numeric zero, the other factor when one is +-1."""
    if _is(a, 0.0) or _is(b, 0.0):
        return 0.0
    if _is(a, 1.0):
        return b
    if _is(b, 1.0):
        return a
    if _is(a, -1.0):
        return -b
    if _is(b, -1.0):
        return -a
    return a * b


def add(a: Any, b: Any) -> Any:
    """``a + b``, the other term when one is a numeric zero."""
    if _is(a, 0.0):
        return b
    if _is(b, 0.0):
        return a
    return a + b


def sub(a: Any, b: Any) -> Any:
    """``a - b``, dropping a numeric-zero term."""
    if _is(b, 0.0):
        return a
    if _is(a, 0.0):
        return -b
    return a - b


def add_all(*terms: Any) -> Any:
    """Sum of ``terms`` by :func:`add` (``0.0`` for none)."""
    total: Any = 0.0
    for t in terms:
        total = add(total, t)
    return total


def vadd(*vectors: Vec) -> Vec:
    """Sum of 3-vectors."""
    return [add_all(*(v[k] for v in vectors)) for k in range(3)]


def vscale(s: Any, v: Vec) -> Vec:
    """``s * v``."""
    return [mul(s, x) for x in v]


def cross(a: Vec, b: Vec) -> Vec:
    """``a x b``."""
    return [
        sub(mul(a[1], b[2]), mul(a[2], b[1])),
        sub(mul(a[2], b[0]), mul(a[0], b[2])),
        sub(mul(a[0], b[1]), mul(a[1], b[0])),
    ]


def dot(a: Vec, b: Vec) -> Any:
    """``a . b``."""
    return add_all(*(mul(x, y) for x, y in zip(a, b, strict=True)))


def rot(R: Mat, v: Vec) -> Vec:
    """``R @ v``."""
    return [add_all(*(mul(R[r][c], v[c]) for c in range(3))) for r in range(3)]


def rot_t(R: Mat, v: Vec) -> Vec:
    """``R.T @ v``."""
    return [add_all(*(mul(R[r][c], v[r]) for r in range(3))) for c in range(3)]


def matmul(A: Mat, B: Mat) -> Mat:
    """``A @ B`` (3x3)."""
    return [[add_all(*(mul(A[r][k], B[k][c]) for k in range(3))) for c in range(3)] for r in range(3)]


def rz_t(c: Any, s: Any, v: Vec) -> Vec:
    """``Rz(theta).T @ v`` from ``c = cos(theta)``, ``s = sin(theta)``."""
    return [add(mul(c, v[0]), mul(s, v[1])), sub(mul(c, v[1]), mul(s, v[0])), v[2]]


def rz(c: Any, s: Any, v: Vec) -> Vec:
    """``Rz(theta) @ v``."""
    return [sub(mul(c, v[0]), mul(s, v[1])), add(mul(s, v[0]), mul(c, v[1])), v[2]]


def scalar(x: Any) -> Any:
    """``x`` as a float when it is a numeric constant (an ``SX`` constant included), else ``x`` itself."""
    value = numeric_value(x)
    return value if value is not None else x
