"""pole_placement against python-control, on hypothesis pole sets and on designs built to fail."""

from __future__ import annotations

import dataclasses

import control
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from designkit.families import pid_servo, pid_tracking
from designkit.models.linear_system import LinearSystem
from designkit.models.link import LinkPlant
from designkit.synthesis import pid
from designkit.synthesis.requirements import dominant_poles
from designkit.verification.pole_zero import coefficient_error, finite_zeros, match_roots, pole_placement
from designkit.verification.tolerances import POLE_REL
from tests import oracles
from tests.verification.helpers import plants, pole_sets, real_pole, same_multiset, well_separated

PLANT = LinkPlant(Km=2.0, tau=0.5)


def _siso(design, inp):
    sys = design.closed_loop.to_control()
    j = list(sys.input_labels).index(inp)
    return control.ss(sys.A, sys.B[:, j : j + 1], sys.C[0:1, :], sys.D[0:1, j : j + 1])


@settings(max_examples=60, deadline=None)
@given(plant=plants, poles=pole_sets(), zero=real_pole)
def test_servo_gains_place_exactly_the_requested_poles_and_zero(plant, poles, zero):
    assume(well_separated([*poles, zero]))
    gains = pid.servo_gains(plant, poles, zero)
    design = pid_servo.design(plant, poles, zero)
    assert design.gains == gains
    sys = design.closed_loop.to_control()
    assert same_multiset(control.poles(sys), poles)
    sub = _siso(design, "xD")
    z, _ = finite_zeros(sub)
    assert same_multiset(z, [zero])
    assert abs(control.dcgain(sub) - 1.0) <= 1e-9
    check = pole_placement(design)
    assert check.passed is True, check.detail
    assert check.margin > 0


@settings(max_examples=40, deadline=None)
@given(plant=plants, poles=pole_sets())
def test_tracking_gains_place_exactly_the_requested_poles(plant, poles):
    assume(well_separated(poles))
    design = pid_tracking.design(plant, poles)
    assert same_multiset(control.poles(design.closed_loop.to_control()), poles)
    z, _ = finite_zeros(_siso(design, "xi"))
    assert np.allclose(z, [0.0], atol=1e-9 * np.max(np.abs(poles)))
    check = pole_placement(design)
    assert check.passed is True, check.detail


@settings(max_examples=40, deadline=None)
@given(plant=plants, poles=pole_sets(), zero=real_pole)
def test_notes_misprinted_K2_does_not_place_the_poles(plant, poles, zero):
    """Notes 3.2 print K2 = -[(p1+p2+p3) tau - 1]/Km; our derivation has +1.  Only ours works."""
    s1 = sum(poles).real
    good = pid_servo.design(plant, poles, zero)
    gains = dict(good.gains)
    gains["K2"] = -(s1 * plant.tau - 1.0) / plant.Km
    bad = dataclasses.replace(good, gains=gains, closed_loop=oracles.servo_closed_loop(gains, plant))
    assert not same_multiset(control.poles(bad.closed_loop.to_control()), poles, rel=1e-6)
    check = pole_placement(bad)
    assert check.passed is False
    assert "poles" in check.detail


def test_zero_cancelling_a_pole_is_matched():
    design = pid_servo.design(PLANT, [-4, -5, -20], -20.0)
    check = pole_placement(design)
    assert check.passed is True
    assert np.allclose(check.certificate["zeros"], [[-20.0, 0.0]], rtol=1e-9)


def test_double_pole_from_zero_overshoot_passes_with_cluster_tolerance():
    poles = dominant_poles(0.0, 1.0).poles  # zeta = 1: double real pole
    check = pole_placement(pid_servo.design(PLANT, poles, poles[2].real))
    assert check.passed is True
    clusters = {row["cluster"] for row in check.certificate["pole_matching"]}
    assert clusters == {1, 2}


def test_wrong_zero_fails():
    design = pid_servo.design(PLANT, [-4, -5, -20], -3.0)
    claimed = dataclasses.replace(design, zeros=(complex(-4.0),))
    check = pole_placement(claimed)
    assert check.passed is False
    assert "zeros" in check.detail


def test_dc_gain_not_one_fails():
    design = pid_servo.design(PLANT, [-4, -5, -20], -3.0)
    cl = design.closed_loop
    B, D = np.array(cl.B), np.array(cl.D)
    B[:, 0] *= 1.1
    D[:, 0] *= 1.1
    scaled = LinearSystem(A=cl.A, B=B, C=cl.C, D=D, states=cl.states, inputs=cl.inputs, outputs=cl.outputs)
    check = pole_placement(dataclasses.replace(design, closed_loop=scaled))
    assert check.passed is False
    assert "DC gain" in check.detail
    assert check.certificate["dc_gain"] == pytest.approx(1.1, rel=1e-9)


