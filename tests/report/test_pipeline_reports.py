"""Reports of real pipeline runs (synthesis, simulation and verification of the shipped specs)."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.pipeline import run
from designkit.report import build_report_model, write_report
from designkit.spec import load_spec

SPECS = Path(__file__).resolve().parents[2] / "specs"


@pytest.mark.parametrize("name", ["posspeed-perturbation", "tracking-pid", "posspeed-relay"])
def test_report_of_a_real_run(name, tmp_path):
    path = SPECS / f"{name}.yaml"
    if not path.exists():
        pytest.skip(f"{path.name} not shipped")
    result = run(load_spec(path))
    model = build_report_model(result)
    assert model.verified == result.verified
    if result.verified:
        assert model.verdict == "VERIFIED"
    else:
        assert model.verdict.startswith(("FAILED: ", "UNDECIDED: "))
    assert [c.name for c in model.checks] == [c.name for c in result.checks]
    assert {f.filename for f in model.figures} >= {"fig-pole-zero.svg", "fig-linear-response.svg",
                                                   "fig-loop-bode.svg", "fig-simulation.svg"}
    files = write_report(result, tmp_path)
    html = files.html.read_text(encoding="utf-8")
    assert "http" not in html and "src=" not in html
    for check in result.checks:
        assert check.name.replace("_", "_<wbr>") in html
        assert f'<span class="badge {check.status}">{check.status}</span>' in html
    assert files.pdf.read_bytes().startswith(b"%PDF")
