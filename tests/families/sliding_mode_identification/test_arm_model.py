"""The pieces of the robot form against independent routes: the base regressor and the base parameters against
the two-link arm's Euler-Lagrange equations derived in sympy, the LDL' solve against NumPy, the multisine reference
against finite differences and its spectrum (NumPy's FFT)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.families.sliding_mode_identification.arm import base_of, regressor_symbols, true_beta
from designkit.families.sliding_mode_identification.arm_law import ldl_solve
from designkit.models.robot_plant import zoo_plant
from designkit.simulation.reference import multisine
from tests.families.sliding_mode_identification import two_link


def _values(plant):
    return {n: plant.parameter(n).value for n in two_link.NAMES}


@pytest.mark.parametrize("overrides", [{}, {"m2": 4.0}, {"m1": 2.0, "d1": 0.7, "I2": 0.1, "f1": 0.3}])
def test_base_regressor_reproduces_the_euler_lagrange_torque(overrides):
    """Wb(q, qd, qdd) beta = tau_EL at random states, beta = K P of the model layer at the plant's values."""
    plant = zoo_plant("planar2r", overrides=overrides)
    base = base_of(plant)
    beta = true_beta(base, plant)
    q, qd, qdd = two_link.states(50, seed=3)
    tau = two_link.torque(_values(plant), q, qd, qdd)
    model = np.stack([np.asarray(base.W_base(q[k], qd[k], qdd[k]), dtype=float) @ beta for k in range(50)])
    assert model.shape == tau.shape
    assert np.max(np.abs(model - tau)) <= 1e-10 * max(1.0, np.abs(tau).max())


def test_base_parameters_are_the_coordinates_of_the_euler_lagrange_torque():
    """The least-squares coordinates of tau_EL in the base columns are the model layer's beta, and the closed forms
    of the notes' appendix B: the gravity coefficients (m2 + m1/2) d1 and m2 d2/2, the frictions f1, f2."""
    plant = zoo_plant("planar2r")
    base = base_of(plant)
    beta, residual = two_link.base_by_least_squares(_values(plant), base.W_base)
    assert residual <= 1e-10
    assert beta == pytest.approx(true_beta(base, plant), abs=1e-10)
    by = dict(zip(base.names, beta, strict=True))
    assert by["mcx1R"] == pytest.approx((3.0 + 5.0 / 2) * 0.5, rel=1e-12)
    assert by["mcx2R"] == pytest.approx(3.0 * 0.4 / 2, rel=1e-12)
    assert (by["fv1"], by["fv2"]) == pytest.approx((2.0, 1.0), rel=1e-12)
    assert abs(by["fc1"]) < 1e-12 and abs(by["mcy1"]) < 1e-12


def test_the_regressor_depends_on_the_kinematics_and_gravity_only():
    assert set(regressor_symbols(zoo_plant("planar2r"))) == {"d1", "d2", "g"}


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 6))
def test_ldl_solve_against_numpy(seed, n):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    M = A @ A.T + 0.1 * np.eye(n)
    b = rng.normal(size=n)
    x, ok = ldl_solve(ca.SX(ca.DM(M)), ca.SX(ca.DM(b)))
    assert float(ca.evalf(ok)) == 1.0
    assert np.asarray(ca.evalf(x), dtype=float).ravel() == pytest.approx(np.linalg.solve(M, b), rel=1e-9, abs=1e-9)
    indefinite = M - (np.linalg.eigvalsh(M)[-1] + 1.0) * np.outer(np.eye(n)[0], np.eye(n)[0])
    x, ok = ldl_solve(ca.SX(ca.DM(indefinite)), ca.SX(ca.DM(b)))
    assert float(ca.evalf(ok)) == 0.0 and np.all(np.asarray(ca.evalf(x)) == 0.0)


def test_multisine_derivatives_bound_and_interleaved_spectrum():
    ref = multisine([1.0, 0.5, 0.2], 4.0, 5, start=[0.1, 0.2, 0.3])
    t = np.arange(0.0, 4.0, 1e-3)
    x = ref.evaluate(t)
    assert np.allclose(x[0, :, 0], [0.1, 0.2, 0.3])  # starts at the initial positions
    fine = np.linspace(0.0, 4.0, 400_001)
    xf = ref.evaluate(fine)
    for j in range(3):
        np.testing.assert_allclose(np.gradient(xf[:, j, 0], fine)[5:-5], xf[5:-5, j, 1], rtol=0, atol=1e-6)
        np.testing.assert_allclose(np.gradient(xf[:, j, 1], fine)[5:-5], xf[5:-5, j, 2], rtol=0, atol=1e-4)
        swing = x[:, j, 0] - x[:, j, 0].mean()
        assert np.abs(swing).max() <= [1.0, 0.5, 0.2][j]  # within the amplitude of its centre
        spectrum = np.abs(np.fft.rfft(x[:, j, 0] - x[:, j, 0].mean()))  # bins are harmonics of 1/4 Hz
        lines = set(np.flatnonzero(spectrum > 1e-6 * spectrum.max()))
        assert lines == {j + 1 + 3 * i for i in range(5)}  # joint j: harmonics j + 1 + 3 i, none shared
