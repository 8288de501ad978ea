"""Warnings a reviewer must see (weak margins, chattering, non-physical inertias) on page 1 and in --json."""

from __future__ import annotations

import json

import designkit as dk
from designkit.cli import main


def test_weak_margins_reach_the_json_and_the_first_page(tmp_path, capsys):
    code = main(["synth", "specs/scara-decentralized-pid.yaml", "--out", str(tmp_path), "--json", "--no-studies"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1  # the overshoot fails; the warnings are not part of the verdict
    assert any("u4: phase margin 19.2°, below 30°" in w for w in out["warnings"])
    html = (tmp_path / "scara-decentralized-pid" / "report.html").read_text()
    first = html.index('id="warnings"')
    assert first < html.index('id="compliance"')  # before the evidence
    assert "u4: phase margin 19.2°, below 30°" in html[first:first + 4000]


def test_a_calm_loop_has_no_warnings():
    result = dk.run(dk.load_spec("specs/posspeed-link.yaml"), simulate=False)
    assert result.warnings == () and result.to_json()["warnings"] == []


def test_non_physical_inertia_of_the_plant_is_a_warning():
    text = ("name: p\nplant: {kind: robot, robot: puma560}\ncontroller: {kind: computed_torque, poles: [-20, -20]}\n"
            "simulation: {initial_position: [0, 0.78, -2.35, 0, 0.78, 0]}\n")
    result = dk.run(dk.parse_spec(text), simulate=False)
    assert any("not physically consistent" in w and "link 3 (joint3)" in w for w in result.warnings)
    fixed = dk.run(dk.parse_spec(text.replace("robot: puma560}", "robot: puma560, consistent_inertia: raise}")),
                   simulate=False)
    assert not any("not physically consistent" in w for w in fixed.warnings)


def test_a_command_switching_at_the_step_is_a_first_page_warning(tmp_path, capsys):
    code = main(["synth", "specs/pid-sm-link.yaml", "--out", str(tmp_path), "--json", "--no-studies"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["verified"] is True  # a warning, not part of the verdict
    (text,) = [w for w in out["warnings"] if "numerical choice" in w]
    assert "The commanded u switches" in text and "dominates" in text
    html = (tmp_path / "pid-sm-link" / "report.html").read_text()
    first = html.index('id="warnings"')
    assert first < html.index('id="compliance"')
    assert "depends on a numerical choice" in html[first:first + 6000]
