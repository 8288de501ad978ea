"""ReportModel: verdict, sections, check rows, purity."""

from __future__ import annotations

import dataclasses
import json
from types import SimpleNamespace

import numpy as np
import pytest

from designkit.report.model import ReportModel, build_report_model
from designkit.report.verdict import verdict_of
from designkit.verification.check import Check
from tests.report.conftest import make_result, servo_checks


def test_verified_verdict(servo_result, servo_model):
    assert servo_result.verified
    assert servo_model.verified is True
    assert servo_model.verdict == "VERIFIED"
    assert servo_model.verdict_kind == "verified"
    assert servo_model.verdict_summary.startswith("5 passed, 0 failed, 0 undecided")


def test_failed_verdict_names_the_failed_checks(failed_result):
    model = build_report_model(failed_result, studies=False)
    assert not failed_result.verified
    assert model.verified is False
    assert model.verdict == "FAILED: Overshoot"
    assert model.verdict_kind == "failed"


def test_undecided_verdict_is_not_a_pass(undecided_result):
    model = build_report_model(undecided_result, studies=False)
    assert not undecided_result.verified
    assert model.verdict == "UNDECIDED: Overshoot"
    assert model.verdict_kind == "undecided"


def test_failed_and_undecided_together():
    checks = (Check("a", True), Check("b", None), Check("c", False), Check("d", False))
    assert verdict_of(checks) == ("FAILED: C, D; UNDECIDED: B", "failed")


def test_the_verdict_names_checks_in_words_per_joint_ones_grouped():
    checks = (Check("pole_placement[joint1]", False, label="Pole placement (joint1)"),
              Check("pole_placement[joint2]", False, label="Pole placement (joint2)"),
              Check("settling_time", False, label="Settling time (2 % band)"), Check("max_control", None))
    assert verdict_of(checks) == ("FAILED: Pole placement (joint1, joint2), Settling time (2 % band); UNDECIDED: "
                                  "Max control", "failed")


def test_no_checks_is_vacuously_verified_and_says_so():
    result = make_result(checks=(), simulate=False, margins=False)
    model = build_report_model(result, studies=False)
    assert result.verified and model.verdict == "VERIFIED"
    assert "No checks were run" in model.verdict_summary
    assert model.checks == () and model.simulation == ()
    assert model.compliance == () and model.why == ()


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
    assert [r.name for r in rows] == ["routh_hurwitz", "lyapunov", "overshoot", "robust_grid", "loop_margins"]
    assert [r.status for r in rows] == ["PASS"] * 5
    over = rows[2]
    assert (over.target, over.achieved, over.margin, over.unit) == ("<= 10 %", "4.2", "+5.8", "%")
    assert over.certificate == ()


def test_model_is_frozen_and_build_is_pure(servo_result):
    before = json.dumps(servo_result.to_json(), sort_keys=True)
    sim_before = servo_result.simulation.state.copy()
    model = build_report_model(servo_result, studies=False)
    assert isinstance(model, ReportModel)
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.verdict = "x"  # type: ignore[misc]
    assert json.dumps(servo_result.to_json(), sort_keys=True) == before
    np.testing.assert_array_equal(servo_result.simulation.state, sim_before)


def test_build_is_deterministic(servo_result, servo_model):
    again = build_report_model(servo_result, studies=False)
    assert again == servo_model


def test_tracking_model(tracking_result):
    model = build_report_model(tracking_result, studies=False)
    assert model.controller == "PID trajectory tracking (pid_tracking)"
    assert [g.name for g in model.gains] == ["K1", "K2", "K3"]
    assert model.zeros == ()
    loop = {r.name: r for r in model.loop}
    assert float(loop["gain margin"].value.split()[0]) < 1  # conditionally stable loop
    assert "conditionally stable" in loop["gain margin"].meaning


def test_simulation_settings_rows(servo_model):
    rows = {r.name: r.value for r in servo_model.simulation}
    assert rows["Kind"] == "step"
    assert rows["Integrator"] == "linear (test fixture)"
    assert rows["Samples"] == "801 over 0 s to 4 s"
    assert rows["Time step"] == "0.005 s"  # labelled in words, with its unit
    assert rows["Measurement noise"] == "none"  # None in words, not Python


