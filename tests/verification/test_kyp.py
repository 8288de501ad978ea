"""Strictly positive real (KYP) check: analytic SPR condition, frequency response, MIMO by
construction, and every FAIL / UNDECIDED path."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.linalg
import scipy.signal
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from designkit.verification import kyp
from designkit.verification.kyp import positive_real, spr_frequency_sweep
from designkit.verification.lmi import KypSolution, solve_kyp

W = np.logspace(-4, 5, 3000)  # rad/s, the tests' own grid


def _second_order(a: float, b: float, c: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Controllable canonical form of H(s) = (s + c) / (s^2 + a s + b)."""
    return np.array([[0.0, 1.0], [-b, -a]]), np.array([[0.0], [1.0]]), np.array([[c, 1.0]])


def _hurwitz(rng: np.random.Generator, n: int, decay: float) -> np.ndarray:
    M = rng.normal(size=(n, n))
    return M - (np.max(np.linalg.eigvals(M).real) + decay) * np.eye(n)


def _assert_kyp_by_numpy(A: np.ndarray, B: np.ndarray, C: np.ndarray, P: np.ndarray) -> None:
    """The returned P, judged here without the module: P > 0, A'P + PA < 0, P B = C'."""
    assert np.allclose(P, P.T, rtol=0, atol=1e-12 * np.max(np.abs(P)))
    assert np.min(np.linalg.eigvalsh(P)) > 0
    assert np.max(np.linalg.eigvalsh(A.T @ P + P @ A)) < 0
    assert np.linalg.norm(P @ B - C.T) <= 1e-7 * (np.linalg.norm(P) * np.linalg.norm(B) + np.linalg.norm(C))


@settings(max_examples=30, deadline=None)
@given(
    a=st.floats(0.1, 10.0),
    b=st.floats(0.1, 10.0),
    ratio=st.one_of(st.floats(0.01, 0.95), st.floats(1.05, 20.0)),
)
def test_verdict_agrees_with_the_analytic_spr_condition(a, b, ratio):
    """H(s) = (s + c)/(s^2 + a s + b), a, b, c > 0, is SPR iff c < a.

    Poles in the open left half plane (a, b > 0).  With s = jw:
    H(jw) = (c + jw)(b - w^2 - j a w) / |b - w^2 + j a w|^2, so
    Re H(jw) = (c b + (a - c) w^2) / |.|^2 and w^2 Re H(jw) -> a - c.
    c < a: Re H > 0 for every w and the limit a - c > 0 (with C B = 1 > 0): SPR.
    c > a: Re H < 0 for w^2 > c b / (c - a): not even positive real.
    The band 0.95 a < c < 1.05 a, where the limit is nearly zero, is excluded.
    """
    c = ratio * a
    A, B, C = _second_order(a, b, c)
    check = positive_real(A, B, C)
    if c < a:
        assert check.passed is True, check.detail
        _assert_kyp_by_numpy(A, B, C, np.array(check.certificate["P"]))
    else:
        assert check.passed is False, check.detail
        w = check.certificate["evidence"]["frequency_rad_s"]
        assert w ** 2 > c * b / (c - a)  # where the analytic Re H is negative
        re = (c * b + (a - c) * w ** 2) / ((b - w ** 2) ** 2 + (a * w) ** 2)
        assert re < 0
        assert check.certificate["evidence"]["min_eig_hermitian"] == pytest.approx(2 * re, rel=1e-6)


