"""Spec validation: every bad input gives one SpecError naming the key path."""

from __future__ import annotations

import pytest

from designkit.errors import SpecError
from designkit.schema.loader import load_spec, parse_spec
from tests.problems import POSSPEED_YAML


def test_the_posspeed_spec_loads_with_its_poles_and_zero():
    loaded = parse_spec(POSSPEED_YAML)
    assert loaded.spec.controller.poles == [-4, -5, -20]
    assert loaded.spec.controller.zero == -3
    assert len(loaded.sha256) == 64


@pytest.mark.parametrize(
    ("replace", "by", "path", "words"),
    [
        ("-20]", "0.5]", "controller.poles[2]", "negative real part"),
        ("-20]", "0]", "controller.poles[2]", "negative real part"),
        ("[-4, -5, -20]", "['-4+2j', -5, -20]", "controller.poles", "no conjugate"),
        ("[-4, -5, -20]", "[-4, -5]", "controller.poles", "exactly 3"),
        ("[-4, -5, -20]", "[-4, -5, abc]", "controller.poles[2]", "complex string"),
        ("[-4, -5, -20]", "[-4, -5, .inf]", "controller.poles[2]", "finite"),
        ("Km: 2.0", "Km: -1", "plant.Km", "greater than 0"),
        ("Km: 2.0", "Km: 0", "plant.Km", "greater than 0"),
        ("tau: 0.5", "tau: 0", "plant.tau", "greater than 0"),
        ("tau: 0.5", "tau: .nan", "plant.tau", "finite"),
        ("Km: 2.0", "Km: two", "plant.Km", "must be a number, got the string 'two'"),
        ("zero: -3", "zero: 3", "controller.zero", "negative"),
        ("zero: -3", "zero: -5", "controller.zero", "differ from every pole"),
        ("zero: -3", "zero: -3, gain: 1", "controller.gain", "unknown key"),
        ("tau: 0.5}", "tau: 0.5, mass: 3}", "plant.mass", "unknown key"),
        ("kind: link", "kind: arm", "plant.kind", "'link'"),
        ("kind: pid_servo", "kind: pid_magic", "controller.kind", "pid_magic"),
        ("{kind: link, Km: 2.0, tau: 0.5}", "{kind: robot}", "plant", "exactly one of robot"),
        ("{kind: link, Km: 2.0, tau: 0.5}", "{kind: robot, robot: planar2r, dh: [{a: 1}]}", "plant",
         "got robot and dh"),
        ("kind: pid_servo", "kind: decentralized_pid", "controller.kind", "robot plant"),
        ("tau: 0.5}", "tau: 0.5, uncertainty: {Km: [2, 1]}}", "plant.uncertainty.Km", "low <= high"),
        ("tau: 0.5}", "tau: 0.5, uncertainty: {grid: 5}}", "plant.uncertainty", "at least one parameter"),
        ("name: posspeed-link\n", "", "name", "missing"),
        (", poles: [-4, -5, -20]", "", "controller.poles", "missing"),
    ],
)
def test_bad_input_names_the_key_path(replace, by, path, words):
    text = POSSPEED_YAML.replace(replace, by)
    assert text != POSSPEED_YAML
    with pytest.raises(SpecError) as info:
        parse_spec(text)
    assert info.value.path == path, str(info.value)
    assert words in info.value.message
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("text", ["name: [", "just a string", "- a\n- list", ""])
def test_malformed_yaml_or_not_a_mapping(text):
    with pytest.raises(SpecError) as info:
        parse_spec(text)
    assert "\n" not in str(info.value)


def test_unknown_top_level_key_and_uncertainty_order():
    with pytest.raises(SpecError, match="^plants: unknown key"):
        parse_spec(POSSPEED_YAML + "plants: 1\n")
    bad = POSSPEED_YAML.replace("tau: 0.5}", "tau: 0.5, uncertainty: {Km: [3, 1]}}")
    with pytest.raises(SpecError, match=r"plant.uncertainty.Km: interval must be \[low, high\]"):
        parse_spec(bad)


def test_missing_file(tmp_path):
    with pytest.raises(SpecError, match="not found"):
        load_spec(tmp_path / "nope.yaml")


def test_requirements_can_replace_poles():
    text = POSSPEED_YAML.replace(", poles: [-4, -5, -20], zero: -3", "") + (
        "requirements: {overshoot: 5, settling_time: 1.0}\n"
    )
    assert parse_spec(text).spec.controller.poles is None