def test_simulation_settings_of_nested_values_are_words():
    from designkit.report.simulation_rows import simulation_rows
    from designkit.simulation.result import SimulationResult

    result = make_result()
    sim = result.simulation
    settings = {"dt": 0.001, "ignored": (), "plant": {"Km": 2.0, "tau": 0.5}, "duration_source": "simulation.duration",
                "controller": {"kind": "pid_servo", "gains": {"K1": 50.0}, "anti_windup": {}}, "fastest_rate": 20.0}
    sim = SimulationResult(time=sim.time, reference=sim.reference, state=sim.state,
                           controller_state=sim.controller_state, u_command=sim.u_command, u_applied=sim.u_applied,
                           perturbation=sim.perturbation, measured=sim.measured, kind="step", settings=settings)
    rows = {r.name: r.value for r in simulation_rows(sim, result.design.plant)}
    assert rows["Time step"] == "0.001 s"
    assert rows["Spec settings ignored"] == "none"
    assert rows["Simulated plant"] == "Km = 2 (rad/s)/(N·m), τ = 0.5 s"
    assert rows["Duration taken from"] == "simulation › duration"
    assert rows["Controller"] == "kind = pid_servo, gains = (K1 = 50), anti windup = none"
    assert rows["Fastest closed-loop rate |p|max"] == "20 1/s"
    for value in rows.values():
        assert "{" not in value and "[" not in value and "_" not in value.replace("pid_servo", "")


def test_why_it_failed_rows_have_the_shortfall(failed_result):
    model = build_report_model(failed_result, studies=False)
    (row,) = model.why
    assert (row.check, row.label, row.status) == ("overshoot", "Overshoot", "FAIL")
    assert row.requirement == "≤ 10 %"
    # the fixture's check says 4.2 % achieved with margin +5.8 even though it failed: no shortfall to report
    assert row.shortfall == "not measurable" and row.shortfall_percent == ""
    assert model.why_note
    assert build_report_model(make_result(), studies=False).why == ()  # a verified design has no such section


def test_why_row_shortfall_absolute_and_percent():
    checks = (Check("max_control", False, target="<= 5 N*m", achieved=13386.2, margin=-13381.2, unit="N*m"),
              Check("overshoot", None, target="<= 5 %", achieved=None, margin=None, unit="%"))
    model = build_report_model(make_result(checks=checks, simulate=False, margins=False), studies=False)
    rows = {r.check: r for r in model.why}
    assert rows["max_control"].requirement == "≤ 5 N·m"
    assert rows["max_control"].achieved == "1.339e+04 N·m"
    assert rows["max_control"].shortfall == "1.338e+04 N·m"
    assert rows["max_control"].shortfall_percent == "268000 %"
    assert rows["overshoot"].status == "UNDECIDED" and rows["overshoot"].shortfall == "not decided"
    assert [s.anchor for s in model.contents][:2] == ["why", "compliance"]


def test_compliance_and_informational_rows(servo_result, servo_model):
    required = [c.name for c in servo_result.checks if c.required]
    assert [r.name for r in servo_model.compliance] == required
    assert [r.name for r in servo_model.informational] == [c.name for c in servo_result.checks if not c.required]
    over = next(r for r in servo_model.compliance if r.name == "overshoot")
    assert (over.label, over.limit, over.achieved, over.margin, over.margin_percent) == (
        "Overshoot", "≤ 10 %", "4.2 %", "+5.8 %", "+58 %")
    for row in (*servo_model.compliance, *servo_model.informational):
        assert "_" not in row.label
        if row.evidence:
            assert row.evidence in servo_model.figure_anchors
            fig = servo_model.figures[servo_model.figure_anchors.index(row.evidence)]
            assert row.name in fig.evidence and row.evidence_title == fig.title


def test_figure_anchors_follow_the_file_names(servo_model):
    stems = tuple(f.filename.rsplit(".", 1)[0] for f in servo_model.figures)
    assert all(s.startswith("fig-") for s in stems)  # the file names carry the prefix: anchors are the stems
    assert servo_model.figure_anchors == stems


def test_glossary_explains_the_words_of_the_tables(servo_model):
    terms = dict(servo_model.glossary)
    for word in ("margin", "scaled", "informational", "UNDECIDED"):
        assert terms[word]


def test_equations_are_typeset_from_the_formulas(servo_model):
    from designkit.display.typeset import MathFrac

    labels = [e.label for e in servo_model.equations]
    assert labels[:3] == ["Plant", "Plant", "Control law"]
    assert "Closed loop" in labels and labels[-1] == "Loop transfer (Bode plot)"
    loop = servo_model.equations[-1]
    assert "1 + L(s) = 0" in loop.note and "u = −C(s)" in loop.note
    assert isinstance(loop.nodes[-1], MathFrac)  # Km (K2 s² + K1 s + K3) / (s² (τ s + 1))
    law = servo_model.equations[2]
    k1 = law.nodes[3]
    assert (k1.kind, k1.text, k1.sub) == ("mi", "K", "1")
    assert law.nodes[2].text == "−"  # a minus sign, as in the law: u = −K1 (x1 − xD) ...


