"""LP core: optimum against scipy's HiGHS and the exact vertex formula, certified verdicts
against vertex evaluation, counterexamples, Farkas certificates and every undecided path."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.optimize
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from designkit.synthesis.design import LinearCondition
from designkit.verification import lp_feasibility, robust_linear
from designkit.verification.lp import LpSolution, Polytope, solve_lp
from designkit.verification.lp_certificates import LowerBoundCertificate
from designkit.verification.lp_feasibility import linear_feasibility
from designkit.verification.robust_linear import robust_linear_conditions
from designkit.verification.tolerances import LP_EPS


@st.composite
def boxes(draw, max_dim: int = 4):
    """A parameter box (names, lo, hi) with lo < hi."""
    n = draw(st.integers(1, max_dim))
    lo = np.array([draw(st.floats(-5.0, 5.0)) for _ in range(n)])
    width = np.array([draw(st.floats(0.01, 5.0)) for _ in range(n)])
    return tuple(f"p{j}" for j in range(n)), lo, lo + width


def _box_minimum(c: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Exact minimum of c . theta over a box: theta_j = lo_j if c_j > 0 else hi_j."""
    return float(np.sum(np.where(c > 0, c * lo, c * hi)))


@settings(max_examples=30, deadline=None)
@given(box=boxes(), seed=st.integers(0, 100_000), cuts=st.integers(0, 3))
def test_lp_optimum_agrees_with_linprog_and_the_vertex_oracle(box, seed, cuts):
    names, lo, hi = box
    n = len(names)
    rng = np.random.default_rng(seed)
    c = rng.normal(size=n)
    poly = Polytope.box(names, lo, hi)
    if cuts:  # extra random half spaces that keep the box centre inside: a general polytope
        G = rng.normal(size=(cuts, n))
        centre = 0.5 * (lo + hi)
        h = G @ centre + rng.uniform(0.1, 2.0, size=cuts) * np.linalg.norm(G, axis=1)
        poly = Polytope(names, np.vstack([poly.A, G]), np.concatenate([poly.b, h]))
    sol = solve_lp(c, poly.A, poly.b)
    assert sol.status == "optimal"
    ref = scipy.optimize.linprog(c, A_ub=poly.A, b_ub=poly.b, bounds=[(None, None)] * n, method="highs")
    assert ref.status == 0
    scale = 1.0 + float(np.sum(np.abs(c) * np.maximum(np.abs(lo), np.abs(hi))))
    assert abs(sol.value - ref.fun) <= 1e-7 * scale
    assert abs(float(c @ sol.x) - ref.fun) <= 1e-7 * scale
    if not cuts:
        assert abs(ref.fun - _box_minimum(c, lo, hi)) <= 1e-9 * scale
    # the re-checked dual bound is a rigorous lower bound, and tight
    blo, bhi = poly.bounding_box()
    cert = LowerBoundCertificate(0.0, c, poly.A, poly.b, np.maximum(sol.dual, 0.0), blo, bhi, LP_EPS)
    lower = cert.recheck().values["lower_bound"]
    assert lower <= ref.fun + 1e-12 * scale
    assert lower >= ref.fun - 1e-6 * scale


@settings(max_examples=30, deadline=None)
@given(box=boxes(), seed=st.integers(0, 100_000), offset=st.floats(-3.0, 3.0))
def test_certified_verdict_agrees_with_evaluation_at_all_vertices(box, seed, offset):
    names, lo, hi = box
    rng = np.random.default_rng(seed)
    coefficients = dict(zip(names, rng.normal(size=len(names)), strict=True))
    c = np.array(list(coefficients.values()))
    corners = np.array(np.meshgrid(*zip(lo, hi, strict=True), indexing="ij")).reshape(len(names), -1).T
    constant = offset - float(np.min(corners @ c))  # the minimum over the box is offset
    vertex_min = float(np.min(constant + corners @ c))
    size = abs(constant) + float(np.sum(np.abs(c) * np.maximum(np.abs(lo), np.abs(hi))))
    # too thin to decide: a certified margin below eps, or a minimum within rounding of zero
    assume(not (-1e-12 * size < vertex_min <= 10 * LP_EPS * size))
    check = robust_linear_conditions("robust", [LinearCondition("cond", constant, coefficients, "N")],
                                     Polytope.box(names, lo, hi))
    if vertex_min > 0:
        assert check.passed is True, check.detail
        entry = check.certificate["conditions"][0]
        assert 0 < entry["certified_lower_bound"] <= vertex_min + 1e-12 * size
    else:
        assert check.passed is False, check.detail
        theta = np.array([check.certificate["evidence"]["theta"][n] for n in names])
        assert np.all((theta >= lo) & (theta <= hi))  # a point of the box
        assert constant + theta @ c <= 0
    json.dumps(check.to_dict(), allow_nan=False)


