"""The boundary search on planted outcomes: every change located, whatever its shape, and a recommendation only
where a whole neighbourhood passes (the runs are a known function of the value, not simulations)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from designkit.studies.boundary import PER_DECADE, REFINE, neighbourhood, search, search_grid
from designkit.studies.core.budget import Budget
from designkit.studies.core.study import Row
from designkit.synthesis.knobs import Metric


def _planted(passing, metric=lambda v: abs(math.log10(v) - 1.5), budget=None):
    """``run_many(values) -> rows``: verified where ``passing(value)``, with a metric; counts its calls and charges
    ``budget`` one second a run."""
    calls = []

    def run(v: float) -> Row:
        calls.append(v)
        if budget is not None:
            budget.record(1.0)
        ok = passing(v)
        return Row(1.0, float(v), {"m": metric(v)}, "verified" if ok else "failed", "" if ok else "planted")

    return (lambda values: [run(v) for v in values]), calls


METRIC = Metric("m", "planted metric", "", lambda r: None)
RESOLUTION = 10.0 ** (1.0 / (PER_DECADE * 2**REFINE))


def test_every_change_of_a_non_monotone_outcome_is_located():
    # passes on two separate stretches: a threshold search would report one boundary, here there are four
    edges = (10.0, 100.0, 1e3, 3e3)
    run, calls = _planted(lambda v: 10.0 <= v <= 100.0 or 1e3 <= v <= 3e3)
    rows, pick, nu, reduced = search(1.0, 1e5, run, Budget(1e9, 1.0), METRIC)
    assert reduced == ""
    changes = [(a.value, b.value) for a, b in zip(rows, rows[1:], strict=False) if a.passed != b.passed]
    assert len(changes) == 4
    for (a, b), edge in zip(changes, edges, strict=True):
        assert a <= edge * (1 + 1e-12) and b >= edge * (1 - 1e-12), (a, b, edge)
        assert b / a <= RESOLUTION * (1 + 1e-9)  # bisected REFINE times
    # the recommendation passes with both ends of its neighbourhood, every run inside passing too
    assert pick is not None
    assert math.isclose(pick.low * nu, pick.value) and math.isclose(pick.high / nu, pick.value)
    inside = [r for r in rows if pick.low * (1 - 1e-9) <= r.value <= pick.high * (1 + 1e-9)]
    assert all(r.passed for r in inside) and len(inside) >= 3
    assert pick.low >= 10.0 and pick.high <= 100.0 or pick.low >= 1e3 and pick.high <= 3e3


def test_no_recommendation_where_no_neighbourhood_fits():
    # one passing stretch narrower than a neighbourhood (nu^2 = 3.16): nothing is recommended
    run, _ = _planted(lambda v: 10.0 <= v <= 20.0)
    rows, pick, nu, _ = search(1.0, 1e4, run, Budget(1e9, 1.0), METRIC)
    assert nu**2 > 2.0
    assert pick is None
    assert any(r.passed for r in rows)


def test_the_grid_is_anchored_on_decades():
    # two searches that start from different values share their grid points: one scenario, one boundary
    a, b = search_grid(3.0, 3e4), search_grid(5.0, 3e4)
    common = np.intersect1d(np.round(np.log10(a) * PER_DECADE, 9), np.round(np.log10(b) * PER_DECADE, 9))
    assert set(np.round(np.log10(search_grid(10.0, 1e4)) * PER_DECADE, 9)) <= set(common)
    # and the boundary found inside both ranges is the same
    passing = lambda v: v < 2.7e3  # noqa: E731
    rows_a = search(3.0, 3e4, _planted(passing)[0], Budget(1e9, 1.0), METRIC)[0]
    rows_b = search(5.0, 3e4, _planted(passing)[0], Budget(1e9, 1.0), METRIC)[0]

    def change(rows):
        return next((a.value, b.value) for a, b in zip(rows, rows[1:], strict=False) if a.passed != b.passed)

    assert change(rows_a) == pytest.approx(change(rows_b), rel=1e-12)


def test_a_small_budget_thins_the_grid_and_says_so():
    budget = Budget(5.0, 1.0)  # five runs of 1 s
    run, calls = _planted(lambda v: v < 50.0, budget=budget)
    rows, _, _, reduced = search(1.0, 1e6, run, budget, METRIC)
    assert "budget" in reduced
    assert len(calls) <= 5 + 1  # the grid fits the budget (a thinned grid keeps at least its two ends)


def test_neighbourhood_is_half_a_grid_step():
    assert neighbourhood(2) == pytest.approx(10 ** 0.25)
    assert neighbourhood(1) == pytest.approx(10 ** 0.5)
