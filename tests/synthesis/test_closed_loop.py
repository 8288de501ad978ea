"""The plant composed with a family's law, linearized: against hand-derived loops and python-control."""

from __future__ import annotations

import control
import numpy as np
import pytest
from hypothesis import given, settings

from designkit.families import pid_servo, pid_tracking
from designkit.models.link import LinkPlant
from designkit.models.robot_plant import zoo_plant
from designkit.synthesis.closed_loop import equilibria, linearize, loop_functions, reference_names
from tests import oracles
from tests.tolerances import TOL
from tests.verification.helpers import plants, pole_sets


@settings(max_examples=25, deadline=None)
@given(plant=plants, poles=pole_sets())
def test_servo_linearization_equals_the_hand_derived_loop(plant, poles):
    design = pid_servo.design(plant, poles, -0.7)
    ref = oracles.servo_closed_loop(dict(design.gains), plant)
    cl = design.closed_loop
    for name in ("A", "B", "C", "D"):
        np.testing.assert_allclose(getattr(cl, name), getattr(ref, name), rtol=TOL["algebra"], atol=TOL["algebra"])
    assert cl.inputs == oracles.INPUTS and cl.outputs == ("x1", "u")


@settings(max_examples=25, deadline=None)
@given(plant=plants, poles=pole_sets(), other=plants)
def test_tracker_on_another_plant_equals_the_hand_derived_loop(plant, poles, other):
    design = pid_tracking.design(plant, poles)
    got, _, point = linearize(other, pid_tracking.law(design), [0.0, 0.0, 0.0])
    ref = oracles.tracking_closed_loop(dict(design.gains), other, plant)
    np.testing.assert_allclose(got.A, ref.A, rtol=TOL["algebra"], atol=TOL["algebra"])
    np.testing.assert_allclose(got.B, ref.B, rtol=TOL["algebra"], atol=TOL["algebra"])
    assert point["residual"] <= 1e-12


def test_servo_closed_loop_equals_python_control_interconnection():
    """x1/xD and x1/xi from a python-control interconnection of the plant and the controller blocks."""
    plant = LinkPlant(Km=1.3, tau=0.8)
    design = pid_servo.design(plant, [-3 + 4j, -3 - 4j, -12], -2.0)
    g = design.gains
    s = control.tf("s")
    P = plant.Km / (s * (plant.tau * s + 1))
    C_fb = g["K1"] + g["K2"] * s + g["K3"] / s
    C_ff = g["K1"] + g["K3"] / s + g["K3"] * g["K4"]
    x1_xD = control.minreal(P * C_ff / (1 + P * C_fb), verbose=False)
    x1_xi = control.minreal(P / (1 + P * C_fb), verbose=False)
    ss = design.closed_loop.to_control()
    w = np.logspace(-2, 3, 40)
    np.testing.assert_allclose(ss[0, 0].frequency_response(w).complex, x1_xD.frequency_response(w).complex,
                               rtol=1e-9)
    np.testing.assert_allclose(ss[0, 3].frequency_response(w).complex, x1_xi.frequency_response(w).complex,
                               rtol=1e-9)


def test_input_loop_gives_the_closed_loop_back():
    """Closing the input loop again: A = A_open + B (-C) with the loop broken at the plant input."""
    design = pid_servo.design(LinkPlant(2.0, 0.5), [-4, -5, -20], -3.0)
    lp = design.input_loop
    A_open = lp.A + lp.B @ lp.C  # the loop broken
    np.testing.assert_allclose(A_open - lp.B @ lp.C, design.closed_loop.A, atol=1e-12)
    # the open loop has the plant's and the integrator's poles: 0 (twice) and -1/tau
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(A_open).real), [-2.0, 0.0, 0.0], atol=1e-12)


def test_batched_equilibria_equal_one_by_one_and_hold_the_arm_against_gravity():
    plant = zoo_plant("planar2r")
    design = pid_servo.design(LinkPlant(0.5, 0.9), [-4, -5, -20], -3.0)  # for its gains only
    from designkit.families import decentralized_pid
    from designkit.families.decentralized_pid.data import DecentralizedPidData
    from designkit.synthesis.design import Design, Gain, Gains

    gains = Gains.of(Gain(k, [float(design.gains[k])] * 2, design.gains.unit(k)) for k in ("K1", "K2", "K3", "K4"))
    data = DecentralizedPidData(configuration=(0.0, 0.0), links=(), gravity_feedforward="none", workspace=None)
    d = Design(kind="decentralized_pid", plant=plant, gains=gains, data=data)
    law = decentralized_pid.law(d)
    fns = loop_functions(plant, law)
    r0 = np.array([0.4, -0.3, 0, 0, 0, 0])
    z0 = np.zeros(6)
    P = np.tile(plant.parameter_vector, (3, 1))
    P[:, plant.parameter_names.index("m2")] = [2.0, 3.0, 4.0]
    eq = equilibria(fns, z0, r0, P)
    assert np.all(eq.converged)
    for k in range(3):
        one = equilibria(fns, z0, r0, P[k:k + 1])
        np.testing.assert_allclose(eq.z[k], one.z[0], rtol=TOL["algebra"], atol=TOL["algebra"])
        q = eq.z[k, :2]
        np.testing.assert_allclose(q, r0[:2], atol=1e-10)  # integral action: at rest on the reference
        # the PIDs' torque holds gravity: the plant's acceleration is zero at (q, 0) under that torque
        u = np.asarray(fns.loop(eq.z[k], r0, np.zeros(2), P[k])[1]).ravel()
        np.testing.assert_allclose(plant.rhs(np.concatenate([q, [0, 0]]), u, p=P[k]), 0.0, atol=1e-9)


def test_reference_names():
    assert reference_names(1) == ("xD", "xDd", "xDdd")
    assert reference_names(2) == ("xD1", "xD2", "xDd1", "xDd2", "xDdd1", "xDdd2")


def test_no_equilibrium_is_an_error_not_a_guess():
    design = pid_servo.design(LinkPlant(2.0, 0.5), [-4, -5, -20], -3.0)
    bad = design.gains.replace(K3=0.0, K1=0.0)  # a double pole at 0: the Jacobian is singular
    import dataclasses

    with pytest.raises(ValueError, match="no equilibrium"):
        linearize(design.plant, pid_servo.law(dataclasses.replace(design, gains=bad)), [1.0, 0.0, 0.0],
                  z0=[0.0, 0.0, 0.0])
