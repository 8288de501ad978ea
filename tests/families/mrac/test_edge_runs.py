"""MRAC runs at the edges of its inputs carried to a verdict: a sampling period far beyond the model's time
constants, a run that ends before its plant change or is a single step long, a reference that does not move."""

from __future__ import annotations

from designkit.pipeline import run
from designkit.schema.loader import load_spec
from tests.cli_verdict import assert_fails, run_cli

HEAD = """\
name: edge
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: mrac, poles: [-4, -5], gamma: 10000, Q: [1, 0.1]}
"""


def test_sampling_period_beyond_the_model_is_a_stability_fail(tmp_path, capsys):
    """A command held 100 s against a model with poles -4, -5 1/s: the adaptive run leaves its bound, a FAIL
    with the instant, and the report is written (the Floquet estimate is skipped on a grid that cannot resolve
    the model)."""
    text = HEAD + ("simulation: {duration: 4, sampling_period: 100, "
                   "trajectory: {kind: square, amplitude: 0.5, period: 2}}\nstudies: {budget: 1}\n")
    assert_fails(tmp_path, capsys, text, "adaptive_stability", "the gradient rule lost stability", synth=True)
    assert (tmp_path / "out" / "edge" / "report.html").is_file()


def test_run_shorter_than_its_plant_change_ignores_the_change(tmp_path, capsys):
    """The link changes at t = 20 s, after a 4 s run: the run is on the nominal link throughout, so the
    parameters that match the model at the end are the nominal ones (a1, a2 = 20, 9 for poles -4, -5 on
    Km = 2, tau = 0.5: s^2 + 9 s + 20), not those of the changed link."""
    text = HEAD + ("simulation: {duration: 4, trajectory: {kind: square, amplitude: 0.5, period: 2}, "
                   "plant_change: {time: 20, values: {Km: 1.0}}}\n")
    spec = tmp_path / "spec.yaml"
    spec.write_text(text)
    result = run(load_spec(spec))
    conv = next(c for c in result.checks if c.name == "parameter_convergence")
    assert conv.certificate["final_link"] == {"Km": 2.0, "tau": 0.5}
    assert [round(v, 9) for v in conv.certificate["matching"]] == [20.0, 9.0]
    adaptation = next(c for c in result.checks if c.name == "adaptation_error")
    assert "the link changes" not in adaptation.detail


def test_single_step_run_is_judged(tmp_path, capsys):
    """duration 1e-6 s: no error to speak of, RMS 0 for both runs; judged, not divided by zero."""
    text = HEAD + ("simulation: {duration: 1.0e-6, trajectory: {kind: square, amplitude: 0.5, period: 4}, "
                   "plant_change: {time: 20, values: {Km: 1.0}}}\n")
    code, out, _ = run_cli(tmp_path, capsys, text)
    assert code in (0, 1)
    assert "adaptation_error" in out


def test_reference_that_does_not_move_is_judged(tmp_path, capsys):
    """A square wave of amplitude 0 with the link changing: nothing moves, both errors are 0 and the
    adaptation (which has nothing to act on) is reported with both RMS values."""
    text = HEAD + ("simulation: {duration: 4, trajectory: {kind: square, amplitude: 0, period: 2}, "
                   "plant_change: {time: 1, values: {Km: 1.0}}}\n")
    code, out, _ = run_cli(tmp_path, capsys, text)
    assert code in (0, 1)
    row = next(ln for ln in out.splitlines() if ln.startswith("adaptation_error"))
    assert "0 rad" in row
