"""Robustness over a box of named plant parameters: the batched sweep against independent routes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings

from designkit.families import pid_servo, pid_tracking
from designkit.models.link import LinkPlant
from designkit.spec.plants import Uncertainty
from designkit.verification.robustness import (
    Box,
    Sweeper,
    box_from_uncertainty,
    characteristic_coefficients,
    grid_check,
    robustness_checks,
    stable_fraction,
    vertex_check,
)
from tests import oracles
from tests.verification.helpers import plants, pole_sets

PLANT = LinkPlant(Km=2.0, tau=0.5)


def _designs():
    return [
        pid_servo.design(PLANT, [-4, -5, -20], -3.0),
        pid_servo.design(PLANT, [-1 + 2j, -1 - 2j, -6], None),
        pid_tracking.design(PLANT, [-10, -12, -15]),
        pid_tracking.design(PLANT, [-1, -1.2, -1.5]),
    ]


def _oracle_A(design, plant: LinkPlant) -> np.ndarray:
    """The hand-derived closed loop of the design's gains on ``plant`` (tests/oracles.py)."""
    g = dict(design.gains)
    if design.kind == "pid_servo":
        return oracles.servo_closed_loop(g, plant).A
    return oracles.tracking_closed_loop(g, plant, design.plant).A


def _box(**intervals) -> Uncertainty:
    return Uncertainty(**{k: list(v) for k, v in intervals.items()})


@pytest.mark.parametrize("design", _designs(), ids=lambda d: f"{d.kind}{d.poles[0]}")
def test_batched_sweep_equals_per_plant_eigenvalues_of_the_hand_derived_loop(design):
    rng = np.random.default_rng(7)
    Km = rng.uniform(0.05, 20.0, 400)
    tau = rng.uniform(0.02, 10.0, 400)
    fast = stable_fraction(design, {"Km": Km, "tau": tau})
    slow, far = [], []
    for k, t in zip(Km, tau, strict=True):
        ev = np.linalg.eigvals(_oracle_A(design, LinkPlant(Km=float(k), tau=float(t))))
        slow.append(bool(np.all(ev.real < 0)))
        far.append(np.min(np.abs(ev.real)) > 1e-6 * np.max(np.abs(ev)))
    slow, far = np.array(slow), np.array(far)
    assert far.mean() > 0.95  # almost every sample is decidable
    np.testing.assert_array_equal(fast[far], slow[far])
    if design.poles[0] == -1:  # the slow tracker is not robust on this wide box: both outcomes occur
        assert 0 < fast.mean() < 1


@settings(max_examples=25, deadline=None)
@given(nominal=plants, poles=pole_sets(), plant=plants)
def test_stable_fraction_matches_eigenvalues_on_random_designs(nominal, poles, plant):
    design = pid_servo.design(nominal, poles, None)
    ev = np.linalg.eigvals(_oracle_A(design, plant))
    if np.min(np.abs(ev.real)) <= 1e-6 * np.max(np.abs(ev)):
        return  # too close to the boundary to compare
    got = stable_fraction(design, {"Km": plant.Km, "tau": plant.tau})
    assert bool(got) == bool(np.all(ev.real < 0))


def test_sweep_matrices_equal_the_hand_derived_loops():
    design = _designs()[2]
    theta = np.array([[1.3, 0.2], [2.9, 1.7]])
    res = Sweeper(design, ("Km", "tau")).sweep(theta)
    for A, (k, t) in zip(res.A, theta, strict=True):
        np.testing.assert_allclose(A, _oracle_A(design, LinkPlant(Km=k, tau=t)), rtol=1e-12, atol=1e-12)


def test_characteristic_coefficients_are_those_of_numpy_poly():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(20, 5, 5))
    ref = np.array([np.poly(a) for a in A])  # from the eigenvalues: an independent route
    np.testing.assert_allclose(characteristic_coefficients(A), ref, rtol=1e-9, atol=1e-9)


def test_stable_fraction_broadcasts():
    design = _designs()[3]
    rng = np.random.default_rng(0)
    Km = rng.uniform(0.1, 10.0, 6)
    s = stable_fraction(design, {"Km": Km.reshape(2, 3), "tau": 0.5})
    assert s.shape == (2, 3) and s.dtype == bool


