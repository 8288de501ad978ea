"""The entry grammar over named parameters: values against Python arithmetic written out here, refusals."""

from __future__ import annotations

import casadi as ca
import pytest

from designkit.errors import ModelError
from designkit.models.expression import parse_entry

A, B = 1.5, -0.25


def _value(text):
    a, b = ca.SX.sym("a"), ca.SX.sym("b")
    return float(ca.Function("f", [a, b], [parse_entry(text, {"a": a, "b": b}, "x")])(A, B))


@pytest.mark.parametrize(("text", "expected"), [
    ("b", B), ("-a", -A), ("2*a", 2 * A), ("a + b*2", A + B * 2), ("(a + b)*2", (A + B) * 2),
    ("a/b/2", A / B / 2), ("-(a - 3)/ -b", -(A - 3) / -B), ("--a", A), ("1e-3*a", 1e-3 * A), (".5", 0.5),
    ("  a  ", A), (2.5, 2.5), (3, 3.0),
])
def test_entries_evaluate_as_arithmetic(text, expected):
    assert _value(text) == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize(("text", "words"), [
    ("", "empty"), ("a +", "ends where"), ("(a", "not closed"), ("a)", "unexpected ')'"), ("a ** 2", "unexpected '*'"),
    ("c", "unknown parameter 'c'"), ("sin(a)", "unknown parameter 'sin'"), ("a.real", "cannot read"),
    ("a; b", "cannot read"), ("1e999", "not finite"), ("x" * 201, "longer than"),
])
def test_unreadable_entries_are_refused_at_their_field(text, words):
    a = ca.SX.sym("a")
    with pytest.raises(ModelError) as info:
        parse_entry(text, {"a": a}, "A[0][1]")
    assert info.value.field == "A[0][1]" and words in info.value.message


@pytest.mark.parametrize("value", [float("nan"), float("inf"), True])
def test_non_finite_or_boolean_numbers_are_refused(value):
    with pytest.raises(ModelError):
        parse_entry(value, {}, "den[1]")
