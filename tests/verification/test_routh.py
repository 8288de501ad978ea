"""Routh array: known polynomials, zero pivots and the shifted re-test, root counting, batches."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.verification.routh import (
    MARGINAL,
    STABLE,
    UNSTABLE,
    routh_array,
    routh_batch,
    routh_hurwitz,
)


@pytest.mark.parametrize(
    ("coeffs", "status"),
    [
        ([1, 3, 3, 1], "stable"),
        ([2, 1], "stable"),
        ([1, 10, 35, 50, 24], "stable"),  # (s+1)(s+2)(s+3)(s+4)
        ([1, 1, 1, 1], "marginal"),  # -1, +-j: zero row
        ([1, 0, 1], "marginal"),  # +-j
        ([1, 0, 1, 1], "unstable"),  # zero pivot (a1 = 0), roots 0.34 +- 1.16j: decided by the shift
        ([1, 0, 0, 1], "unstable"),  # s^3 + 1: zero pivot, roots 0.5 +- 0.87j
        ([1, 2, 3, 0], "marginal"),  # root at 0
        ([1, -1, 2, 1], "unstable"),
        ([-1, -3, -3, -1], "stable"),  # sign of a0 does not matter
        ([1, 1, -2], "unstable"),
    ],
)
def test_known_polynomials(coeffs, status):
    assert routh_array(coeffs).status == status


def test_marginal_is_undecided_not_a_division_by_zero():
    check = routh_hurwitz([1.0, 1.0, 1.0, 1.0])
    assert check.passed is None
    assert check.status == "UNDECIDED"
    assert "imaginary axis" in check.detail
    assert check.certificate["first_column"][2] == 0.0
    assert check.certificate["first_column"][3] is None  # not computed past the zero pivot


def test_zero_pivot_is_resolved_by_the_shifted_retest_only_when_roots_are_off_the_axis():
    far = routh_array([1.0, 0.0, 1.0, 1.0])
    assert far.status == "unstable" and np.isnan(far.first_column[2])
    near = routh_array(np.real(np.poly([1e-12 + 1j, 1e-12 - 1j, -1.0])))  # zero pivot, inside the band
    assert near.status == "marginal"
    assert routh_array(np.real(np.poly([1e-9 + 1j, 1e-9 - 1j, -1.0]))).status == "unstable"  # array decides
    off = routh_array(np.real(np.poly([1e-3 + 1j, 1e-3 - 1j, -1.0])))
    assert off.status == "unstable"


def test_invalid_polynomials_raise():
    with pytest.raises(ValueError):
        routh_array([0.0, 1.0, 2.0])
    with pytest.raises(ValueError):
        routh_array([1.0, np.nan, 2.0])


@settings(max_examples=80, deadline=None)
@given(
    roots=st.lists(
        st.tuples(st.floats(min_value=0.05, max_value=20.0), st.booleans(), st.floats(0.0, 10.0), st.booleans()),
        min_size=1, max_size=3,
    )
)
def test_sign_changes_count_right_half_plane_roots(roots):
    """Real roots and conjugate pairs, |Re| >= 0.05, up to degree 6."""
    rs = []
    for mag, rhp, im, pair in roots:
        re = mag if rhp else -mag
        rs += [complex(re, im), complex(re, -im)] if pair and im > 0.05 else [complex(re, 0)]
    coeffs = np.real(np.poly(rs))
    r = routh_array(coeffs)
    n_rhp = sum(1 for z in rs if z.real > 0)
    if n_rhp == 0:
        assert r.status == "stable"
    else:  # a symmetric root set (e.g. +-a with positive coefficients) can hit an exact zero entry:
        # undecided is then acceptable, "stable" never is
        assert r.status in ("unstable", "marginal")
    if r.sign_changes is not None:
        assert r.sign_changes == n_rhp


def test_batch_equals_scalar():
    rng = np.random.default_rng(1)
    coeffs = rng.normal(size=(200, 4))
    coeffs[:, 0] = np.abs(coeffs[:, 0]) + 0.1
    b = routh_batch(coeffs)
    for k in range(200):
        r = routh_array(coeffs[k])
        assert {STABLE: "stable", UNSTABLE: "unstable", MARGINAL: "marginal"}[int(b.status[k])] == r.status
        np.testing.assert_allclose(b.first_column[k], r.first_column, rtol=1e-15)
