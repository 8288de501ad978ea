"""The lifted error system ``H`` of the learning family against independent routes.

* The simulator: on the exact-model arm two trials differing by a feedforward ``v`` differ in their sampled error
  by exactly ``H v`` (``e_k - e_{k+1} = H (d_{k+1} - d_k)``), ``e_0`` does not move and ``v_{N-1}`` moves nothing
  recorded -- for white (rough) and smooth ``v``, with different gains per joint; with CVODES against the exact
  zero-order hold.  With a mass error the part the lifted model does not explain is measured and must grow in
  proportion to the error (first order in ``M^-1 M^ - I``).
* The Markov parameters against one step of the simulator's own RK4 (:func:`designkit.simulation.integrate.rk4`)
  on the linear error system with matrix powers, and against scipy's ``cont2discrete`` (zero-order hold).
* The structured products (FFT) and norms against dense Toeplitz matrices and a dense SVD on a small horizon.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.signal import cont2discrete

from designkit.families.ilc.learning import lifted_errors, lifted_of
from designkit.families.ilc.lifted import MAX_LIFTED, lifted_model
from designkit.pipeline import design as design_of
from designkit.pipeline import plant as plant_of
from designkit.schema.loader import parse_spec
from designkit.simulation.integrate import rk4
from designkit.simulation.run import build
from tests.families.ilc.common import arm_spec


def _simulator(text: str):
    loaded = parse_spec(text)
    plant = plant_of(loaded)
    design = design_of(loaded, plant)
    return design, build(loaded.spec, design, plant=plant)


def _smooth(rng: np.random.Generator, t: np.ndarray, n: int) -> np.ndarray:
    """A smooth signal ``(N, n)`` (rad/s^2): a few random sines."""
    f = rng.uniform(0.5, 4.0, size=(3, n))
    a = rng.uniform(-3.0, 3.0, size=(3, n))
    return np.sum(a[:, None, :] * np.sin(2 * np.pi * f[:, None, :] * t[None, :, None]), axis=0)


@pytest.fixture(scope="module")
def exact():
    return _simulator(arm_spec("{kind: ilc, poles: [[-10, -10], [-8, -15]]}"))


@pytest.mark.parametrize("shape", ["white", "smooth"])
def test_lifted_H_is_the_simulated_trial_to_trial_map(exact, shape):
    design, sim = exact
    lifted = lifted_of(design, sim.time)
    rng = np.random.default_rng(1)
    N, n = sim.time.size, lifted.n
    v = 5.0 * rng.standard_normal((N, n)) if shape == "white" else _smooth(rng, sim.time, n)
    base, moved = sim.run(), sim.run(feedforward=v)
    measured = lifted_errors(base) - lifted_errors(moved)  # e_k - e_(k+1) = H (d_(k+1) - d_k)
    predicted = lifted.apply(v.T[:, :lifted.L])
    rel = float(np.max(np.abs(measured - predicted)) / np.max(np.abs(predicted)))
    assert rel < 1e-9, rel  # measured 1.4e-11 (rounding of M^-1 M^ = I in the arm's forward dynamics)
    assert np.array_equal(base.tracking_errors[0], moved.tracking_errors[0])  # e_0 does not depend on d
    last = v.copy()
    last[-1] += 100.0  # v_(N-1) acts after the last recorded sample
    assert np.array_equal(sim.run(feedforward=last).state, moved.state)


def test_lifted_H_with_cvodes_is_the_exact_zero_order_hold():
    design, sim = _simulator(arm_spec("{kind: ilc, poles: [-10, -10]}", duration=0.2,
                                      numerics="{compile: never, integrator: cvodes, rtol: 1e-10, atol: 1e-12}"))
    lifted = lifted_of(design, sim.time)
    assert lifted.integrator == "cvodes"
    v = _smooth(np.random.default_rng(2), sim.time, 2)
    measured = lifted_errors(sim.run()) - lifted_errors(sim.run(feedforward=v))
    predicted = lifted.apply(v.T[:, :lifted.L])
    assert np.max(np.abs(measured - predicted)) / np.max(np.abs(predicted)) < 1e-6  # measured 3.8e-8


def _mismatch(m2: float, rng: np.random.Generator) -> float:
    design, sim = _simulator(arm_spec(f"{{kind: ilc, poles: [-10, -10], model: {{parameters: {{m2: {m2}}}}}}}"))
    lifted = lifted_of(design, sim.time)
    v = 1e-3 * _smooth(rng, sim.time, 2)  # small: the part of the residual that is linear in the mismatch
    measured = lifted_errors(sim.run()) - lifted_errors(sim.run(feedforward=v))
    predicted = lifted.apply(v.T[:, :lifted.L])
    return float(np.linalg.norm(measured - predicted) / np.linalg.norm(predicted))


def test_the_unexplained_part_is_first_order_in_the_mass_error():
    ten, twenty = (_mismatch(m2, np.random.default_rng(3)) for m2 in (2.7, 2.4))  # true m2 = 3 kg
    assert 0.01 < ten < 0.2 and 0.02 < twenty < 0.4, (ten, twenty)  # measured 0.037 and 0.078
    assert 1.7 < twenty / ten < 2.3, (ten, twenty)  # linear in M^ - M: the ratio of the errors, 2


def _powers(Phi: np.ndarray, Gamma: np.ndarray, L: int) -> np.ndarray:
    out, x = np.zeros(L), Gamma.copy()
    for m in range(L):
        out[m] = x[0]
        x = Phi @ x
    return out


@pytest.mark.parametrize(("K1", "K2", "dt"), [(100.0, 20.0, 1e-3), (400.0, 40.0, 2e-3), (49.0, 5.0, 5e-3)])
def test_markov_parameters_against_the_simulators_rk4_step_and_scipy_zoh(K1, K2, dt):
    L = 400
    A = np.array([[0.0, 1.0], [-K1, -K2]])
    B = np.array([0.0, 1.0])

    def step(s, v):  # one step of the simulator's RK4 on x' = A x + B v, v held
        return rk4(lambda x, _a: A @ x + B * v, s, dt, (None, None, None))

    Phi = np.column_stack([step(np.eye(2)[:, i], 0.0) for i in range(2)])
    Gamma = step(np.zeros(2), 1.0)
    rk = lifted_model((K1,), (K2,), dt, L + 1, "rk4").markov[0]
    np.testing.assert_allclose(rk, _powers(Phi, Gamma, L), rtol=1e-10, atol=1e-15 * np.max(np.abs(rk)))
    Ad, Bd, *_ = cont2discrete((A, B[:, None], np.array([[1.0, 0.0]]), np.zeros((1, 1))), dt, method="zoh")
    zoh = lifted_model((K1,), (K2,), dt, L + 1, "cvodes").markov[0]
    np.testing.assert_allclose(zoh, _powers(Ad, Bd[:, 0], L), rtol=1e-10, atol=1e-15 * np.max(np.abs(zoh)))
    # RK4 against the exact hold: local error O((dt |p|)^5) per step
    assert np.max(np.abs(rk - zoh)) / np.max(np.abs(zoh)) < 1e-4
    assert rk[0] == pytest.approx(dt**2 / 2 - K2 * dt**3 / 6 + (K2**2 - K1) * dt**4 / 24, rel=1e-12)


@pytest.fixture(scope="module")
def small():
    lifted = lifted_model((100.0, 64.0), (20.0, 6.0), 2e-3, 301)  # joint 2 underdamped (zeta = 0.375)
    dense = [sl.toeplitz(lifted.markov[j], np.zeros(lifted.L)) for j in range(2)]
    return lifted, dense


def test_structured_products_against_dense_toeplitz(small):
    lifted, dense = small
    X = np.random.default_rng(4).standard_normal((2, lifted.L))
    for j in range(2):
        scale = np.max(np.abs(dense[j] @ X[j]))
        np.testing.assert_allclose(lifted.apply(X)[j], dense[j] @ X[j], atol=1e-12 * scale)
        np.testing.assert_allclose(lifted.apply_transpose(X)[j], dense[j].T @ X[j],
                                   atol=1e-12 * np.max(np.abs(dense[j].T @ X[j])))
        inverse = sl.solve_triangular(dense[j], X[j], lower=True)
        np.testing.assert_allclose(lifted.apply_inverse(X)[j], inverse, atol=1e-8 * np.max(np.abs(inverse)))


def test_singular_values_against_dense_svd(small):
    lifted, dense = small
    for j in range(2):
        s = np.linalg.svd(dense[j], compute_uv=False)
        hi, lo = lifted.sigma_max[j], lifted.sigma_min[j]
        assert hi.estimate == pytest.approx(s[0], rel=1e-9)
        assert hi.power == pytest.approx(s[0], rel=1e-6)
        assert hi.lower <= s[0] * (1 + 1e-12) and s[0] <= hi.upper
        assert lo.estimate == pytest.approx(s[-1], rel=1e-6)  # dense sigma_min: error ~ eps sigma_max
        assert lo.lower <= s[-1] * (1 + 1e-6) and s[-1] <= lo.upper * (1 + 1e-6)
    assert lifted.sigma_max[1].upper < float(np.sum(np.abs(lifted.markov[1])))  # oscillating: the symbol is tighter


def test_two_thousand_samples_per_joint_are_cheap():
    t0 = time.perf_counter()
    lifted = lifted_model((400.0, 400.0, 100.0), (40.0, 40.0, 20.0), 1e-3, 2001)
    norms = lifted.sigma_max, lifted.sigma_min
    elapsed = time.perf_counter() - t0
    assert elapsed < 5.0, elapsed  # measured 0.3 s (two distinct joints: identical ones share their norms)
    assert lifted.markov.nbytes + lifted.inverse_markov.nbytes < 1e5  # O(n N): a dense 3N x 3N would be 288 MB
    assert norms[0][0] is norms[0][1] and MAX_LIFTED > 2001 * 3
