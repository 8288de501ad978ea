"""Condition certificates: the form read off the expression, the vertex theorem against a dense grid, LP for affine."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.verification.conditions import Condition, ConditionSet, certify, form_of


def _form(fn, k=2):
    theta = ca.SX.sym("t", k)
    return form_of(fn(theta), theta)


def test_the_form_is_read_off_the_expression():
    assert _form(lambda t: 3 + 2 * t[0] - t[1]) == "affine"
    assert _form(lambda t: 4 * 30 * t[0] * t[1] - 1) == "multiaffine"
    assert _form(lambda t: t[0] * t[1] * (t[0] + 1)) == "general"
    assert _form(lambda t: 1 / t[1]) == "general"
    assert _form(lambda t: t[0] * t[1] + t[0] * t[2] - t[1] * t[2] * t[0], k=3) == "multiaffine"


coefficient = st.floats(-5, 5, allow_nan=False, allow_infinity=False)


@settings(max_examples=40, deadline=None)
@given(c=st.lists(coefficient, min_size=8, max_size=8), lo=st.lists(st.floats(-3, 2), min_size=3, max_size=3),
       width=st.lists(st.floats(0.1, 3), min_size=3, max_size=3))
def test_a_multiaffine_minimum_over_a_box_is_at_a_vertex(c, lo, width):
    """The certificate's minimum equals the minimum over a dense grid of the box (the theorem), and its verdict is
    the grid's sign (within the rounding margin)."""
    def g(p):
        x, y, z = p["x"], p["y"], p["z"]
        return c[0] + c[1] * x + c[2] * y + c[3] * z + c[4] * x * y + c[5] * x * z + c[6] * y * z + c[7] * x * y * z

    box = {n: (a, a + w) for n, a, w in zip("xyz", lo, width, strict=True)}
    cs = ConditionSet("a test condition", ("x", "y", "z"), (Condition("g > 0", g),))
    check = certify("t", cs, box)
    entry = check.certificate["conditions"][0]
    if entry["form"] == "affine":  # c[4..7] all zero: the LP route
        return
    axes = [np.linspace(a, b, 21) for a, b in box.values()]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    grid_min = float(np.min(g({"x": X, "y": Y, "z": Z})))
    assert entry["minimum"] == pytest.approx(grid_min, rel=1e-12, abs=1e-12)
    if grid_min > 1e-6:
        assert check.passed is True
    if grid_min < -1e-6:
        assert check.passed is False and check.certificate["evidence"]["value"] <= 0


def test_affine_conditions_go_to_the_lp_core_and_fail_with_a_counterexample():
    cs = ConditionSet("linear", ("Km", "tau"), (
        Condition("1 + 2 Km - tau > 0", lambda p: 1 + 2 * p["Km"] - p["tau"], "1"),
        Condition("tau - 0.5 > 0", lambda p: p["tau"] - 0.5, "s"),
    ))
    ok = certify("lin", cs, {"Km": (1.0, 2.0), "tau": (0.6, 0.9)})
    assert ok.passed is True and {e["form"] for e in ok.certificate["conditions"]} == {"affine"}
    assert ok.certificate["conditions"][1]["minimum"] == pytest.approx(0.1)
    bad = certify("lin", cs, {"Km": (1.0, 2.0), "tau": (0.4, 0.9)})
    assert bad.passed is False and bad.certificate["evidence"]["theta"]["tau"] == pytest.approx(0.4)


def test_a_general_condition_is_undecided_never_a_pass():
    cs = ConditionSet("curved", ("Km",), (Condition("Km^2 - 1 > 0", lambda p: p["Km"] ** 2 - 1),))
    check = certify("c", cs, {"Km": (2.0, 3.0)})
    assert check.passed is None and "neither affine nor multi-affine" in check.detail


def test_bad_boxes_are_refused():
    cs = ConditionSet("x", ("Km",), (Condition("Km > 0", lambda p: p["Km"]),))
    with pytest.raises(ValueError, match="lo <= hi"):
        certify("c", cs, {"Km": (2.0, 1.0)})
    with pytest.raises(ValueError, match="no interval"):
        certify("c", cs, {})
