"""The spec's ``studies`` section: what a study cannot honour is refused before anything runs (exit 2, one line
naming the key path, nothing written)."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.cli import main

SPECS = Path(__file__).resolve().parents[2] / "specs"


@pytest.mark.parametrize(("spec", "studies", "path"), [
    ("posspeed-link", "{gains: {knobs: [K9]}}", "studies.gains.knobs[0]"),
    ("posspeed-link", "{gains: {factors: [1]}}", "studies.gains.factors"),
    ("mrac-link", "{gains: {factors: [1.0e-9]}}", "studies.gains.factors[0]"),
    ("mrac-link", "{boundary: {knob: gamma, low: 1.0e-20}}", "studies.boundary.low"),
    ("mrac-link", "{boundary: {knob: poles}}", "studies.boundary.knob"),
    ("posspeed-link", "{boundary: {}}", "studies.boundary.knob"),
    ("posspeed-link", "{budget: 0.01}", "studies.budget"),
    ("posspeed-link", "{budget: -1}", "studies.budget"),
    ("posspeed-link", "{sweeping: {}}", "studies.sweeping"),
    ("posspeed-link", "{gains: 3}", "studies.gains"),
])
def test_refused_with_the_key_path(spec, studies, path, tmp_path, capsys):
    text = (SPECS / f"{spec}.yaml").read_text() + f"studies: {studies}\n"
    file = tmp_path / "spec.yaml"
    file.write_text(text)
    out = tmp_path / "out"
    assert main(["synth", str(file), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"designkit: error: {path}"), err
    assert not out.exists()


def test_a_valid_section_runs_the_study_as_asked(tmp_path, capsys):
    import json

    text = (SPECS / "posspeed-link.yaml").read_text() + "studies: {budget: 30, gains: {knobs: [K3], factors: [0.5]}}\n"
    file = tmp_path / "spec.yaml"
    file.write_text(text)
    assert main(["synth", str(file), "--out", str(tmp_path / "out"), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    gains = [s for s in payload["studies"] if s["name"] == "gains"]
    assert [s["parameter"] for s in gains] == ["K3"]
    assert [r["factor"] for r in gains[0]["rows"]] == [0.5, 1.0]
    assert all(set(r) == {"factor", "value", "metrics", "outcome", "detail"} for r in gains[0]["rows"])
    json.dumps(payload["studies"], allow_nan=False)  # JSON's own numbers: an infinite metric is null
