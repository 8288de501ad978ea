"""Lyapunov LMI: certificates re-checked by NumPy, the SciPy route, and every undecided path."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.families import pid_servo
from designkit.models.link import LinkPlant
from designkit.verification import lyapunov
from designkit.verification.lmi import solve_kyp
from designkit.verification.lyapunov import (
    LmiSolution,
    LyapunovCertificate,
    common_lyapunov,
    cross_check,
    lyapunov_equation,
    lyapunov_lmi,
    recheck,
)
from designkit.verification.tolerances import LMI_EPS
from tests.verification.helpers import plants, pole_sets

PLANT = LinkPlant(Km=2.0, tau=0.5)


def _random_stable(seed: int, n: int, decay: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n))
    shift = np.max(np.linalg.eigvals(M).real) + decay
    return M - shift * np.eye(n)


@settings(max_examples=40, deadline=None)
@given(plant=plants, poles=pole_sets())
def test_cvxpy_and_scipy_certificates_agree_on_synthesised_loops(plant, poles):
    A = pid_servo.design(plant, poles, None).closed_loop.A
    x = cross_check(A)
    assert x.status == "optimal"
    assert x.lmi is not None and x.lmi.ok, x.lmi
    assert x.equation.ok, x.equation
    # the LMI's P solves A'P + PA = -Q_lmi, and SciPy reproduces it from Q_lmi
    assert x.reconstruction_error < 1e-8
    assert lyapunov_lmi(A).passed is True


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 6), decay=st.floats(0.05, 5.0), scale=st.floats(1e-3, 1e3))
def test_random_stable_matrices_pass_and_are_scale_invariant(seed, n, decay, scale):
    A = _random_stable(seed, n, decay)
    c1, c2 = lyapunov_lmi(A), lyapunov_lmi(scale * A)
    assert c1.passed is True and c2.passed is True
    assert c1.margin == pytest.approx(c2.margin, rel=1e-3, abs=1e-6)
    # the certificate stored in the Check passes the NumPy re-check on its own
    P = np.array(c1.certificate["P"])
    assert recheck([A], P).ok
    assert np.all(np.array(c1.certificate["eig_P"]) > 0)
    assert np.all(np.array(c1.certificate["eig_AtP_PA"][0]) < 0)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 6), excess=st.floats(1e-3, 5.0))
def test_unstable_matrices_fail_with_eigenvalue_evidence(seed, n, excess):
    A = _random_stable(seed, n, -excess)  # largest real part = +excess
    c = lyapunov_lmi(A)
    assert c.passed is False
    lam = c.certificate["evidence"]["eigenvalue"]
    assert lam[0] == pytest.approx(excess, rel=1e-6)
    assert "solver_status" not in c.certificate  # decided without the solver


def test_marginal_rotation_has_no_lyapunov_function():
    c = lyapunov_lmi(np.array([[0.0, 1.0], [-1.0, 0.0]]))
    assert c.passed is False
    assert "imaginary axis" in c.detail


def test_stiff_but_stable_is_certified_by_the_equation_and_beyond_rounding_undecided():
    """Condition number beyond 1/eps: no LMI certificate with margin eps exists, the Lyapunov equation's
    P (judged by rounding bounds) certifies it; where even that is within rounding: undecided, not FAIL."""
    c = lyapunov_lmi(np.diag([-1e-8, -1.0]))
    assert c.passed is True and "equation_route" in c.certificate
    P = np.array(c.certificate["equation_route"]["P"])
    assert P[0, 0] == pytest.approx(0.5e8, rel=1e-9) and P[1, 1] == pytest.approx(0.5, rel=1e-9)  # -1/(2 lambda)
    c = lyapunov_lmi(np.diag([-1e-17, -1.0]))
    assert c.passed is None
    assert c.status == "UNDECIDED"
    assert lyapunov_lmi(np.diag([-1e-3, -1.0])).passed is True


def test_unavailable_solver_is_undecided():
    c = lyapunov_lmi(np.diag([-1.0, -2.0]), solver="NO_SUCH_SOLVER")
    assert c.passed is None
    assert "solver" in c.detail


def test_inaccurate_status_is_undecided_even_with_a_good_P(monkeypatch):
    A = np.diag([-1.0, -2.0])
    fake = LmiSolution(np.eye(2), 0.5, "optimal_inaccurate", "CLARABEL")
    monkeypatch.setattr(lyapunov, "solve_lmi", lambda As, solver: fake)
    c = lyapunov_lmi(A)
    assert c.passed is None
    assert "optimal_inaccurate" in c.detail


def test_optimal_status_with_a_bad_P_is_undecided(monkeypatch):
    """The solver's word is not enough: the NumPy re-check decides."""
    A = np.array([[-1.0, 100.0], [0.0, -1.0]])  # I is not a Lyapunov matrix for this A
    assert not recheck([A], np.eye(2)).ok
    monkeypatch.setattr(lyapunov, "solve_lmi", lambda As, solver: LmiSolution(np.eye(2), 0.5, "optimal", solver))
    c = lyapunov_lmi(A)
    assert c.passed is None
    assert "re-check" in c.detail
    monkeypatch.undo()
    assert lyapunov_lmi(A).passed is True


