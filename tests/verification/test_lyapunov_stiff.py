"""The Lyapunov-equation route for stiff loops: its certificates hold in exact arithmetic."""

from __future__ import annotations

import mpmath
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.verification.lyapunov import equation_certificate, lyapunov_lmi
from tests.problems import POSSPEED_YAML


def _servo_A(poles: list[float]) -> np.ndarray:
    from designkit.families import synthesize
    from designkit.schema.loader import parse_spec

    text = POSSPEED_YAML.replace("poles: [-4, -5, -20]", f"poles: {poles}")
    return synthesize(parse_spec(text).spec).closed_loop.A


def _exactly_lyapunov(A: np.ndarray, P: np.ndarray) -> bool:
    """P > 0 and A'P + PA < 0 by Sylvester's criterion in 60-digit arithmetic (mpmath)."""
    mpmath.mp.dps = 60
    Am, Pm = mpmath.matrix(A.tolist()), mpmath.matrix(P.tolist())
    Pm = (Pm + Pm.T) / 2
    L = -(Am.T * Pm + Pm * Am)
    n = A.shape[0]
    minors = [mpmath.det(M[:k, :k]) for M in (Pm, L) for k in range(1, n + 1)]
    return all(m > 0 for m in minors)


def test_stiff_servo_is_certified_and_the_certificate_is_exact():
    A = _servo_A([-1, -2, -1e6])
    check = lyapunov_lmi(A)
    assert check.passed is True
    eq = check.certificate["equation_route"]
    assert eq["pole_spread"] > 1e5
    assert _exactly_lyapunov(A, np.array(eq["P"]))


def test_unstable_or_marginal_matrices_get_no_certificate():
    assert equation_certificate(np.array([[0.0, 1.0], [-1.0, 0.0]])) is None  # centre: A'P + PA = -I has no P
    assert equation_certificate(np.diag([-1.0, 1e-3])) is None


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(min_value=-7.0, max_value=1.0), min_size=2, max_size=5),
       st.integers(min_value=0, max_value=2**31 - 1))
def test_every_certificate_is_a_lyapunov_function_in_exact_arithmetic(exponents, seed):
    rng = np.random.default_rng(seed)
    n = len(exponents)
    T = rng.normal(size=(n, n)) + 3 * np.eye(n)
    A = T @ np.diag(-(10.0 ** np.array(exponents))) @ np.linalg.inv(T)
    eq = equation_certificate(A)
    if eq is not None:
        assert _exactly_lyapunov(A, np.array(eq["P"]))
