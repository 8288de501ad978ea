"""The example specs through ``designkit verify --json``, and the conformance case proposed for tests/problems.py."""

from __future__ import annotations

import json

import pytest

from designkit.cli import main
from tests.families.sliding_mode.common import LINK_SPEC, WEAK_SPEC, run_text

CASE = ("{kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 0.5}",
        "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
        "{overshoot: 2, settling_time: 1.5, steady_state_error: 0.005}")
"""The line proposed for ``tests/problems.py`` CASES["sliding_mode"]["link"]."""


def _verify(path, capsys) -> tuple[int, dict]:
    code = main(["verify", str(path), "--json", "--jobs", "1"])
    out = capsys.readouterr().out
    return code, json.loads(out)


def test_link_example_verifies_with_the_gains_in_the_json(capsys):
    code, data = _verify(LINK_SPEC, capsys)
    assert code == 0 and data["verified"] is True
    assert set(data["gains"]) == {"alpha", "beta", "M", "c"}
    assert data["gain_units"] == {"alpha": "N*m/rad", "beta": "N*m/rad", "M": "N*m", "c": "1/s"}
    assert data["gains"]["c"] == 5.0 and data["gains"]["M"] == pytest.approx(1.2)
    assert data["poles"] == [[-5.0, 0.0]]
    sm = data["sliding"]
    assert sm["sliding_function"] == "s = x2 + c (x1 - xD)" and sm["sliding_pole"] == -5.0
    assert sm["measured_pole"] == pytest.approx(-5.0, rel=1e-2)
    assert 0 < sm["reaching_time"] < 1.0 and sm["chattering_amplitude"] <= sm["band_run"] <= sm["band_target"]
    statuses = {c["name"]: c["status"] for c in data["checks"]}
    assert statuses == {**{name: "PASS" for name in (
        "sliding_existence", "sliding_reaching", "sliding_perturbation", "reaching_time", "sliding_band",
        "sliding_pole", "overshoot", "settling_time", "steady_state_error", "command_switching", "generated_code")},
        "chattering": "FAIL"}  # informational: the relay reverses at a rate the integration step sets
    assert any("numerical choice" in w for w in data["warnings"])


def test_weak_switching_example_fails_and_says_by_how_much(capsys):
    code, data = _verify(WEAK_SPEC, capsys)
    assert code == 1 and data["verified"] is False
    checks = {c["name"]: c for c in data["checks"]}
    pert = checks["sliding_perturbation"]
    assert pert["status"] == "FAIL"
    assert "M = 0.8 N*m is below sup|xi| = 1 N*m by 0.2 N*m; M >= 1.2 N*m with the 20 % margin" in pert["detail"]
    assert checks["sliding_band"]["status"] == "FAIL"
    assert checks["sliding_existence"]["status"] == checks["sliding_reaching"]["status"] == "PASS"


@pytest.mark.parametrize("path", [LINK_SPEC, WEAK_SPEC], ids=["link", "weak"])
def test_example_specs_round_trip_through_the_json_schema(path):
    import jsonschema

    from designkit.schema.loader import load_spec
    from designkit.schema.spec import Spec

    loaded = load_spec(path)
    assert loaded.spec.description
    data = json.loads(loaded.spec.model_dump_json())
    jsonschema.validate(data, Spec.model_json_schema())
    assert Spec.model_validate(data) == loaded.spec


def test_proposed_conformance_case_verifies():
    from tests.problems import PLANTS, for_family

    controller, simulation, requirements = CASE
    text = (f"name: conformance-sliding_mode-link\nplant: {for_family('sliding_mode', PLANTS['link'])}\n"
            f"controller: {controller}\n"
            f"requirements: {requirements}\nsimulation: {simulation}\n")
    result = run_text(text)
    assert result.verified, [(c.name, c.detail) for c in result.failed]
