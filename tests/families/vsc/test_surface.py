"""c from the sliding poles: the reduced-order system on c x = 0 has exactly the requested poles."""

from __future__ import annotations

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.families.vsc.surface import reduced_poles, sliding_surface
from designkit.models.elastic import elastic_state_space
from designkit.models.robots.elastic_link import DEFAULTS


def _reduced_matrix(A, B, c):
    """The sliding motion on c x = 0 in an orthonormal basis N of ker c (numpy SVD):
    z' = N^T (I - B c/(cB)) A N z."""
    n = A.shape[0]
    _, _, vt = np.linalg.svd(c.reshape(1, n))
    N = vt[1:].T
    proj = np.eye(n) - B.reshape(n, 1) @ c.reshape(1, n) / float(c @ B.ravel())
    return N.T @ proj @ A @ N


def _closed_loop_by_python_control(A, B, c, lam):
    """Independent route: python-control's state-space closed loop under u = -(cB)^-1 c (A - lam I) x, whose
    poles are lam (the motion of sigma) and the sliding motion's."""
    K = (c @ (A - lam * np.eye(A.shape[0]))) / (c @ B.ravel())
    sys = control.ss(A, B, np.eye(A.shape[0]), np.zeros((A.shape[0], 1)))
    closed = control.feedback(sys, control.ss([], [], [], K.reshape(1, -1)), sign=-1)
    return closed.A


@st.composite
def problems(draw):
    n = draw(st.integers(2, 5))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    A = rng.normal(size=(n, n))
    B = rng.normal(size=(n, 1))
    W = np.column_stack([np.linalg.matrix_power(A, k) @ B for k in range(n)])
    if np.linalg.cond(W) > 1e6:
        A = A + np.diag(np.arange(n))  # usually restores a comfortable controllability
    k = draw(st.integers(0, (n - 1) // 2))
    poles = []
    for _ in range(k):
        re, im = -draw(st.floats(0.2, 5.0)), draw(st.floats(0.1, 5.0))
        poles += [complex(re, im), complex(re, -im)]
    while len(poles) < n - 1:
        poles.append(complex(-draw(st.floats(0.2, 8.0)), 0.0))
    return A, B, poles


@settings(max_examples=60, deadline=None)
@given(problems())
def test_reduced_system_has_the_requested_poles(problem):
    A, B, poles = problem
    W = np.column_stack([np.linalg.matrix_power(A, k) @ B for k in range(A.shape[0])])
    if np.linalg.cond(W) > 1e8:
        return  # numerically uncontrollable draws are the refusal's business (test_specs)
    c = sliding_surface(A, B, poles)
    assert c @ B.ravel() > 0
    # characteristic polynomials (well conditioned even for repeated poles, unlike the eigenvalues)
    want = np.real(np.poly(np.asarray(poles)))
    got = np.poly(_reduced_matrix(A, B, c))
    scale = np.abs(want) + 1.0
    assert np.all(np.abs(got - want) <= 1e-7 * scale)
    lam = -3.7
    closed = np.poly(_closed_loop_by_python_control(A, B, c, lam))
    want_closed = np.real(np.poly(np.asarray([*poles, lam])))
    assert np.all(np.abs(closed - want_closed) <= 1e-6 * (np.abs(want_closed) + 1.0))
    if len(set(poles)) == len(poles):  # distinct poles: the module's own eigenvalues agree too
        got_eig = reduced_poles(A, B, c)
        assert all(np.min(np.abs(got_eig - p)) <= 1e-5 * scale.max() for p in poles)


def test_elastic_joint_surface_is_figure_5_3_closed_form_with_tau2():
    """c1 = -(p1+p2+p3) - 1/tau2, c2 = 1, c3 = -p1 p2 p3/k2 - c1, c4 = (p1p2+p1p3+p2p3)/k2 - 1 - c1/(tau2 k2)
    (hand-derived from det(sI - A_r); the notes print c2 where tau2 is meant in c4)."""
    A, B = elastic_state_space(DEFAULTS)
    p = np.array([-8.0, -10.0, -12.0])
    c = sliding_surface(A, B, p)
    k2, t2 = DEFAULTS.KR * DEFAULTS.R2**2 / DEFAULTS.J2, DEFAULTS.tau2
    c1 = -p.sum() - 1 / t2
    c3 = -np.prod(p) / k2 - c1
    c4 = (p[0] * p[1] + p[0] * p[2] + p[1] * p[2]) / k2 - 1 - c1 / (t2 * k2)
    assert c == pytest.approx([c1, 1.0, c3, c4], rel=1e-12)
    # the printed c4 (c1 J2/(c2 KR R2^2) with c2 = 1) is not it: the sliding motion would have other poles
    printed = c.copy()
    printed[3] = (p[0] * p[1] + p[0] * p[2] + p[1] * p[2]) / k2 - 1 - c1 / k2
    assert np.max(np.abs(np.sort(reduced_poles(A, B, printed).real) - np.sort(p))) > 0.1


def test_link_surface_is_the_notes_slm():
    A = np.array([[0.0, 1.0], [0.0, -2.0]])
    B = np.array([[0.0], [4.0]])
    c = sliding_surface(A, B, [-5.0])
    assert c == pytest.approx([5.0, 1.0])  # slm = x2 + c x1 with c = 5


def test_wrong_number_of_poles_and_uncontrollable_are_refused():
    A, B = elastic_state_space(DEFAULTS)
    with pytest.raises(ValueError, match="needs 3 sliding poles"):
        sliding_surface(A, B, [-1.0, -2.0])
    A2 = A.copy()
    A2[3, 0] = 0.0  # the link decoupled from the motor
    with pytest.raises(ValueError, match="not controllable"):
        sliding_surface(A2, B, [-1.0, -2.0, -3.0])
