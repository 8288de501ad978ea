"""The Clopper-Pearson interval against its definition by binomial tails (scipy.stats.binom), and the closed forms
at k = 0 and k = n."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom

from designkit.sweep.stats import clopper_pearson, quantiles


@pytest.mark.parametrize(("k", "n"), [(1, 10), (5, 10), (37, 400), (999, 1000), (250, 251)])
def test_the_ends_are_where_the_binomial_tails_are_alpha_over_two(k, n):
    lo, hi = clopper_pearson(k, n)
    assert binom.sf(k - 1, n, lo) == pytest.approx(0.025, rel=1e-6)  # P(X >= k | lo)
    assert binom.cdf(k, n, hi) == pytest.approx(0.025, rel=1e-6)  # P(X <= k | hi)


@pytest.mark.parametrize("n", [1, 7, 100, 10_000])
def test_no_failure_and_no_pass_have_closed_forms(n):
    assert clopper_pearson(n, n) == (pytest.approx(0.025 ** (1 / n)), 1.0)
    assert clopper_pearson(0, n) == (0.0, pytest.approx(1 - 0.025 ** (1 / n)))


def test_coverage_is_at_least_the_level():
    """Over many binomial draws at p = 0.3, n = 40, the interval holds p at least 95 % of the time."""
    rng = np.random.default_rng(3)
    ks = rng.binomial(40, 0.3, size=2000)
    inside = [lo <= 0.3 <= hi for lo, hi in (clopper_pearson(int(k), 40) for k in ks)]
    assert np.mean(inside) >= 0.95


def test_undefined_margins_count_as_the_worst():
    q = quantiles(np.array([1.0, np.nan, 2.0, 3.0]))
    assert q["q0"] is None and q["q1"] == 3.0 and q["q0.5"] == 1.0
