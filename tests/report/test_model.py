"""ReportModel: verdict, formatting, certificates, purity."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from designkit.report.model import (
    ReportModel,
    build_report_model,
    fmt_number,
    render_certificate,
    verdict_of,
)
from designkit.verification.check import Check
from tests.report.conftest import make_result, servo_checks


def test_verified_verdict(servo_result, servo_model):
    assert servo_result.verified
    assert servo_model.verified is True
    assert servo_model.verdict == "VERIFIED"
    assert servo_model.verdict_kind == "verified"
    assert servo_model.verdict_summary.startswith("4 passed, 0 failed, 0 undecided")


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
    result = make_result(checks=(), simulate=False)
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
    assert servo_model.formulas == servo_result.design.formulas
    assert servo_model.notes == servo_result.design.notes
    loop = {r.name: r for r in servo_model.loop}
    assert float(loop["phase margin"].value) == pytest.approx(78.75, abs=0.01)
    assert loop["gain margin"].value == "∞"


def test_check_rows_in_order_with_formatted_values(servo_model):
    rows = servo_model.checks
    assert [r.name for r in rows] == ["routh_hurwitz", "lyapunov", "overshoot", "robust_stability"]
    assert [r.status for r in rows] == ["PASS"] * 4
    over = rows[2]
    assert (over.target, over.achieved, over.margin, over.unit) == ("<= 10 %", "4.2", "+5.8", "%")
    assert over.certificate == ()


def test_lyapunov_certificate_matrix_has_four_significant_digits(servo_model):
    cert = {e.key: e for e in servo_model.checks[1].certificate}
    P = cert["P"].matrix
    assert P is not None and cert["P"].header is None
    assert P[0] == ("1", "0.1235", "-3.3e-05")
    assert P[2] == ("-3.3e-05", "0.01", "0.25")
    assert cert["eig_P"].text == "[0.2, 0.5, 1]"
    assert cert["solver_status"].text == "optimal"
    assert cert["eig_A"].text == "[[-4, -5, -20]]"  # [re, im] pairs shown as (real) complex numbers


def test_certificate_records_become_a_table(servo_model):
    cert = {e.key: e for e in servo_model.checks[0].certificate}
    cond = cert["conditions"]
    assert cond.header == ("condition", "value", "threshold", "margin", "unit")
    assert cond.matrix[0] == ("K2 > -1/Km", "6.75", "-0.5", "7.25", "N*m*s/rad")
    assert cert["coefficients"].text == "[0.5, 14.5, 100, 200]"


def test_certificate_grid_is_summarised(servo_model):
    (entry,) = servo_model.checks[3].certificate
    assert entry.key == "grid"
    assert "Km ∈ [1.5, 2.5] (5 points)" in entry.text and "robustness figure" in entry.text


def test_render_certificate_edge_cases():
    big = np.arange(100.0).reshape(10, 10).tolist()
    entries = {e.key: e for e in render_certificate({
        "M": big, "v": list(range(20)), "nested": {"a": 1.23456, "b": "x"}, "none": None,
        "evidence": {"eigenvalue": [0.5, -2.0]}, "flag": True, "pair": [1.0, 2.0],
    })}
    M = entries["M"].matrix
    assert len(M) == 8 and M[-1][0] == "⋮" and len(M[0]) == 8 and M[0][-1] == "…"
    assert entries["v"].text.endswith("(20 items)") and "…" in entries["v"].text
    assert entries["nested.a"].text == "1.235" and entries["nested.b"].text == "x"
    assert entries["none"].text == "—"
    assert entries["evidence.eigenvalue"].text == "0.5 - 2j"
    assert entries["flag"].text == "true"
    assert entries["pair"].text == "[1, 2]"


@pytest.mark.parametrize(("value", "text"), [
    (0.0, "0"), (1.0, "1"), (123456.0, "1.235e+05"), (-0.000123456, "-0.0001235"), (float("inf"), "∞"),
    (float("-inf"), "-∞"), (float("nan"), "nan"), (None, "—"), (3 + 4j, "3 + 4j"), (-2.0 + 0j, "-2"),
    (np.float64(2.5), "2.5"), (np.int64(7), "7"), ("text", "text"),
])
def test_fmt_number(value, text):
    assert fmt_number(value).replace("−", "-") == text


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
