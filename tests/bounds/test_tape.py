"""Ball evaluation of CasADi expression graphs (designkit.bounds.tape) against mpmath.

Independent routes: mpmath at 60 digits for the exact value of an expression at a point (so a float's
own rounding cannot make a sound enclosure look unsound), and mpmath's interval arithmetic (``mpmath.iv``)
for the natural interval extension of expressions in which no variable repeats (whose extension is the
exact range, so both libraries must give it to rounding).
"""

from __future__ import annotations

import math

import casadi as ca
import mpmath
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from designkit.bounds.tape import compile_tape, evaluate, lower_float, span_ball, upper_float
from designkit.errors import SpecError

mpmath.mp.dps = 60

# ----------------------------------------------------------------------------- random expressions

UNARY = {
    "sin": (ca.sin, mpmath.sin), "cos": (ca.cos, mpmath.cos),
    "exp": (lambda x: ca.exp(x / 4), lambda x: mpmath.exp(x / 4)),
    "sq": (lambda x: x**2, lambda x: x**2), "cube": (lambda x: x**3, lambda x: x**3),
    "neg": (lambda x: -x, lambda x: -x),
    "abs": (ca.fabs, abs), "atan": (ca.atan, mpmath.atan), "sqrt1": (lambda x: ca.sqrt(1 + x**2),
                                                                     lambda x: mpmath.sqrt(1 + x**2)),
    "tanh": (ca.tanh, mpmath.tanh),
}
BINARY = {
    "add": (lambda a, b: a + b, lambda a, b: a + b), "sub": (lambda a, b: a - b, lambda a, b: a - b),
    "mul": (lambda a, b: a * b, lambda a, b: a * b),
    "div": (lambda a, b: a / (2 + ca.sin(b)), lambda a, b: a / (2 + mpmath.sin(b))),  # denominator in [1, 3]
    "max": (ca.fmax, max), "min": (ca.fmin, min),
}


def _tree(depth: int):
    # every leaf holds a variable: CasADi folds a constant subexpression into one float when the function is built,
    # which is then the function's exact value, not the real-number value mpmath would give the subexpression
    leaf = st.one_of(st.sampled_from(["x0", "x1", "x2"]),
                     st.tuples(st.just("add"), st.sampled_from(["x0", "x1", "x2"]),
                               st.floats(-3, 3, allow_nan=False).map(lambda v: round(v, 3))))
    if depth == 0:
        return leaf
    sub = _tree(depth - 1)
    return st.one_of(leaf, st.tuples(st.sampled_from(sorted(UNARY)), sub),
                     st.tuples(st.sampled_from(sorted(BINARY)), sub, sub))


def _build(node, x, table_index: int):
    if isinstance(node, str):
        return x[int(node[1])]
    if isinstance(node, float):
        return node if table_index == 1 else ca.SX(node)
    if len(node) == 2:
        return UNARY[node[0]][table_index](_build(node[1], x, table_index))
    return BINARY[node[0]][table_index](_build(node[1], x, table_index), _build(node[2], x, table_index))


def _folds_to_a_constant(node) -> bool:
    """Whether CasADi simplifies a subexpression of ``node`` to a constant (``x0 - (x0 + 1)`` is ``-1``): it then
    folds what follows into one float, the built function's exact value, which mpmath's real-number value is not."""
    if isinstance(node, str):
        return False
    x = ca.SX.sym("x", 3)
    if ca.SX(_build(node, [x[0], x[1], x[2]], 0)).is_constant():
        return True
    return any(_folds_to_a_constant(child) for child in node[1:] if not isinstance(child, float))


boxes = st.lists(st.tuples(st.floats(-3, 3), st.floats(0, 2)), min_size=3, max_size=3).map(
    lambda sides: [(c, c + w) for c, w in sides])


@settings(max_examples=60, deadline=None)
@given(node=_tree(4), box=boxes, seed=st.integers(0, 2**31))
def test_natural_extension_contains_every_exact_value_of_random_expressions(node, box, seed):
    assume(not _folds_to_a_constant(node))
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [ca.SX(_build(node, [x[0], x[1], x[2]], 0))], ["x"], ["y"])
    tape = compile_tape(f)
    out = evaluate(tape, [span_ball(lo, hi) for lo, hi in box])[0]
    lo, hi = lower_float(out), upper_float(out)
    rng = np.random.default_rng(seed)
    points = [np.array([a for a, _ in box]), np.array([b for _, b in box])]
    points += list(rng.uniform([a for a, _ in box], [b for _, b in box], size=(40, 3)))
    for p in points:
        exact = _build(node, [mpmath.mpf(float(v)) for v in p], 1)
        # mpmath rounds each of its own operations at its working precision: (sqrt(1 + 2))^2 is 5 + 6e-61 there
        slack = mpmath.mpf(2) ** (8 - mpmath.mp.prec) * (1 + abs(exact))
        assert mpmath.mpf(lo) - slack <= exact <= mpmath.mpf(hi) + slack, (node, p, exact, lo, hi)