def test_common_lyapunov_exists_for_scaled_copies():
    A = pid_servo.design(PLANT, [-4, -5, -20], -3.0).closed_loop.A
    c = common_lyapunov([A, 2.0 * A, 0.5 * A])
    assert c.passed is True
    P = np.array(c.certificate["P"])
    assert recheck([A, 2.0 * A, 0.5 * A], P).ok


def test_common_lyapunov_undecided_when_vertices_stable_but_hull_is_not():
    """Both matrices are Hurwitz, their average is not: no common P exists, and none is found.
    That is reported as undecided (the vertices themselves are stable), never as a pass."""
    A1 = np.array([[-1.0, 10.0], [0.0, -1.0]])
    A2 = np.array([[-1.0, 0.0], [10.0, -1.0]])
    assert np.max(np.linalg.eigvals(0.5 * (A1 + A2)).real) > 0
    assert lyapunov_lmi(A1).passed is True and lyapunov_lmi(A2).passed is True
    c = common_lyapunov([A1, A2])
    assert c.passed is None


def test_common_lyapunov_fails_on_an_unstable_vertex():
    c = common_lyapunov([np.diag([-1.0, -2.0]), np.diag([-1.0, 0.5])])
    assert c.passed is False
    assert c.certificate["evidence"]["vertex"] == 1


def test_lyapunov_equation_solves_the_equation():
    A = _random_stable(3, 4, 0.5)
    P = lyapunov_equation(A, balanced=False)
    np.testing.assert_allclose(A.T @ P + P @ A, -np.eye(4), atol=1e-10)
    Pb = lyapunov_equation(A)  # balanced route: another valid certificate
    assert recheck([A], Pb, eps=LMI_EPS).ok


LYAPUNOV_KEYS = {
    "eps", "normalisation", "solver", "solver_status", "t", "D", "A_scale", "P", "eig_P", "eig_AtP_PA", "Pb",
    "eig_Pb", "eig_AhtPb_PbAh", "recheck_margin", "eig_A",
}


def test_certificate_keys_are_kept_by_the_shared_core():
    """The report reads these keys: the move to the shared LMI core must not change them."""
    ok = lyapunov_lmi(np.diag([-1.0, -2.0]))
    assert set(ok.certificate) == LYAPUNOV_KEYS
    bad = lyapunov_lmi(np.diag([-1.0, 2.0]))
    assert set(bad.certificate) == {"eps", "normalisation", "eig_A", "evidence"}


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 5))
def test_recheck_and_lyapunov_certificate_are_one_test(seed, n):
    """lyapunov.recheck and LyapunovCertificate.recheck give the same verdict and margin, for good
    and for bad candidates (an arbitrary symmetric matrix is rarely a Lyapunov matrix)."""
    rng = np.random.default_rng(seed)
    A = _random_stable(seed, n, 0.5)
    M = rng.normal(size=(n, n))
    for P in (lyapunov_equation(A), M @ M.T + 0.1 * np.eye(n), M + M.T):
        detailed = recheck([A], P)
        summary = LyapunovCertificate((A,), P).recheck()
        assert summary.ok is detailed.ok
        assert summary.margin == detailed.margin or (np.isinf(summary.margin) and np.isinf(detailed.margin))


def test_kyp_certificate_is_also_a_lyapunov_certificate():
    """The KYP solve runs through the same LMI core: its P passes the Lyapunov re-check of A."""
    coeffs = np.poly([-4.0, -5.0, -20.0, -100.0])  # badly scaled companion matrix (entries 1 to 4e4)
    A = np.diag(np.ones(3), 1)
    A[-1] = -coeffs[:0:-1]
    B = np.eye(4)[:, [3]]
    P0 = lyapunov_equation(A)
    sol = solve_kyp(A, B, B.T @ P0)
    assert sol.status == "optimal"
    assert recheck([A], sol.P).ok