def _siso_oracle(A, B, C):
    """SPR from the transfer polynomials (scipy.signal.ss2tf), not from the realisation.

    H = (k s^(n-1) + n1 s^(n-2) + ...)/(s^n + d1 s^(n-1) + ...), so H(jw) = k/(jw) + (n1 - k d1)/(jw)^2 + ...
    and w^2 Re H(jw) -> k d1 - n1.  Returns (spr, ambiguous).
    """
    num, den = scipy.signal.ss2tf(A, B, C, np.zeros((1, 1)))
    num = num[0]
    n = len(den) - 1
    k, d1 = num[1], den[1]
    n1 = num[2] if n > 1 else 0.0
    H = np.polyval(num, 1j * W) / np.polyval(den, 1j * W)
    ref = float(np.linalg.norm(A, 2))
    # Re H scaled by its decay (w^2 + ref^2) / (|k| ref): of order one from w = 0 to infinity
    g = H.real * (W ** 2 + ref ** 2) / (abs(k) * ref)
    hf = (k * d1 - n1) / (abs(k) * ref)
    spr = bool(k > 0 and np.min(g) > 0 and hf > 0)
    ambiguous = bool(abs(np.min(g)) < 1e-3 or abs(hf) < 1e-3)
    return spr, ambiguous


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 100_000), n=st.integers(1, 4), decay=st.floats(0.1, 2.0), kyp_like=st.booleans())
def test_verdict_agrees_with_the_frequency_response_of_random_siso_systems(seed, n, decay, kyp_like):
    rng = np.random.default_rng(seed)
    A = _hurwitz(rng, n, decay)
    B = rng.normal(size=(n, 1))
    if kyp_like:  # C = B'P0 plus a perturbation: SPR or not, near the boundary more often
        P0 = scipy.linalg.solve_continuous_lyapunov(A.T, -np.eye(n))
        C = B.T @ P0 + 0.3 * rng.normal(size=(1, n))
    else:
        C = rng.normal(size=(1, n))
    assume(abs((C @ B).item()) > 0.05 * np.linalg.norm(C) * np.linalg.norm(B))  # relative degree one
    spr, ambiguous = _siso_oracle(A, B, C)
    assume(not ambiguous)
    check = positive_real(A, B, C)
    assert check.passed is spr, (check.detail, spr)
    assert spr_frequency_sweep(A, B, C).positive is spr
    if spr:
        _assert_kyp_by_numpy(A, B, C, np.array(check.certificate["P"]))


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 100_000), n=st.integers(1, 5))
def test_sweep_matches_polynomial_evaluation(seed, n):
    """spr_frequency_sweep's Hermitian part equals 2 Re H(jw) from the transfer polynomials."""
    rng = np.random.default_rng(seed)
    A, B, C = _hurwitz(rng, n, 0.5), rng.normal(size=(n, 1)), rng.normal(size=(1, n))
    w = np.logspace(-2, 3, 200)
    sweep = spr_frequency_sweep(A, B, C, w)
    num, den = scipy.signal.ss2tf(A, B, C, np.zeros((1, 1)))
    H = np.polyval(num[0], 1j * w) / np.polyval(den, 1j * w)
    np.testing.assert_allclose(sweep.min_eig, 2 * H.real, rtol=1e-6, atol=1e-9 * np.max(np.abs(H)))
    assert sweep.cb[0, 0] == pytest.approx((C @ B).item())


def test_mimo_spr_by_construction():
    """A Hurwitz, A'P0 + P0 A = -Q < 0, C = B'P0, B of full column rank: P0 solves the KYP
    conditions, so H + H^* = (Phi B)^* Q (Phi B) > 0 at every w and w^2 (H + H^*) -> B'QB > 0:
    SPR with a strict margin.  The returned P need not be P0 but must satisfy the same conditions."""
    rng = np.random.default_rng(7)
    n = 4
    A = _hurwitz(rng, n, 0.7)
    B = rng.normal(size=(n, 2))
    Q = np.diag([1.0, 2.0, 0.5, 1.5])
    P0 = scipy.linalg.solve_continuous_lyapunov(A.T, -Q)
    C = B.T @ P0
    check = positive_real(A, B, C)
    assert check.passed is True, check.detail
    P = np.array(check.certificate["P"])
    _assert_kyp_by_numpy(A, B, C, P)
    # independently: the Hermitian part by explicit inversion is positive on a grid
    for w in np.logspace(-3, 3, 61):
        H = C @ np.linalg.inv(1j * w * np.eye(n) - A) @ B
        assert np.min(np.linalg.eigvalsh(H + H.conj().T)) > 0
    assert spr_frequency_sweep(A, B, C).positive
    json.dumps(check.to_dict(), allow_nan=False)


