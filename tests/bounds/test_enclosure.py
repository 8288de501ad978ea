"""Proven ranges by branch and bound (designkit.bounds.enclose): soundness, tightness, witnesses, limits.

Independent routes: closed-form ranges (the two-link arm's ``D_11 = a + 2 b cos q2`` from its textbook
formula and the arm's description; a Gaussian bump's maximum), dense grids and random samples of the
function evaluated by CasADi in floating point, and mpmath at 60 digits at the witnesses.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.bounds import enclose
from designkit.errors import SpecError

# the planar two-link arm of the zoo (designkit.models.robots.planar2r): link lengths, masses, centres of mass
# (from each joint) and moments of inertia about the centres of mass, from its description
L1, LC1, LC2, M1, M2, I1, I2 = 0.5, 0.25, 0.2, 5.0, 3.0, 5.0 * 0.5**2 / 12, 3.0 * 0.4**2 / 12
A = I1 + M1 * LC1**2 + I2 + M2 * (L1**2 + LC2**2)  # D_11 = A + 2 B cos q2 (Spong, Hutchinson & Vidyasagar, eq. 7.87)
B = M2 * L1 * LC2


def _closed_form_range(lo: float, hi: float) -> tuple[float, float]:
    """min and max of cos over [lo, hi], analytically (the extrema of cos are at multiples of pi or the ends)."""
    candidates = [math.cos(lo), math.cos(hi)]
    k0, k1 = math.ceil(lo / math.pi), math.floor(hi / math.pi)
    candidates += [math.cos(k * math.pi) for k in range(k0, k1 + 1)]
    return A + 2 * B * min(candidates), A + 2 * B * max(candidates)


@settings(max_examples=25, deadline=None)
@given(lo=st.floats(-6, 6), width=st.floats(0, 6))
def test_two_link_inertia_against_its_closed_form_to_the_tolerance(lo, width):
    import designkit as dk

    hi = lo + width
    arm = dk.robot("planar2r")
    assert arm.mass_matrix([0.3, 1.1])[0, 0] == pytest.approx(A + 2 * B * math.cos(1.1), rel=1e-12)  # the formula
    e = enclose(arm.functions["mass_matrix"], {"q": ([0.0, lo], [0.0, hi])}, index=(0, 0), rel_tol=1e-6)
    d_min, d_max = _closed_form_range(lo, hi)
    assert e.lower <= d_min + 1e-15 and e.upper >= d_max - 1e-15
    assert d_min - e.lower <= 1e-6 * d_min + 1e-12 and e.upper - d_max <= 1e-6 * d_max + 1e-12
    assert e.min_value == pytest.approx(d_min, rel=1.1e-6) and e.max_value == pytest.approx(d_max, rel=1.1e-6)
    for arg in (e.argmin["q"], e.argmax["q"]):
        assert lo <= arg[1] <= hi


def test_a_narrow_peak_between_grid_points_is_bounded_and_found():
    x = ca.SX.sym("x")
    f = ca.Function("bump", [x], [ca.exp(-((x - 0.123) / 0.004) ** 2) + 0.5 * x], ["x"], ["y"])
    grid = np.linspace(0, 1, 7)
    on_grid = np.array([float(f(v)) for v in grid]).max()  # 0.5 at x = 1: the grid misses the peak
    e = enclose(f, {"x": (0.0, 1.0)}, rel_tol=1e-9)
    near = np.linspace(0.11, 0.135, 250_001)
    true_max = np.asarray(f.map(near.size)(near[None, :])).max()  # a 1e-7 rad grid around the peak
    assert on_grid < 0.6 < e.max_value
    assert e.upper >= true_max - 1e-12 and e.upper - e.max_value <= 1e-9 * e.max_value
    assert abs(e.argmax["x"][0] - 0.123) < 1e-3


def _random_function(seed: int):
    rng = np.random.default_rng(seed)
    x = ca.SX.sym("x", 3)
    c = rng.uniform(-2, 2, size=6)
    expr = (c[0] * ca.sin(x[0] + c[1]) * ca.cos(x[1]) + c[2] * x[2] ** 2 / (1.5 + ca.cos(x[0] * x[1]))
            + c[3] * ca.exp(0.3 * x[1]) * x[0] + c[4] * (x[0] - x[2]) ** 3 + c[5] * ca.sqrt(1 + x[1] ** 2))
    return ca.Function("g", [x], [expr], ["x"], ["y"])


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), centre=st.lists(st.floats(-2, 2), min_size=3, max_size=3),
       width=st.floats(0.01, 2.0))
def test_the_enclosure_contains_a_dense_sample_of_random_expressions(seed, centre, width):
    f = _random_function(seed)
    lo, hi = np.array(centre) - width / 2, np.array(centre) + width / 2
    e = enclose(f, {"x": (lo, hi)}, rel_tol=1e-3, abs_tol=1e-9)
    rng = np.random.default_rng(seed + 1)
    grid = np.array(np.meshgrid(*[np.linspace(a, b, 9) for a, b in zip(lo, hi, strict=True)])).reshape(3, -1).T
    pts = np.vstack([rng.uniform(lo, hi, size=(3000, 3)), grid])
    values = np.asarray(f.map(len(pts))(pts.T)).reshape(-1)
    slack = 1e-12 * (1 + np.abs(values).max())  # the samples' own floating-point rounding
    assert e.lower <= values.min() + slack and e.upper >= values.max() - slack
    # the witnesses are points of the box whose values are the ones reported
    for arg, value in ((e.argmin["x"], e.min_value), (e.argmax["x"], e.max_value)):
        assert np.all(arg >= lo) and np.all(arg <= hi)
        assert float(f(arg)) == pytest.approx(value, rel=1e-12, abs=1e-12)
    assert values.max() <= e.max_value + 1e-3 * abs(e.max_value) + 1e-9 + slack  # the witness within the tolerance


def test_thresholds_stop_the_search_once_decided():
    import designkit as dk

    f = dk.robot("planar2r").functions["mass_matrix"]
    box = {"q": ([0.0, -1.0], [0.0, 2.0])}
    proven = enclose(f, box, index=(0, 0), rel_tol=0.5, thresholds=(None, 2.0))  # max is A + 2B = 1.927 < 2
    assert proven.upper < 2.0 and proven.high.stop == "threshold"
    witnessed = enclose(f, box, index=(0, 0), rel_tol=0.5, thresholds=(None, 1.9))
    assert witnessed.max_value >= 1.9 and witnessed.high.stop == "threshold"


def test_the_work_limit_is_refused_with_the_gap_or_returned_unconverged():
    f = _random_function(3)
    box = {"x": (-2.0, 2.0)}
    with pytest.raises(SpecError, match=r"rel_tol: .*needs more than 5 boxes.*gap") as err:
        enclose(f, box, rel_tol=1e-12, max_boxes=5)
    assert err.value.path == "rel_tol"
    e = enclose(f, box, rel_tol=1e-12, max_boxes=5, strict=False)
    assert not e.converged and e.boxes <= 2 * (5 + 2)
    pts = np.random.default_rng(0).uniform(-2, 2, size=(2000, 3))
    values = np.asarray(f.map(len(pts))(pts.T)).reshape(-1)
    assert e.lower <= values.min() and e.upper >= values.max()  # the bounds hold all the same


@pytest.mark.parametrize("box, kwargs, path", [
    ({"x": (1.0, 0.0)}, {}, "box['x'][0]"),
    ({"x": ([0, 0, 0], [1, math.inf, 1])}, {}, "box['x'].hi[1]"),
    ({"x": ([0, 0], [1, 1])}, {}, "box['x'].lo"),
    ({}, {}, "box['x']"),
    ({"x": (0, 1), "z": (0, 1)}, {}, "box['z']"),
    ({"x": (0, 1)}, {"rel_tol": 0.0}, "rel_tol"),
    ({"x": (0, 1)}, {"rel_tol": -1e-3}, "rel_tol"),
    ({"x": (0, 1)}, {"abs_tol": math.nan}, "abs_tol"),
    ({"x": (0, 1)}, {"max_boxes": 0}, "max_boxes"),
    ({"x": (0, 1)}, {"output": "nope"}, "output"),
    ({"x": (0, 1)}, {"index": (0, 5)}, "index"),
])
def test_bad_input_names_the_argument(box, kwargs, path):
    with pytest.raises(SpecError) as err:
        enclose(_random_function(1), box, **kwargs)
    assert err.value.path == path


def test_a_function_is_required():
    with pytest.raises(SpecError) as err:
        enclose(lambda x: x, {"x": (0, 1)})
    assert err.value.path == "function"
