"""Every family declares knobs, and its gain study runs on its conformance case through the family's own run:
never skipped, every row judged by the family's checks, the unit row the case's own run."""

from __future__ import annotations

import pytest

from designkit.families import FAMILIES
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from designkit.studies import STUDIES
from designkit.studies.core.study import OUTCOMES, StudyContext
from tests.marks import slow_cases
from tests.problems import CASES, case_yaml

FIRST = sorted((kind, next(iter(plants))) for kind, plants in CASES.items())
"""One case per family: its first canonical plant."""


def test_every_family_declares_a_knob():
    for kind, fam in FAMILIES.items():
        assert fam.knobs, f"{kind} declares no knob a study may vary"
        for knob in fam.knobs:
            assert knob.meaning and knob.low < knob.high


@pytest.mark.parametrize(("kind", "plant"), slow_cases(FIRST, {"adaptive_computed_torque-two_link"},
                                                       lambda c: "-".join(c)))
def test_the_gain_study_runs_for_every_family(kind, plant):
    result = run(parse_spec(case_yaml(kind, plant)))
    fam = FAMILIES[kind]
    study = STUDIES["gains"].run(StudyContext(result, fam, None, 4.0))
    assert study is not None and study.runs >= 1, f"{kind}: no variant run"
    assert study.entries and study.section is not None
    for entry in study.entries:
        unit_rows = [r for r in entry.rows if r.factor == 1.0]
        assert len(unit_rows) == 1
        assert unit_rows[0].passed == result.verified  # the unit row is the case's own run
        for r in entry.rows:
            assert r.outcome in OUTCOMES
            assert r.outcome in ("verified", "refused") or r.detail  # a row that does not pass says why
    if study.reduced:
        assert "studies.budget" in study.reduced  # a reduced study says what it reduced and why
