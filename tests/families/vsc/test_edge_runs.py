"""Variable structure runs at the edges of their inputs carried to a verdict: a plant change after the end of the
run, a run a single step long (its figures drawn from a run that never reaches the band)."""

from __future__ import annotations

from designkit.families.vsc.measure import run_models
from designkit.pipeline import run
from designkit.schema.loader import load_spec
from tests.cli_verdict import failed_line, run_cli
from tests.families.vsc.common import LINK_SPEC


def test_plant_change_after_the_run_is_not_applied(tmp_path, capsys):
    """``plant_change.time`` 10 s after a 3 s run: the run is on one plant throughout, so the linear models the
    measurements use are the nominal one only, and the spec is judged (exit 0, as without the change)."""
    text = LINK_SPEC.read_text() + "  plant_change: {time: 10, values: {Km: 1.5}}\n"
    code, out, _ = run_cli(tmp_path, capsys, text)
    assert code == 0, out
    spec = tmp_path / "spec.yaml"
    result = run(load_spec(spec))
    assert result.simulation.settings["plant_change"]["time_applied"] is None
    pieces = run_models(result.design, result.simulation)
    assert [t for t, _ in pieces] == [0.0]


def test_single_step_run_is_judged_and_drawn(tmp_path, capsys):
    """``duration: 1e-6``: the run never reaches the hold band; the band check fails saying so, and the report's
    figures are drawn from the run that never reached it."""
    text = LINK_SPEC.read_text().replace("duration: 3.0", "duration: 1.0e-6")
    assert text != LINK_SPEC.read_text()
    code, out, _ = run_cli(tmp_path, capsys, text + "studies: {budget: 1}\n", synth=True)
    assert code == 1, out
    assert "never reached the hold band" in failed_line(out, "vsc_band")
    html = (tmp_path / "out" / "vsc-link" / "report.html").read_text()
    assert "the switching function" in html


def test_diverging_run_is_measured_and_fails(tmp_path, capsys):
    """tau up to 1000 s in the design box: the gains designed over it throw the nominal link off; the run diverges,
    ``finite_run`` names the instant, and the regulator's own measurements judge the records without a warning."""
    text = LINK_SPEC.read_text().replace("tau: [0.35, 0.65]", "tau: [0.35, 1000]")
    assert "1000]" in text
    code, out, _ = run_cli(tmp_path, capsys, text)
    assert code == 1, out
    assert "the run diverged at t = " in failed_line(out, "finite_run")
    assert "vsc_band" in out
