"""The MRAC's adaptation-gain boundary (designkit.studies.boundary) on the MRAC simulator's scenario.

- the recommended γ and both ends of its neighbourhood pass ``designkit verify`` (the CLI, exit 0): the
  recommendation rests on runs a user can repeat;
- two specs of one scenario that differ only in γ (mrac-link and mrac-gamma-unstable) search the same grid and find
  the same boundary, although one passes and the other diverges.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from designkit.cli import main
from designkit.families import family
from designkit.pipeline import run
from designkit.schema.loader import load_spec
from designkit.studies import STUDIES
from designkit.studies.core.study import StudyContext

SPECS = Path(__file__).resolve().parents[2] / "specs"


def _boundary(name: str):
    loaded = load_spec(SPECS / f"{name}.yaml")
    result = run(loaded)
    study = STUDIES["boundary"].run(StudyContext(result, family(result.design.kind), None, 120.0))
    (entry,) = study.entries
    return loaded, entry


@pytest.fixture(scope="module")
def searches():
    return {name: _boundary(name) for name in ("mrac-link", "mrac-gamma-unstable")}


def test_the_recommended_gamma_and_its_neighbourhood_pass_designkit_verify(searches, tmp_path):
    loaded, entry = searches["mrac-link"]
    rec = entry.recommended
    assert rec is not None and rec.low < rec.value < rec.high
    data = yaml.safe_load(loaded.text)
    for gamma in (rec.low, rec.value, rec.high):
        data["controller"]["gamma"] = float(gamma)
        path = tmp_path / f"gamma-{gamma:.6g}.yaml"
        path.write_text(yaml.safe_dump(data))
        assert main(["verify", str(path)]) == 0, gamma


def test_two_specs_of_one_scenario_give_one_boundary(searches):
    (_, a), (_, b) = searches["mrac-link"], searches["mrac-gamma-unstable"]
    grid_a = {round(r.value, 9): r.outcome for r in a.rows}
    grid_b = {round(r.value, 9): r.outcome for r in b.rows}
    common = set(grid_a) & set(grid_b)
    assert len(common) >= 10
    assert all(grid_a[v] == grid_b[v] for v in common)  # the same runs give the same outcomes

    def changes(entry):
        rows = sorted(entry.rows, key=lambda r: r.value)
        return [(round(x.value, 9), round(y.value, 9)) for x, y in zip(rows, rows[1:], strict=False)
                if x.passed != y.passed]

    assert changes(a) == changes(b) and changes(a)
    assert a.recommended == b.recommended