def test_equation_splits_words_and_subscripts():
    from designkit.display.typeset import equation

    text = "L(s) = ((Km K2 − 1) s² + Km K1 s + Km K3) / (s² (τ s + 1))  (x2/Km cancels the link damping)"
    eq = equation("Loop", text)
    assert eq.note == "x2/Km cancels the link damping"
    assert eq.nodes[0].text == "L"
    frac = eq.nodes[-1]
    assert frac.den[0].text == "s" and frac.den[0].sup == "2"
    eq = equation("Law", "u_i = -K1_i (q_i - qD_i) on joint i's simplified link; the margins are measured")
    assert eq.note.startswith("on joint i's simplified link")
    assert eq.nodes[0].sub == "i" and eq.nodes[3].sub == "1,i"
    assert equation("Plant", "2 joints: puma560").nodes == ()  # words only


def test_provenance_rows_are_in_the_model(servo_result):
    rows = (("designkit", "9.9"), ("command line", "designkit synth x.yaml"))
    model = build_report_model(servo_result, provenance=rows, studies=False)
    assert model.provenance == rows


def test_failed_check_detail_kept_verbatim():
    result = make_result(checks=servo_checks(overshoot_passed=False, detail_extra=" <b>&"), simulate=False)
    model = build_report_model(result, studies=False)
    assert model.checks[2].detail.endswith(" <b>&")  # escaping is the renderers' job


def test_a_failed_diagnosis_is_reported_not_raised(failed_result, monkeypatch):
    import designkit.report.model as model

    def broken(result):
        raise ValueError("no simulation")

    monkeypatch.setattr(model, "diagnose_run", lambda result: model_diagnose(broken, result))
    built = build_report_model(failed_result, studies=False)
    assert [r.check for r in built.why] == ["overshoot"]
    assert "diagnosis of this run failed (ValueError: no simulation)" in built.why_note
    assert built.divergence == "" and built.linear_vs_nonlinear == ()


def model_diagnose(fn, result):
    try:
        return fn(result)
    except Exception as exc:  # noqa: BLE001 - mirrors designkit.report.why.diagnose_run
        return exc


def test_findings_of_the_diagnosis_fill_cause_and_fix(failed_result, monkeypatch):
    import designkit.report.model as model

    finding = SimpleNamespace(check="overshoot", status="FAIL", requirement="overshoot <= 10 %", achieved="4.2 %",
                              shortfall="", shortfall_percent="", cause="the loop diverges", fix="add anti-windup")
    diagnosis = SimpleNamespace(findings=(finding,), diverged=True, divergence="The loop diverges at t = 1 s.",
                                limit_cycle=SimpleNamespace(sentence="x1 oscillates at 3 rad/s."),
                                linear_vs_nonlinear=(SimpleNamespace(metric="overshoot", unit="%", linear="4.5",
                                                                     nonlinear=""),))
    monkeypatch.setattr(model, "diagnose_run", lambda result: diagnosis)
    built = build_report_model(failed_result, studies=False)
    (row,) = built.why
    assert (row.cause, row.fix) == ("the loop diverges", "add anti-windup")
    assert built.divergence == "The loop diverges at t = 1 s."
    assert built.limit_cycle == "x1 oscillates at 3 rad/s."
    assert [(m.metric, m.linear, m.nonlinear) for m in built.linear_vs_nonlinear] == [("overshoot", "4.5", "undefined")]
    assert [s.anchor for s in built.contents][:3] == ["why", "compliance", "engineering"]


def test_the_lattice_resolution_is_listed_only_where_a_check_ran_the_lattice():
    """The box's intervals are always listed; its 'points per axis' only beside a robustness lattice check."""
    from designkit.report.design_section import plant_rows
    from designkit.schema.loader import parse_spec

    loaded = parse_spec("name: b\nplant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.5, 2.5], grid: 9}}\n"
                        "controller: {kind: pid_servo, poles: [-4, -5, -20]}\n")
    from designkit.pipeline import plant as plant_of

    p = plant_of(loaded)
    with_lattice = [r.name for r in plant_rows(p, loaded.spec, lattice=True)]
    without = [r.name for r in plant_rows(p, loaded.spec, lattice=False)]
    assert with_lattice[-1] == "grid" and "grid" not in without
    assert without.count("Km") == with_lattice.count("Km") == 2  # the nominal value and the interval