small_boxes = st.lists(st.tuples(st.floats(-3, 3), st.floats(0, 1e-3)), min_size=3, max_size=3).map(
    lambda sides: [(c, c + w) for c, w in sides])


@settings(max_examples=40, deadline=None)
@given(box=small_boxes, kind=st.sampled_from(["a", "b", "c"]))
def test_agrees_with_mpmath_interval_arithmetic_where_the_extension_is_exact(box, kind):
    """Each variable occurs once, so mpmath's interval extension is the exact range (to its 30 digits); the balls
    contain it, wider only by the ball product's second-order excess (boxes up to 1e-3 wide: ~1e-6)."""
    iv = mpmath.iv
    iv.dps = 30
    expr = {
        "a": (lambda x: ca.sin(x[0]) + ca.exp(x[1] / 4) * (x[2] + 4),
              lambda x: iv.sin(x[0]) + iv.exp(x[1] / 4) * (x[2] + 4)),
        "b": (lambda x: x[0] ** 3 - ca.cos(x[1]) * 2 + x[2] ** 2, lambda x: x[0] ** 3 - iv.cos(x[1]) * 2 + x[2] ** 2),
        "c": (lambda x: (x[0] + 5) * (x[1] - 7) / (x[2] + 9), lambda x: (x[0] + 5) * (x[1] - 7) / (x[2] + 9)),
    }[kind]
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [expr[0]([x[0], x[1], x[2]])], ["x"], ["y"])
    ball = evaluate(compile_tape(f), [span_ball(lo, hi) for lo, hi in box])[0]
    ref = expr[1]([iv.mpf([lo, hi]) for lo, hi in box])
    ref_lo, ref_hi = float(ref.a), float(ref.b)
    scale = 1 + max(abs(ref_lo), abs(ref_hi))
    assert lower_float(ball) <= ref_lo + 1e-15 * scale and upper_float(ball) >= ref_hi - 1e-15 * scale
    assert ref_lo - lower_float(ball) <= 1e-5 * scale and upper_float(ball) - ref_hi <= 1e-5 * scale


def test_even_powers_abs_and_sign_are_taken_from_the_endpoints():
    x = ca.SX.sym("x")
    for expr, expected in ((x**2, (0.0, 4.0)), (x**4, (0.0, 16.0)), (ca.fabs(x), (0.0, 2.0)), (ca.sign(x), (-1.0, 1.0)),
                           (ca.constpow(x, 6), (0.0, 64.0))):
        ball = evaluate(compile_tape(ca.Function("f", [x], [expr])), [span_ball(-1.0, 2.0)])[0]
        lo, hi = lower_float(ball), upper_float(ball)
        assert lo <= expected[0] and hi >= expected[1]
        slack = 1e-7 * (1 + max(abs(v) for v in expected))  # 30-bit radii: ~1e-9 of a width, times the power
        assert lo == pytest.approx(expected[0], abs=slack) and hi == pytest.approx(expected[1], abs=slack)


def test_outward_rounding_brackets_the_ball():
    from flint import arb

    for v in (0.1, 1 / 3, math.pi, -2.5e-300, 1e300):
        b = arb(v) / 3
        assert arb(lower_float(b)) <= b and arb(upper_float(b)) >= b
    assert lower_float(arb(1) / arb(0)) == -math.inf and upper_float(arb("nan")) == math.inf


def test_structural_zeros_and_several_inputs():
    a, b = ca.SX.sym("a", 2), ca.SX.sym("b")
    f = ca.Function("f", [a, b], [ca.vertcat(a[0] * b, 0, a[1])], ["a", "b"], ["y"])
    out = evaluate(compile_tape(f), [span_ball(1, 2), span_ball(3, 4), span_ball(-1, 1)])
    assert len(out) == 3 and lower_float(out[0]) <= -2 and upper_float(out[0]) >= 2 and out[1].is_zero()


def test_an_operation_without_an_enclosure_is_named():
    x = ca.SX.sym("x", 2)
    with pytest.raises(SpecError, match="fmod"):
        compile_tape(ca.Function("f", [x], [ca.fmod(x[0], x[1])]))


def test_the_oracle_sets_aside_expressions_casadi_folds_to_a_float():
    # atan(x0 - (x0 + 1)) is built as the float nearest -pi/4, above -pi/4: no enclosure of the built function holds
    # the real value, so the random-expression test draws no such expression
    assert _folds_to_a_constant(("atan", ("sub", "x0", ("add", "x0", 1.0))))
    assert not _folds_to_a_constant(("atan", ("sub", "x0", ("add", "x1", 1.0))))
