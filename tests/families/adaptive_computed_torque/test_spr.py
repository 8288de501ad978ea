"""The SPR condition of H(s) = (1 + psi s)/(s^2 + K2 s + K1): KYP feasibility <=> frequency-domain condition <=>
the analytic condition psi K2 > 1, on random gains away from the boundary (per joint and for diagonal matrix gains).

The frequency-domain route here is written afresh (complex arithmetic on a dense grid, and the limit
w^2 Re H(jw) -> psi K2 - 1 approached at large w), not the family's sweep."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from designkit.families.adaptive_computed_torque.spr import lyapunov_matrix, realisation, stacked_realisation
from designkit.verification.kyp import positive_real

WN = st.floats(0.0, 2.0).map(lambda e: 10.0 ** e)  # natural frequency 1 to 100 rad/s
ZETA = st.floats(0.3, 3.0)  # damping ratio: the certificate core's conditioning stays far from its margin


def _frequency_says_spr(K1: float, K2: float, psi: float) -> bool:
    w = np.concatenate([[0.0], np.logspace(-4, 7, 4000)])
    H = (1 + 1j * psi * w) / ((1j * w) ** 2 + K2 * 1j * w + K1)
    high = 1e6 * np.sqrt(K1) + 1e6 * K2
    Hh = (1 + 1j * psi * high) / ((1j * high) ** 2 + K2 * 1j * high + K1)
    return bool(np.all(H.real > 0) and high**2 * Hh.real > 1e-3 * abs(psi * K2 - 1))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(wn=WN, zeta=ZETA, r=st.floats(0.1, 10.0))
def test_kyp_frequency_and_analytic_agree_per_joint(wn, zeta, r):
    K1, K2 = wn * wn, 2 * zeta * wn
    psi = r / K2  # psi K2 = r
    assume(abs(r - 1.0) > 0.05)
    analytic = r > 1.0
    assert _frequency_says_spr(K1, K2, psi) == analytic
    check = positive_real(*realisation(K1, K2, psi))
    assert check.passed is analytic, check.detail


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(wn=st.lists(st.floats(3.0, 30.0), min_size=2, max_size=4), data=st.data())
def test_diagonal_matrix_gains_are_spr_iff_every_joint_is(wn, data):
    n = len(wn)
    zeta = data.draw(st.lists(ZETA, min_size=n, max_size=n))
    K1 = [w * w for w in wn]
    K2 = [2 * z * w for z, w in zip(zeta, wn, strict=True)]
    r = data.draw(st.lists(st.floats(0.1, 10.0).filter(lambda x: abs(x - 1) > 0.05), min_size=n, max_size=n))
    psi = [ri / k2 for ri, k2 in zip(r, K2, strict=True)]
    check = positive_real(*stacked_realisation(K1, K2, psi))
    assert check.passed is all(ri > 1 for ri in r), check.detail


@pytest.mark.parametrize(("K1", "K2", "psi"), [(400.0, 40.0, 0.05), (100.0, 20.0, 0.1), (1.0, 0.5, 3.0)])
def test_closed_form_certificate(K1, K2, psi):
    """P = [[K2 + psi K1, 1], [1, psi]]: P > 0, P B = C', A'P + PA = -diag(2 K1, 2 (psi K2 - 1)) (NumPy)."""
    A, B, C = realisation(K1, K2, psi)
    P = lyapunov_matrix(K1, K2, psi)
    assert np.all(np.linalg.eigvalsh(P) > 0)
    np.testing.assert_allclose(P @ B, C.T)
    np.testing.assert_allclose(A.T @ P + P @ A, -np.diag([2 * K1, 2 * (psi * K2 - 1)]), atol=1e-12 * K1)


def test_at_the_boundary_re_h_is_positive_but_w2_re_h_vanishes():
    """psi K2 = 1: Re H(jw) = K1/|...|^2 > 0 at every w, yet w^2 Re H(jw) -> 0: PR, not SPR."""
    K1, K2 = 100.0, 20.0
    psi = 1 / K2
    w = np.logspace(-2, 6, 200)
    H = (1 + 1j * psi * w) / ((1j * w) ** 2 + K2 * 1j * w + K1)
    assert np.all(H.real > 0)
    assert (w[-1] ** 2 * H[-1].real) < 1e-6
    assert positive_real(*realisation(K1, K2, psi)).passed is not True
