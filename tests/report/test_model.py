"""ReportModel: verdict, sections, check rows, purity."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from designkit.report.model import (
    ReportModel,
    build_report_model,
    verdict_of,
)
from designkit.verification.check import Check
from tests.report.conftest import make_result, servo_checks


def test_verified_verdict(servo_result, servo_model):
    assert servo_result.verified
    assert servo_model.verified is True
    assert servo_model.verdict == "VERIFIED"
    assert servo_model.verdict_kind == "verified"
    assert servo_model.verdict_summary.startswith("5 passed, 0 failed, 0 undecided")


def test_failed_verdict_names_the_failed_checks(failed_result):
    model = build_report_model(failed_result)
    assert not failed_result.verified
    assert model.verified is False
    assert model.verdict == "FAILED: overshoot"
    assert model.verdict_kind == "failed"


def test_undecided_verdict_is_not_a_pass(undecided_result):
    model = build_report_model(undecided_result)
    assert not undecided_result.verified
    assert model.verdict == "UNDECIDED: overshoot"
    assert model.verdict_kind == "undecided"


def test_failed_and_undecided_together():
    checks = (Check("a", True), Check("b", None), Check("c", False), Check("d", False))
    assert verdict_of(checks) == ("FAILED: c, d; UNDECIDED: b", "failed")


def test_no_checks_is_vacuously_verified_and_says_so():
    result = make_result(checks=(), simulate=False, margins=False)
    model = build_report_model(result)
    assert result.verified and model.verdict == "VERIFIED"
    assert "No checks were run" in model.verdict_summary
    assert model.checks == () and model.simulation == ()


def test_spec_echo_hash_path_and_versions(servo_result, servo_model):
    assert servo_model.spec_text == servo_result.loaded.text
    assert servo_model.spec_sha256 == servo_result.loaded.sha256
    assert servo_model.spec_path == "specs/report-servo.yaml"
    assert dict(servo_model.versions) == dict(servo_result.versions)
    assert "designkit" in dict(servo_model.versions)
    assert servo_model.name == "report-servo"
    assert "report-servo" in servo_model.title and "PID position servo" in servo_model.title


def test_gains_have_units_and_six_digits(servo_model):
    gains = {g.name: g for g in servo_model.gains}
    assert [g.name for g in servo_model.gains] == ["K1", "K2", "K3", "K4"]
    assert gains["K1"].value == "50" and gains["K1"].unit == "N·m/rad"
    assert gains["K2"].value == "6.75" and gains["K2"].unit == "N·m·s/rad"
    assert gains["K3"].unit == "N·m/(rad·s)"
    assert gains["K4"].value == "-0.166667" and gains["K4"].unit == "s"


def test_plant_and_uncertainty_rows(servo_model):
    rows = [(r.name, r.value, r.unit) for r in servo_model.plant_parameters]
    assert ("Km", "2", "(rad/s)/(N·m)") in rows
    assert ("τ", "0.5", "s") in rows
    assert ("Km", "[1.5, 2.5]", "(rad/s)/(N·m)") in rows
    assert "Km" in servo_model.plant_equation and "τ" in servo_model.plant_equation


def test_poles_requested_vs_achieved(servo_model):
    assert [p.requested for p in servo_model.poles] == ["-20", "-5", "-4"]
    assert [p.achieved for p in servo_model.poles] == ["-20", "-5", "-4"]
    assert all(float(p.error) < 1e-9 for p in servo_model.poles)
    assert [z.value for z in servo_model.zeros] == ["-3", "-3"]


def test_formulas_notes_and_loop_margins(servo_result, servo_model):
    from designkit.families import family

    assert servo_model.formulas == (*family("pid_servo").display.law, *servo_result.design.formulas)
    assert servo_model.notes == servo_result.design.notes
    loop = {r.name: r for r in servo_model.loop}
    assert float(loop["phase margin"].value) == pytest.approx(78.75, abs=0.01)
    assert loop["gain margin"].value == "∞"


def test_check_rows_in_order_with_formatted_values(servo_model):
    rows = servo_model.checks
    assert [r.name for r in rows] == ["routh_hurwitz", "lyapunov", "overshoot", "robust_stability", "loop_margins"]
    assert [r.status for r in rows] == ["PASS"] * 5
    over = rows[2]
    assert (over.target, over.achieved, over.margin, over.unit) == ("<= 10 %", "4.2", "+5.8", "%")
    assert over.certificate == ()


def test_model_is_frozen_and_build_is_pure(servo_result):
    before = json.dumps(servo_result.to_json(), sort_keys=True)
    sim_before = servo_result.simulation.state.copy()
    model = build_report_model(servo_result)
    assert isinstance(model, ReportModel)
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.verdict = "x"  # type: ignore[misc]
    assert json.dumps(servo_result.to_json(), sort_keys=True) == before
    np.testing.assert_array_equal(servo_result.simulation.state, sim_before)


def test_build_is_deterministic(servo_result, servo_model):
    again = build_report_model(servo_result)
    assert again == servo_model


def test_tracking_model(tracking_result):
    model = build_report_model(tracking_result)
    assert model.controller == "PID trajectory tracking (pid_tracking)"
    assert [g.name for g in model.gains] == ["K1", "K2", "K3"]
    assert model.zeros == ()
    loop = {r.name: r for r in model.loop}
    assert float(loop["gain margin"].value.split()[0]) < 1  # conditionally stable loop
    assert "conditionally stable" in loop["gain margin"].meaning


def test_simulation_settings_rows(servo_model):
    rows = {r.name: r.value for r in servo_model.simulation}
    assert rows["kind"] == "step"
    assert rows["integrator"] == "linear (test fixture)"
    assert rows["samples"].startswith("801 over")


def test_failed_check_detail_kept_verbatim():
    result = make_result(checks=servo_checks(overshoot_passed=False, detail_extra=" <b>&"), simulate=False)
    model = build_report_model(result)
    assert model.checks[2].detail.endswith(" <b>&")  # escaping is the renderers' job
