"""The sample space: per-sample streams (independent of the split), the distributions against scipy, corners."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from designkit.sweep.sampling import Dimension, SampleSpace


def _space(distribution="uniform", cut=3.0):
    dims = (Dimension("Km", "parameter", "Km", 1.0, 3.0, "", "x"), Dimension("tau", "parameter", "tau", 0.2, 0.4, "s",
                                                                              "y"))
    return SampleSpace(dimensions=dims, distribution=distribution, cut=cut)


def test_a_sample_is_the_same_whichever_samples_are_drawn_with_it():
    space = _space()
    all_, _ = space.draw(7, np.arange(100))
    part, _ = space.draw(7, np.arange(40, 60))
    assert np.array_equal(all_[40:60], part)
    other, _ = space.draw(8, np.arange(40, 60))
    assert not np.array_equal(other, part)


def test_uniform_samples_pass_a_kolmogorov_smirnov_test():
    v, _ = _space().draw(0, np.arange(4000))
    assert stats.kstest(v[:, 0], stats.uniform(1.0, 2.0).cdf).pvalue > 1e-3
    assert stats.kstest(v[:, 1], stats.uniform(0.2, 0.2).cdf).pvalue > 1e-3


def test_normal_samples_are_the_truncated_normal_of_the_box():
    v, _ = _space("normal", cut=2.0).draw(1, np.arange(4000))
    ref = stats.truncnorm(-2.0, 2.0, loc=2.0, scale=0.5)  # centre 2, half-width 1 = 2 standard deviations
    assert stats.kstest(v[:, 0], ref.cdf).pvalue > 1e-3
    assert v[:, 0].min() >= 1.0 and v[:, 0].max() <= 3.0


def test_corners_visit_every_corner_once_per_cycle():
    v, _ = _space("corners").draw(0, np.arange(8))
    corners = {tuple(row) for row in v[:4]}
    assert corners == {(1.0, 0.2), (3.0, 0.2), (1.0, 0.4), (3.0, 0.4)}
    assert np.array_equal(v[:4], v[4:])


@pytest.mark.parametrize("seed", [0, 5])
def test_noise_seeds_are_drawn_per_sample(seed):
    space = SampleSpace(dimensions=_space().dimensions, noise=True)
    _, s1 = space.draw(seed, np.arange(10))
    _, s2 = space.draw(seed, np.arange(5, 10))
    assert np.array_equal(s1[5:], s2) and len(set(s1.tolist())) == 10
