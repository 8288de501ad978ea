"""Only JSON's types are read: text is not a number and a number is not a boolean (cases from the fuzzed corpus)."""

from __future__ import annotations

import pytest

from designkit.errors import SpecError
from designkit.schema.loader import parse_spec

LINK = "name: t\nplant: {kind: link, Km: 2.0, tau: 0.5}\ncontroller: {kind: pid_servo, poles: [-4, -5, -20]}\n"
ROBOT = "name: t\nplant: {kind: robot, robot: planar2r}\ncontroller: {kind: computed_torque, poles: [-20, -20]}\n"


@pytest.mark.parametrize("text, path, words", [
    (LINK.replace("Km: 2.0", "Km: '2.0'"), "plant.Km", "must be a number, got the string '2.0'"),
    (LINK.replace("tau: 0.5", 'tau: "0.5"'), "plant.tau", "must be a number"),
    (LINK.replace("[-4, -5, -20]", "[-4, -5, -20], zero: '-3'"), "controller.zero", "must be a number"),
    (ROBOT.replace("robot: planar2r", "robot: planar2r, parameters: {m2: '3'}"), "plant.parameters.m2",
     "must be a number"),
    (ROBOT.replace("robot: planar2r", "robot: planar2r, friction: 1"), "plant.friction", "must be true or false"),
    (ROBOT.replace("robot: planar2r", "robot: planar2r, motor_inertia: 0"), "plant.motor_inertia",
     "must be true or false"),
])
def test_loose_types_are_refused_with_the_key_path(text, path, words):
    with pytest.raises(SpecError) as err:
        parse_spec(text)
    assert err.value.path == path and words in err.value.message


def test_strings_where_strings_belong_are_still_read():
    spec = parse_spec(ROBOT.replace("robot: planar2r", "robot: planar2r, friction: true")
                      .replace("[-20, -20]", "['-20+1j', '-20-1j']")).spec
    assert spec.plant.friction is True and spec.controller.poles is not None


@pytest.mark.parametrize("written", ["0x1F", "017", "1_000", "1:30", "0o17"])
def test_numbers_only_as_json_writes_them(written):
    with pytest.raises(SpecError) as err:
        parse_spec(LINK.replace("Km: 2.0", f"Km: {written}"))
    assert err.value.path == "plant.Km" and f"got the string '{written}'" in err.value.message


@pytest.mark.parametrize("written, value", [("2", 2.0), ("2.5", 2.5), ("1e-3", 1e-3), ("2.5E+2", 250.0), (".5", 0.5)])
def test_json_numbers_are_read(written, value):
    assert parse_spec(LINK.replace("Km: 2.0", f"Km: {written}")).spec.plant.Km == value


SLIDING = ("name: t\nplant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.4, 2.6]}}\n"
           "controller: {kind: sliding_mode, sliding_poles: [-5], margin: 0.2, perturbation_bound: 1.0}\n")


@pytest.mark.parametrize("text, path", [
    (LINK + "simulation: {noise: {std: 5e-324}}\n", "simulation.noise.std"),
    (SLIDING.replace("margin: 0.2", "margin: 0.2, chattering_band: 5e-324"), "controller.chattering_band"),
    (SLIDING.replace("margin: 0.2", "margin: 0.2, alpha: -2e-308"), "controller.alpha"),
    (ROBOT + "simulation: {step: [0.5, 4e-320]}\n", "simulation.step"),
])
def test_subnormal_numbers_are_refused_with_the_key_path(text, path):
    """A nonzero number below the smallest normal float (2.2250738585072014e-308) in magnitude, in a field whose
    range holds it: whatever is computed from it (a step, a scale) underflows to 0."""
    with pytest.raises(SpecError) as err:
        parse_spec(text)
    assert err.value.path == path and "subnormal" in err.value.message


def test_a_range_that_excludes_subnormal_numbers_says_so_itself():
    with pytest.raises(SpecError) as err:
        parse_spec(LINK.replace("Km: 2.0", "Km: 5e-324"))
    assert err.value.path == "plant.Km" and "must be between 1e-6 and 1e6" in err.value.message


def test_zero_and_the_smallest_normal_numbers_are_read():
    smallest = 2.2250738585072014e-308  # 2**-1022, written out
    assert smallest == 2.0**-1022
    spec = parse_spec(SLIDING.replace("margin: 0.2", f"margin: 0.2, alpha: {smallest!r}")).spec
    assert spec.controller.alpha == smallest
    assert parse_spec(LINK + "simulation: {noise: {std: 0.0}}\n").spec.simulation.noise.std == 0.0
