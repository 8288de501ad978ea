"""Comparison studies are discovered like the others: one planted in the package runs on a comparison, its section is
laid out after the generic one and ``synth --json`` carries its rows, with no generic module edited; the lab
experiments' titles carry their experiment numbers."""

from __future__ import annotations

import json
import re
import sys
from types import MappingProxyType

import pytest

import designkit.studies as studies
from designkit.cli import main
from designkit.comparison.answers import comparison_sections
from designkit.pipeline import run
from designkit.report.comparison_model import build_comparison_model
from designkit.schema.loader import parse_spec
from tests.comparison.test_comparison import STEP

PLANTED = '''
from designkit.display.section import Question, ReportSection
from designkit.studies.core.members import members
from designkit.studies.core.study import Entry, Row, Study, StudyResult


def _run(ctx):
    found = members(ctx.result)
    rows = tuple(Row(1.0, 1.0, {"peak_command": m.values["peak_command"]}, "verified" if m.run.verified else "failed")
                 for m in found)
    section = ReportSection("planted-comparison", "A planted comparison study",
                            questions=(Question("Who is there?", tuple(m.label for m in found)),))
    return StudyResult("planted", "A planted comparison study", (Entry("members", "", rows),), section)


STUDY = Study(name="planted", title="A planted comparison study", order=99, applies=lambda result, family: True,
              run=_run, comparison=True)
'''


@pytest.fixture
def planted(tmp_path, monkeypatch):
    (tmp_path / "planted.py").write_text(PLANTED)
    monkeypatch.setattr(studies, "__path__", [*studies.__path__, str(tmp_path)])
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        found = studies._discover()
    finally:
        sys.modules.pop("designkit.studies.planted", None)
    monkeypatch.setattr(studies, "STUDIES", MappingProxyType({"planted": found["planted"]}))
    return found


def test_a_planted_comparison_study_is_run_laid_out_and_carried_in_json(planted, capsys):
    assert {"lab2", "lab3", "planted"} <= set(planted) and planted["planted"].comparison
    result = run(parse_spec(STEP))
    assert [st.name for st in result.studies] == ["planted"]
    assert [s.anchor for s in comparison_sections(result)] == ["comparison-answers", "planted-comparison"]
    assert [s.anchor for s in comparison_sections(result, studies=False)] == ["comparison-answers"]
    assert "planted-comparison" in [s.anchor for s in build_comparison_model(result, provenance=()).sections]
    payload = result.to_json(studies=True)
    assert [s["name"] for s in payload["studies"]] == ["planted"]
    assert len(payload["studies"][0]["rows"]) == 2 and "studies" in payload["comparison"][0]["result"]
    assert "studies" not in result.to_json()


def test_synth_json_carries_the_comparison_studies(planted, tmp_path, capsys):
    spec = tmp_path / "step.yaml"
    spec.write_text(STEP)
    assert main(["synth", str(spec), "--no-report", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert [s["name"] for s in payload["studies"]] == ["planted"]
    assert main(["synth", str(spec), "--no-report", "--json", "--no-studies"]) == 0
    assert "studies" not in json.loads(capsys.readouterr().out)


def test_the_lab_sections_carry_their_experiment_numbers():
    labs = {name: st for name, st in studies.STUDIES.items() if name.startswith("lab")}
    assert sorted(labs) == ["lab1", "lab2", "lab3"]
    for name, st in labs.items():
        number = re.fullmatch(r"lab(\d+)", name).group(1)
        assert st.title.startswith(f"Lab experiment {number} (notes, appendix A): "), st.title
    assert not labs["lab1"].comparison and labs["lab2"].comparison and labs["lab3"].comparison
