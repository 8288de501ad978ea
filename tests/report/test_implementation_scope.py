"""What the verdict is on, in the report and the JSON: the controller as implemented when the spec gives
``implementation``, else, for a switching law, that the verdict holds for a continuous-time switch."""

from __future__ import annotations

import json
from pathlib import Path

from designkit.pipeline import run
from designkit.report.model import _scope_sentence
from designkit.report.simulation_rows import simulation_rows
from designkit.schema.loader import parse_spec

ROOT = Path(__file__).resolve().parents[2]


def _result(extra: str = ""):
    text = (ROOT / "specs" / "sliding-mode-link.yaml").read_text().replace("duration: 3.0", "duration: 1.5")
    return run(parse_spec(text + extra))


def test_an_implemented_switching_law_is_judged_as_implemented():
    result = _result("implementation: {sampling_period: 0.002, actuator: {limit: 5, bandwidth: 300}}\n")
    scope = json.loads(json.dumps(result.to_json()))["scope"]
    assert scope["implemented"] is True
    assert scope["words"].startswith("as implemented: sampled at 500 Hz (every 2 ms")
    assert "actuator limited to ±5 N*m with a 300 rad/s first-order lag" in scope["words"]
    assert _scope_sentence(result) == "The verdict is on the controller " + scope["words"].replace("N*m", "N·m") + "."
    rows = simulation_rows(result.simulation)
    assert rows[2].name == "The verdict is on the controller" and rows[2].value.startswith("as implemented")
    assert float(result.simulation.settings["sampling_period"]) == 0.002


def test_a_switching_law_without_the_section_says_its_verdict_is_for_a_continuous_time_switch():
    result = _result()
    scope = result.to_json()["scope"]
    assert scope["implemented"] is False
    rate = 1.0 / float(result.simulation.settings["dt"])
    assert "continuous-time switch" in scope["words"] and f"{rate / 1e3:.4g} kHz" in scope["words"]
    assert _scope_sentence(result).startswith("The verdict holds for a continuous-time switch")
    assert simulation_rows(result.simulation)[2].name == "What the verdict holds for"
