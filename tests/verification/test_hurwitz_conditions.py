"""Routh-Hurwitz conditions of a design: gain conditions of the notes, the design check, and the
equivalence Routh <=> eigenvalues in the open LHP <=> Lyapunov LMI feasible."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import assume, event, given, settings
from hypothesis import strategies as st

from designkit.families import pid_servo, pid_tracking
from designkit.models.link import LinkPlant
from designkit.verification.hurwitz_conditions import cubic_conditions, gain_conditions, routh_hurwitz_design
from designkit.verification.lyapunov import lyapunov_lmi
from designkit.verification.routh import routh_array
from tests import oracles
from tests.verification.helpers import plants, pole_sets

PLANT = LinkPlant(Km=2.0, tau=0.5)


@settings(max_examples=50, deadline=None)
@given(plant=plants, poles=pole_sets(), zero=st.floats(-50, -0.1))
def test_servo_gain_conditions_are_the_notes_formulas(plant, poles, zero):
    design = pid_servo.design(plant, poles, zero)
    K1, K2, K3 = (design.gains[k] for k in ("K1", "K2", "K3"))
    conds = {c.condition: c for c in gain_conditions(design, plant)}
    assert conds["K3 > 0"].threshold == pytest.approx(0.0, abs=1e-9 * (1 + abs(K3)))
    assert conds["K2 > -1/Km"].threshold == pytest.approx(-1.0 / plant.Km, rel=1e-9, abs=1e-12 * (1 + abs(K2)))
    assert conds["K1 > tau K3/(1 + Km K2)"].threshold == pytest.approx(
        plant.tau * K3 / (1 + plant.Km * K2), rel=1e-9, abs=1e-12 * (1 + abs(K1))
    )
    assert all(c.margin > 0 for c in conds.values())  # synthesised for stable poles


def test_tracking_gain_conditions_on_nominal_plant():
    design = pid_tracking.design(PLANT, [-10, -12, -15])
    K2, K3 = design.gains["K2"], design.gains["K3"]
    conds = gain_conditions(design, PLANT)
    assert conds[1].threshold == pytest.approx(0.0, abs=1e-12)  # K2 > 0 on the nominal plant
    assert conds[2].threshold == pytest.approx(PLANT.tau * K3 / (PLANT.Km * K2), rel=1e-12)


def test_design_check_fails_and_names_the_condition():
    design = pid_servo.design(PLANT, [-4, -5, -20], -3.0)
    bad = dataclasses.replace(design, gains=design.gains.replace(K1=1.0))  # below tau K3/(1 + Km K2) = 3.45
    check = routh_hurwitz_design(bad)
    assert check.passed is False
    assert "K1 > tau K3/(1 + Km K2)" in check.detail
    cond = {c["condition"]: c for c in check.certificate["conditions"]}["K1 > tau K3/(1 + Km K2)"]
    assert cond["margin"] == pytest.approx(1.0 - 0.5 * 100.0 / 14.5)


def test_cubic_conditions_match_array():
    for coeffs in ([1, 3, 3, 1], [1, 1, 1, 2], [1, -1, 1, 1], [2, 3, 1, 0.5]):
        closed = all(c.margin > 0 for c in cubic_conditions(*coeffs))
        assert closed == (routh_array(coeffs).status == "stable")


gains_st = st.fixed_dictionaries({
    "K1": st.floats(-5.0, 200.0), "K2": st.floats(-3.0, 20.0), "K3": st.floats(-50.0, 500.0), "K4": st.just(0.0),
})


@settings(max_examples=100, deadline=None)
@given(plant=plants, gains=gains_st, kind=st.sampled_from(["pid_servo", "pid_tracking"]))
def test_routh_iff_eigenvalues_iff_lyapunov(plant, gains, kind):
    """Random gains and plants, kept away from the boundary: the three tests agree."""
    base = pid_servo.design(plant, [-1, -2, -3], -4.0) if kind == "pid_servo" else pid_tracking.design(
        plant, [-1, -2, -3]
    )
    used = gains if kind == "pid_servo" else {k: gains[k] for k in ("K1", "K2", "K3")}
    design = dataclasses.replace(base, gains=base.gains.replace(**used))
    # the hand-derived closed loop (tests/oracles.py), not the library's linearization
    A = (oracles.servo_closed_loop(used, plant) if kind == "pid_servo"
         else oracles.tracking_closed_loop(used, plant, base.plant)).A
    ev = np.linalg.eigvals(A)
    assume(np.min(np.abs(ev.real)) > 1e-3 * max(1.0, np.max(np.abs(ev))))
    eig_stable = bool(np.all(ev.real < 0))
    event("stable" if eig_stable else "unstable")
    routh = routh_hurwitz_design(design, plant)
    assert routh.passed is eig_stable
    lyap = lyapunov_lmi(A)
    if eig_stable:
        # a certificate must be found unless the conditioning exceeds 1/eps (then undecided, never False)
        assert lyap.passed in (True, None)
        if lyap.passed is None:
            assert lyap.certificate["t"] is not None and lyap.certificate["t"] < 1e-5
    else:
        assert lyap.passed is False