def test_closed_loop_is_affine_in_inverse_tau_and_gain_over_tau():
    """Basis of the common-Lyapunov claim for the link: A(Km, tau) = A0 + (1/tau) Aa + (Km/tau) Ab."""
    for design in _designs():
        sweeper = Sweeper(design, ("Km", "tau"))

        def A(k, t, sweeper=sweeper):
            return sweeper.sweep([[k, t]]).A[0]

        pts = [(1.0, 1.0), (2.0, 1.0), (1.0, 0.5)]
        M = np.array([[1.0, 1.0 / t, k / t] for k, t in pts])
        coef = np.linalg.solve(M, np.array([A(k, t).ravel() for k, t in pts]))
        for k, t in [(3.7, 0.23), (0.4, 4.0)]:
            pred = (np.array([1.0, 1.0 / t, k / t]) @ coef).reshape(3, 3)
            np.testing.assert_allclose(pred, A(k, t), rtol=1e-12, atol=1e-9 * np.abs(A(k, t)).max())


def test_tracking_spec_box_passes_all_three():
    design = _designs()[2]
    checks = robustness_checks(design, _box(Km=(1.6, 2.4), tau=(0.4, 0.6)))
    assert [c.name for c in checks] == ["robust_vertices", "robust_grid", "common_lyapunov"]
    assert all(c.passed is True for c in checks), [c.detail for c in checks]
    cert = checks[1].certificate
    assert cert["lattice_plants"] == 21 * 21
    # every pair of lattice neighbours is bisected at least once: 2 axes x 21 lines x 20 pairs
    assert cert["refined_plants"] >= 2 * 21 * 20
    assert cert["plants"] == 21 * 21 + cert["refined_plants"]
    assert f"{cert['plants']} sampled plants stable" in checks[1].detail and "sampled" in checks[1].target
    assert checks[1].certificate["grid"]["axes"][0]["name"] == "Km"
    assert all(c.margin > 0 for c in checks)
    assert checks[2].certificate["covers_box"].startswith("yes")


def test_wide_box_fails_at_the_unstable_corner():
    design = _designs()[0]
    box = Box(names=("Km", "tau"), lo=(0.5, 0.1), hi=(8.0, 5.0), grid=51)
    v, g = vertex_check(design, box), grid_check(design, box)
    assert v.passed is False and g.passed is False
    assert "(Km=0.5, tau=5) unstable" in v.detail
    ev = np.linalg.eigvals(_oracle_A(design, LinkPlant(Km=0.5, tau=5.0)))
    assert np.max(ev.real) > 0  # the corner named is unstable by the independent route
    assert g.margin < 0 and g.certificate["unstable"] > 0
    lyap = robustness_checks(design, _box(Km=(0.5, 8.0), tau=(0.1, 5.0)))[2]
    assert lyap.passed is False and "vertex" in lyap.detail


def test_one_parameter_box_varies_only_that_parameter():
    design = _designs()[0]
    box = box_from_uncertainty(design.plant, Uncertainty(tau=[0.4, 0.6], grid=5))
    assert box.names == ("tau",)
    np.testing.assert_array_equal(box.vertices, [[0.4], [0.6]])
    g = grid_check(design, box)
    assert g.certificate["lattice_plants"] == 5 and len(g.certificate["grid"]["axes"]) == 1
    assert g.certificate["plants"] == 5 + g.certificate["refined_plants"] and g.certificate["refined_plants"] >= 4


def test_random_samples_are_seeded_and_added():
    design = _designs()[0]
    u = Uncertainty(Km=[1.5, 2.5], tau=[0.4, 0.6], grid=3, samples=50, seed=4)
    g1 = robustness_checks(design, u)[1]
    g2 = robustness_checks(design, u)[1]
    cert = g1.certificate
    assert cert["plants"] == 9 + 50 + cert["refined_plants"] and cert["random_samples"] == 50
    assert g1.certificate["worst_abscissa"] == g2.certificate["worst_abscissa"]


def test_common_lyapunov_undecided_is_not_reported_as_instability():
    """A box whose corners are stable but with no common quadratic P: undecided (never True)."""
    design = pid_tracking.design(PLANT, [-0.3 + 3j, -0.3 - 3j, -1.0])
    for hi in (2.5, 4.0, 6.0, 10.0, 20.0):
        v, g, c = robustness_checks(design, Uncertainty(Km=[2.0, hi], tau=[0.5, 0.5], grid=41))
        if v.passed and c.passed is not True:
            assert c.passed is None
            assert "not proven for the continuum" in c.detail
            return
    pytest.skip("every stable box of this family had a common P")