def test_non_hurwitz_fails_with_eigenvalue_evidence():
    A = np.array([[0.5, 1.0], [0.0, -2.0]])
    check = positive_real(A, np.array([1.0, 1.0]), np.array([1.0, 1.0]))
    assert check.passed is False
    assert check.certificate["evidence"]["eigenvalue"] == pytest.approx([0.5, 0.0])
    assert "solver_status" not in check.certificate  # decided without the solver
    rotation = positive_real(np.array([[0.0, 1.0], [-1.0, 0.0]]), np.array([0.0, 1.0]), np.array([0.0, 1.0]))
    assert rotation.passed is False and "imaginary axis" in rotation.detail


def test_non_spr_fails_with_frequency_evidence():
    """H = (s + 3)/(s^2 + s + 1): Re H(jw) = (3 - 2 w^2)/|.|^2 < 0 for w > sqrt(3/2)."""
    check = positive_real(*_second_order(1.0, 1.0, 3.0))
    assert check.passed is False
    ev = check.certificate["evidence"]
    w = ev["frequency_rad_s"]
    H = (1j * w + 3.0) / ((1j * w) ** 2 + 1j * w + 1.0)
    assert w > np.sqrt(1.5)
    assert H.real < 0
    assert ev["H"][0][0] == pytest.approx([H.real, H.imag], rel=1e-9)
    assert "solver_status" not in check.certificate


def test_negative_markov_parameter_fails():
    """H = -1/(s + 1): C B = -1 < 0, and s H(s) -> -1 on the positive real axis."""
    check = positive_real(np.array([[-1.0]]), np.array([[1.0]]), np.array([[-1.0]]))
    assert check.passed is False
    assert check.certificate["evidence"]["CB"] == [[-1.0]]


def test_asymmetric_markov_parameter_fails():
    """A = -I, B = I, C = [[1, 1], [-1, 1]]: H = C/(s + 1) and
    (1 + w^2)(H + H^*) = 2 I - j w (C - C'), whose eigenvalues are 2 +- 2 w: negative for w > 1."""
    C = np.array([[1.0, 1.0], [-1.0, 1.0]])
    check = positive_real(-np.eye(2), np.eye(2), C)
    assert check.passed is False
    assert check.certificate["evidence"]["CB_asymmetry"] > 0.1
    w = 3.0
    H = C / (1j * w + 1.0)
    assert np.min(np.linalg.eigvalsh(H + H.conj().T)) < 0


def test_stiff_but_spr_is_undecided_not_failed():
    """SPR by construction, but every KYP certificate has condition number ~1e8 > 1/eps."""
    A = np.diag([-1e-8, -1.0])
    B = np.array([[1.0], [1.0]])
    P0 = scipy.linalg.solve_continuous_lyapunov(A.T, -np.eye(2))
    check = positive_real(A, B, B.T @ P0)
    assert check.passed is None
    assert check.certificate["t"] < 1e-6


def test_unavailable_solver_is_undecided():
    check = positive_real(*_second_order(1.0, 1.0, 0.5), solver="NO_SUCH_SOLVER")
    assert check.passed is None
    assert "solver" in check.detail


def test_inaccurate_status_is_undecided_even_with_a_good_P(monkeypatch):
    A, B, C = _second_order(1.0, 1.0, 0.5)
    good = solve_kyp(A, B, C)
    assert good.status == "optimal"
    fake = KypSolution(good.P, good.t, good.alpha, "optimal_inaccurate", "CLARABEL")
    monkeypatch.setattr(kyp, "solve_kyp", lambda A, B, C, solver: fake)
    check = positive_real(A, B, C)
    assert check.passed is None
    assert "optimal_inaccurate" in check.detail


def test_optimal_status_with_a_bad_P_is_undecided(monkeypatch):
    """The solver's word is not enough: P = I is a Lyapunov matrix here but P B != C'."""
    A, B, C = _second_order(1.0, 1.0, 0.5)
    monkeypatch.setattr(kyp, "solve_kyp", lambda A, B, C, solver: KypSolution(np.eye(2), 0.3, 1.0, "optimal", solver))
    check = positive_real(A, B, C)
    assert check.passed is None
    assert "re-check" in check.detail
    assert check.certificate["equality_residual"] > 1e-3
    monkeypatch.undo()
    assert positive_real(A, B, C).passed is True


def test_realisation_shapes_are_validated():
    with pytest.raises(ValueError):
        positive_real(-np.eye(2), np.ones((2, 2)), np.ones((1, 2)))
