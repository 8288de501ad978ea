"""``command_switching``: every law's command measured as physics; the requirements ``max_reversal_rate`` and
``max_command_variation`` checked against counts of our own; the switching examples warned on page 1."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import designkit as dk
from designkit.cli import main
from designkit.verification.checks.command_switching import RULE
from designkit.verification.suite import Context
from tests.verification.helpers import step_result

DT = 1e-4
T = np.arange(0.0, 1.0 + DT / 2, DT)


def _spec(**requirements):
    """Requirements, a continuous-time command and a loop pole at -2 1/s (an averaging window of 0.5 s)."""
    req = SimpleNamespace(**{"max_reversal_rate": None, "max_command_variation": None, **requirements})
    return SimpleNamespace(requirements=req, simulation=SimpleNamespace(sampling_period=0.0),
                           controller=SimpleNamespace(poles=[-2.0]))


def _square_run(f: float, amplitude: float):
    square = amplitude * np.sign(np.sin(2 * np.pi * f * T + 0.1))
    u = 1.0 + square
    return step_result(T, 1 - np.exp(-5 * T), u.reshape(-1, 1)), square


def _own_reversals(u: np.ndarray) -> int:
    du = np.diff(u)
    s = np.sign(du[du != 0])
    return int(np.count_nonzero(s[1:] != s[:-1]))


def test_requirements_against_own_count():
    sim, square = _square_run(40.0, 2.0)
    rate = _own_reversals(1.0 + square) / 1.0
    tv_rate = float(np.sum(np.abs(np.diff(square)))) / 1.0
    for factor, passed in ((1.1, True), (0.9, False)):
        checks = {c.name: c for c in RULE.run(None, Context(_spec(max_reversal_rate=factor * rate,
                                                                  max_command_variation=factor * tv_rate), sim))}
        assert checks["max_reversal_rate"].achieved == pytest.approx(rate)
        assert checks["max_reversal_rate"].passed is passed and checks["max_reversal_rate"].required
        assert checks["max_command_variation"].achieved == pytest.approx(tv_rate)
        assert checks["max_command_variation"].passed is passed
        info = checks["command_switching"]
        assert info.required is False and info.passed is True


def test_without_requirements_one_informational_check_and_a_warning_when_switching_dominates():
    sim, _ = _square_run(40.0, 2.0)  # the switching part (RMS 2) dominates the averaged 1
    (check,) = RULE.run(None, Context(_spec(), sim))
    assert check.name == "command_switching" and check.required is False
    assert len(check.warnings) == 1 and "dominates" in check.warnings[0]
    assert "integration step" not in check.warnings[0]  # 80 reversals a second is far from 1e4 a step
    calm, _ = _square_run(40.0, 0.2)
    (check,) = RULE.run(None, Context(_spec(), calm))
    assert check.warnings == ()


@pytest.mark.parametrize("name, rate", [("pid-sm-link", 1.2e4), ("sliding-mode-link", 3e3)])
def test_switching_examples_are_warned(name, rate):
    result = dk.run(dk.load_spec(f"specs/{name}.yaml"))
    check = next(c for c in result.checks if c.name == "command_switching")
    measured = check.certificate["inputs"][0]
    u = np.asarray(result.simulation.u_command[:, 0])
    duration = float(result.simulation.time[-1] - result.simulation.time[0])
    own = _own_reversals(u)
    assert measured["reversals"] == pytest.approx(own, rel=0.01)  # hysteresis drops at most a handful
    assert measured["reversal_rate_per_s"] == pytest.approx(own / duration, rel=0.01)
    assert measured["reversal_rate_per_s"] > rate
    assert measured["set_by_step"] is True
    assert any("numerical choice" in w for w in result.to_json()["warnings"])
    assert result.verified is True  # a warning, not part of the verdict


def test_a_boundary_layer_is_calm():
    result = dk.run(dk.load_spec("specs/pid-sm-link-boundary-layer.yaml"))
    check = next(c for c in result.checks if c.name == "command_switching")
    assert check.warnings == ()
    chatter = next(c for c in result.checks if c.name == "pid_sm_chattering")
    assert chatter.passed is True


def test_the_family_chattering_check_judges_physics():
    result = dk.run(dk.load_spec("specs/pid-sm-link.yaml"))
    chatter = next(c for c in result.checks if c.name == "pid_sm_chattering")
    assert chatter.passed is False and chatter.required is False
    (sw,) = chatter.certificate["switching"]
    u = np.asarray(result.simulation.u_command[:, 0])
    relay = next(g.value for g in result.design.gains.entries if g.name == "M")
    # a relay toggling every step: half the median step-to-step change is M, and so is its switching part's RMS
    assert float(np.median(np.abs(np.diff(u[-1000:])))) / 2 == pytest.approx(relay, rel=0.01)
    assert sw["switching_rms"] == pytest.approx(relay, rel=0.02)
    assert sw["switching_rms"] > sw["averaged_rms"]


def test_a_requirement_in_a_spec_is_checked(tmp_path, capsys):
    text = Path("specs/pid-sm-link.yaml").read_text().replace(
        "steady_state_error: 0.005}", "steady_state_error: 0.005, max_reversal_rate: 1000}")
    path = tmp_path / "s.yaml"
    path.write_text(text)
    code = main(["verify", str(path), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1
    check = next(c for c in out["checks"] if c["name"] == "max_reversal_rate")
    assert check["status"] == "FAIL" and check["achieved"] > 1e4


@pytest.mark.parametrize("key, value", [("max_reversal_rate", -1), ("max_command_variation", 0)])
def test_bad_requirement_is_refused_with_its_key(tmp_path, capsys, key, value):
    text = Path("specs/pid-sm-link.yaml").read_text().replace(
        "steady_state_error: 0.005}", f"steady_state_error: 0.005, {key}: {value}}}")
    path = tmp_path / "s.yaml"
    path.write_text(text)
    code = main(["verify", str(path)])
    err = capsys.readouterr().err
    assert code == 2 and f"requirements.{key}" in err


def test_a_sampled_switching_law_is_set_by_its_sampling_not_the_step():
    text = Path("specs/sliding-mode-link.yaml").read_text().replace(
        "duration: 3.0", "duration: 3.0\n  sampling_period: 0.001")
    result = dk.run(dk.parse_spec(text))
    measured = next(c for c in result.checks if c.name == "command_switching").certificate["inputs"][0]
    u = np.asarray(result.simulation.u_command[:, 0])
    own = _own_reversals(u)  # a held command changes at most once a sample
    assert measured["reversals"] == pytest.approx(own, rel=0.02)
    assert measured["reversal_rate_per_s"] <= 1000.0
    assert measured["set_by_sampling"] is True and measured["set_by_step"] is False
    assert any("sampling period (0.001 s)" in w for w in result.warnings)


def test_robel_switching_designs_are_warned_and_the_linear_ones_are_not():
    comparison = dk.run(dk.load_spec("specs/robel.yaml"))
    seen = {}
    for result in comparison.results:
        check = next(c for c in result.checks if c.name == "command_switching")
        measured = check.certificate["inputs"][0]
        switching = bool(getattr(result.design.law, "discontinuous", False))
        seen[switching] = seen.get(switching, 0) + 1
        u = np.asarray(result.simulation.u_command[:, 0])
        duration = float(result.simulation.time[-1] - result.simulation.time[0])
        if switching:
            assert _own_reversals(u) / duration > 1e3  # own count: thousands of reversals a second
            assert measured["dominates"] and measured["set_by_step"] and check.warnings
        else:
            assert not measured["dominates"] and not measured["set_by_step"] and check.warnings == ()
    assert seen == {True: 2, False: 2}
