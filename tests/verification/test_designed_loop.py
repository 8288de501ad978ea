"""designed_loop: a run that does not start at the designed equilibrium, or whose law is not the designed loop,
fails."""

from __future__ import annotations

import dataclasses

import pytest

from designkit.families import synthesize
from designkit.families.pid_servo import law as servo_law
from designkit.schema.loader import parse_spec
from designkit.verification.designed_loop import SMALL_SIGNAL_REL, designed_loop_check

SERVO = """\
name: dl
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
simulation: {duration: 3.0, initial_position: 0.5, step: 0.4}
"""


@pytest.fixture(scope="module")
def servo():
    spec = parse_spec(SERVO).spec
    return spec, synthesize(spec)


def test_the_designed_servo_passes_from_any_initial_position(servo):
    spec, design = servo
    check = designed_loop_check(spec, design)
    assert check.passed is True, check.detail
    assert check.certificate["largest_relative_difference"] < 1e-6  # RK4 against the exact response
    assert check.certificate["controller_start"][0] == pytest.approx(float(design.gains["K4"]) * 0.5)


def test_an_integral_started_at_zero_off_the_origin_fails(servo):
    """The seam the check guards: K3 K4 xD on the absolute reference, the integral at 0, the arm at q0 = 0.5."""
    spec, design = servo
    at_zero = dataclasses.replace(design, law=dataclasses.replace(design.law, rest_start=()))
    check = designed_loop_check(spec, at_zero)
    assert check.passed is False
    assert "does not start at rest" in check.detail
    # the residual is the plant's acceleration the unbalanced feed-forward gives: (Km/tau) K3 K4 q0
    K3, K4 = float(design.gains["K3"]), float(design.gains["K4"])
    assert check.achieved == pytest.approx(abs(2.0 / 0.5 * K3 * K4 * 0.5), rel=1e-9)


def test_a_law_that_is_not_the_designed_loop_fails_in_the_small(servo):
    """The closed loop certified for one K1, the law simulated with another: the small-signal run leaves it."""
    spec, design = servo
    other = dataclasses.replace(design, gains=design.gains.replace(K1=1.2 * float(design.gains["K1"])))
    swapped = dataclasses.replace(design, law=servo_law(other))
    check = designed_loop_check(spec, swapped)
    assert check.passed is False and check.achieved > SMALL_SIGNAL_REL
    assert "not the designed loop" in check.detail


def test_a_plant_with_coulomb_friction_is_only_checked_at_rest():
    text = ("name: dl-puma\nplant: {kind: robot, robot: puma560}\ncontroller: {kind: computed_torque, poles: "
            "[-10, -10]}\nsimulation: {duration: 0.5, initial_position: [0, 0.785, -3.14, 0, 0.785, 0], trajectory: "
            "{kind: quintic, amplitude: 0.1, duration: 0.4}}\n")
    spec = parse_spec(text).spec
    check = designed_loop_check(spec, synthesize(spec))
    assert check.passed is True and "Coulomb friction" in check.detail
    assert check.certificate["small_signal"].startswith("not applicable")


def test_an_implemented_controller_is_named_as_left_out_of_the_linear_reference(servo):
    """The implementation (hold, delay, quantisation, actuator) is part of the verified run; the small-signal run
    compares the design without it, and the check says so instead of passing silently."""
    _, design = servo
    spec = parse_spec(SERVO + "implementation: {sampling_period: 0.005, delay: 0.001, quantization: 1.0e-4, "
                      "actuator: {limit: 20, bandwidth: 300}}\n").spec
    check = designed_loop_check(spec, design)
    assert check.passed is True, check.detail
    assert check.certificate["largest_relative_difference"] < 1e-6  # the designed loop itself, not the implemented
    assert "leaves out the controller as implemented (the sampling and hold, the computation delay" in check.detail
    assert "not of the designed linear loop" in check.certificate["not_in_linear_reference"]
    plain = designed_loop_check(parse_spec(SERVO).spec, design)
    assert "not_in_linear_reference" not in plain.certificate and "leaves out" not in plain.detail