def test_failing_condition_returns_the_counterexample_vertex():
    """1 - a - b > 0 on [0, 1]^2 fails at the vertex (1, 1), where it is -1."""
    check = robust_linear_conditions(
        "robust", [LinearCondition("1 - a - b > 0", 1.0, {"a": 1.0, "b": 1.0} | {"a": -1.0, "b": -1.0})],
        Polytope.box(["a", "b"], [0.0, 0.0], [1.0, 1.0]),
    )
    assert check.passed is False
    ev = check.certificate["evidence"]
    assert ev["theta"] == {"a": 1.0, "b": 1.0}
    assert ev["value"] == -1.0
    assert ev["condition"] == "1 - a - b > 0"


def test_passing_and_failing_conditions_together_fail():
    box = Polytope.box(["Km", "tau"], [0.5, 0.1], [2.0, 1.0])
    good = LinearCondition("good", 1.0, {"Km": 0.2, "tau": -0.5}, "1/s")  # min 1 + 0.1 - 0.5 = 0.6
    bad = LinearCondition("bad", 0.2, {"tau": -0.5}, "1/s")  # min 0.2 - 0.5 = -0.3
    assert robust_linear_conditions("r", [good], box).passed is True
    check = robust_linear_conditions("r", [good, bad], box)
    assert check.passed is False
    assert check.certificate["evidence"]["condition"] == "bad"
    assert check.certificate["conditions"][0]["certified_lower_bound"] == pytest.approx(0.6, rel=1e-6)


TRIANGLE = Polytope(
    ("a", "b"),
    np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
    np.array([0.0, 0.0, 1.0, 1.0, 1.0]),
)  # a, b >= 0, a + b <= 1, with the bounding rows a, b <= 1


def test_general_polytope_certificate_and_counterexample():
    """On the triangle the minimum of -(a + b)/2 is -1/2 (on the edge a + b = 1); over its
    bounding box it would be -1, so a pass needs the dual of the cut a + b <= 1."""
    assert not TRIANGLE.is_box
    ok = robust_linear_conditions("t", [LinearCondition("c", 0.55, {"a": -0.5, "b": -0.5})], TRIANGLE)
    assert ok.passed is True, ok.detail
    assert ok.certificate["conditions"][0]["certified_lower_bound"] == pytest.approx(0.05, rel=1e-6)
    bad = robust_linear_conditions("t", [LinearCondition("c", 0.45, {"a": -0.5, "b": -0.5})], TRIANGLE)
    assert bad.passed is False
    ev = bad.certificate["evidence"]
    theta = np.array([ev["theta"]["a"], ev["theta"]["b"]])
    assert ev["source"] == "LP minimiser"
    assert TRIANGLE.contains(theta) and 0.45 - 0.5 * theta.sum() <= 0


def test_a_bad_dual_leaves_the_condition_undecided(monkeypatch):
    """The solver claims optimal with zero multipliers: the re-check only has the bounding box,
    where the condition's minimum is -0.45, so it cannot certify; the point is no counterexample."""
    fake = LpSolution(np.array([0.5, 0.5]), -0.5, np.zeros(5), "optimal", "CLARABEL")
    monkeypatch.setattr(robust_linear, "solve_lp", lambda c, G, h, solver: fake)
    check = robust_linear_conditions("t", [LinearCondition("c", 0.55, {"a": -0.5, "b": -0.5})], TRIANGLE)
    assert check.passed is None
    assert check.certificate["conditions"][0]["certified_lower_bound"] < 0


def test_solver_failure_is_undecided_but_a_counterexample_still_fails(monkeypatch):
    box = Polytope.box(["a"], [0.0], [1.0])
    holds = LinearCondition("holds", 1.0, {"a": 1.0})
    fails = LinearCondition("fails", -0.5, {"a": 1.0})  # -0.5 at a = 0, found without the solver
    assert robust_linear_conditions("r", [holds], box, solver="NO_SUCH_SOLVER").passed is None
    assert robust_linear_conditions("r", [fails], box, solver="NO_SUCH_SOLVER").passed is False
    good = solve_lp(np.array([1.0]), box.A, box.b)
    inaccurate = LpSolution(good.x, good.value, good.dual, "optimal_inaccurate", "CLARABEL")
    monkeypatch.setattr(robust_linear, "solve_lp", lambda c, G, h, solver: inaccurate)
    check = robust_linear_conditions("r", [holds], box)
    assert check.passed is None and "optimal_inaccurate" in check.detail