def test_tracker_with_wrong_feedforward_is_not_perfect_tracking():
    design = pid_tracking.design(PLANT, [-10, -12, -15])
    wrong = oracles.tracking_closed_loop(dict(design.gains), PLANT, LinkPlant(Km=2.0, tau=0.6))
    # same Km0, so same feedback and poles; only the xD'' feed-forward tau0/Km0 is wrong
    check = pole_placement(dataclasses.replace(design, closed_loop=wrong))
    assert check.passed is False
    assert "x1/xD is not 1" in check.detail


def test_the_trackers_disturbance_zero_is_checked_when_its_law_integrates_the_error():
    design = pid_tracking.design(PLANT, [-10, -12, -15])
    assert design.law.integral_states == ("x3",)
    check = pole_placement(design)
    assert check.passed is True and "xi zeros" in check.certificate["error_over_tolerance"]
    # a disturbance that also enters the integral: x1/xi loses its zero at 0, which the check sees
    cl = design.closed_loop
    B = np.array(cl.B, dtype=float)
    B[cl.states.index("x3"), cl.inputs.index("xi")] = 1.0
    leaky = LinearSystem(A=cl.A, B=B, C=cl.C, D=cl.D, states=cl.states, inputs=cl.inputs, outputs=cl.outputs)
    check = pole_placement(dataclasses.replace(design, closed_loop=leaky))
    assert check.passed is False and "(integral action)" in check.detail
    # a law without integral states is not asked for the zero
    without = dataclasses.replace(design.law, integral_states=())
    proportional = dataclasses.replace(design, closed_loop=leaky, law=without)
    check = pole_placement(proportional)
    assert check.passed is True and "xi zeros" not in check.certificate["error_over_tolerance"]


def test_infinite_zeros_are_discarded():
    # x1/xD with K1 + K3 K4 = 0 has no finite zero: the numerator is the constant Km K3
    g = pid.servo_gains(PLANT, [-4, -5, -20], -3.0)
    g["K4"] = -g["K1"] / g["K3"]
    cl = oracles.servo_closed_loop(g, PLANT).to_control()
    sub = control.ss(cl.A, cl.B[:, 0:1], cl.C[0:1, :], cl.D[0:1, 0:1])
    z, discarded = finite_zeros(sub)
    assert z.size == 0
    assert discarded >= 0


def test_match_and_coefficients_helpers():
    assert match_roots([1.0, 2.0], [2.0, 1.0 + 1e-12], 2.0)["ok"]
    assert not match_roots([1.0, 2.0], [2.0, 1.1], 2.0)["ok"]
    assert not match_roots([1.0], [1.0, 2.0], 2.0)["ok"]
    assert coefficient_error([-1, -2, -3], [-3, -2, -1], 3.0) == 0.0
    assert coefficient_error([-1, -2, -3.001], [-3, -2, -1], 3.0) > POLE_REL


@settings(max_examples=20, deadline=None)
@given(poles=pole_sets(), shift=st.floats(min_value=1e-6, max_value=0.1))
def test_pole_placement_detects_a_perturbed_pole(poles, shift):
    """A design that claims poles it does not have fails (the check can fail)."""
    design = pid_servo.design(PLANT, poles, None)
    R = max(abs(p) for p in poles)
    if poles[0].imag == 0:
        moved = (poles[0] + shift * R, poles[1], poles[2])
    else:  # move the pair together so that it stays conjugate
        moved = (poles[0] + shift * R, poles[1] + shift * R, poles[2])
    assert pole_placement(dataclasses.replace(design, poles=moved)).passed is False


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 8))
def test_exhaustive_assignment_has_scipys_optimal_cost(seed, n):
    from scipy.optimize import linear_sum_assignment

    from designkit.verification.pole_zero import assignment

    cost = np.random.default_rng(seed).exponential(size=(n, n))
    rows, cols = assignment(cost)
    r_ref, c_ref = linear_sum_assignment(cost)
    assert sorted(cols.tolist()) == list(range(n))  # a permutation
    assert cost[rows, cols].sum() == pytest.approx(cost[r_ref, c_ref].sum(), rel=1e-12)