@st.composite
def systems(draw):
    """(G, h, feasible): feasible ones around a point x0 with positive slack; infeasible ones
    with a row that contradicts a positive combination of the others by delta > 0."""
    seed = draw(st.integers(0, 100_000))
    rng = np.random.default_rng(seed)
    n, m = draw(st.integers(1, 4)), draw(st.integers(1, 5))
    G = rng.normal(size=(m, n))
    x0 = rng.normal(size=n)
    h = G @ x0 + rng.uniform(0.05, 1.0, size=m) * np.linalg.norm(G, axis=1)
    if draw(st.booleans()):
        return G, h, True
    y0 = rng.uniform(0.1, 1.0, size=m)
    delta = draw(st.floats(0.05, 2.0))
    # row -y0'G with right-hand side -y0'h - delta: y = [y0, 1] is a Farkas vector
    return np.vstack([G, -(y0 @ G)]), np.concatenate([h, [-(y0 @ h) - delta]]), False


@settings(max_examples=30, deadline=None)
@given(system=systems())
def test_feasibility_verdict_agrees_with_linprog_and_certificates_recheck(system):
    G, h, feasible = system
    result = linear_feasibility(G, h)
    ref = scipy.optimize.linprog(np.zeros(G.shape[1]), A_ub=G, b_ub=h, bounds=[(None, None)] * G.shape[1],
                                 method="highs")
    assert ref.status == (0 if feasible else 2)
    assert result.feasible is feasible, result.detail
    if feasible:
        assert np.all(h - G @ result.x > 0)  # slacks, independently
        np.testing.assert_allclose(result.slacks, h - G @ result.x)
    else:
        y = result.farkas.y
        assert np.all(y >= 0)
        assert np.linalg.norm(G.T @ y) <= 1e-8 * float(y @ np.linalg.norm(G, axis=1))
        assert h @ y < 0
    json.dumps(result.to_check().to_dict(), allow_nan=False)


def test_farkas_certificate_of_contradicting_bounds():
    """x <= -1 and x >= 1: y = (1, 1)/2 gives G'y = 0 and h . y = -1."""
    result = linear_feasibility(np.array([[1.0], [-1.0]]), np.array([-1.0, -1.0]), names=["x"])
    assert result.feasible is False
    np.testing.assert_allclose(result.farkas.y / result.farkas.y.sum(), [0.5, 0.5], atol=1e-8)
    check = result.to_check()
    assert check.passed is False and "farkas_y" in check.certificate["evidence"]


def test_zero_row_with_negative_bound_is_infeasible_without_the_solver():
    result = linear_feasibility(np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([-1.0, 1.0]), solver="NO_SUCH_SOLVER")
    assert result.feasible is False
    assert result.status == "not solved"


def test_feasibility_solver_failure_is_undecided(monkeypatch):
    G, h = np.array([[1.0], [-1.0]]), np.array([1.0, 1.0])
    assert linear_feasibility(G, h, solver="NO_SUCH_SOLVER").feasible is None
    fake = LpSolution(np.array([0.0, 1.0]), -1.0, np.array([0.5, 0.5, 0.0]), "optimal_inaccurate", "CLARABEL")
    monkeypatch.setattr(lp_feasibility, "solve_lp", lambda c, G, h, solver: fake)
    result = linear_feasibility(G, h)
    assert result.feasible is None
    assert result.to_check().status == "UNDECIDED"


def test_optimal_status_with_a_wrong_point_is_undecided(monkeypatch):
    """The solver claims x = 5 (outside 0 <= x <= 1) with margin 1 and no useful dual."""
    G, h = np.array([[1.0], [-1.0]]), np.array([1.0, 0.0])
    fake = LpSolution(np.array([5.0, 1.0]), -1.0, np.zeros(3), "optimal", "CLARABEL")
    monkeypatch.setattr(lp_feasibility, "solve_lp", lambda c, G, h, solver: fake)
    assert linear_feasibility(G, h).feasible is None


def test_polytope_helpers():
    box = Polytope.box(["a", "b", "c"], [0.0, -1.0, 2.0], [1.0, 1.0, 3.0])
    assert box.is_box
    assert box.vertices().shape == (8, 3)
    assert {tuple(v) for v in box.vertices()} >= {(0.0, -1.0, 2.0), (1.0, 1.0, 3.0)}
    with pytest.raises(ValueError):
        TRIANGLE.vertices()
    scaled = Polytope(("a",), np.array([[3.0], [-3.0]]), np.array([1.0, 1.0]))  # |a| <= 1/3
    lo, hi = scaled.bounding_box()
    assert lo[0] <= -1.0 / 3.0 and hi[0] >= 1.0 / 3.0  # rounded outwards
    assert hi[0] - 1.0 / 3.0 < 1e-15
    with pytest.raises(ValueError):
        LinearCondition("x", 1.0, {"nope": 1.0}).vector(["a"])
    assert LinearCondition("x", 1.0, {"a": 2.0, "b": 3.0}).at(np.array([1.0, 1.0]), ["a", "b"]) == 6.0
