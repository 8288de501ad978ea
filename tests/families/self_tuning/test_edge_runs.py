"""Self-tuning runs at the edges of their inputs carried to a verdict: a loop that diverges (an actuator that
saturates at 1e-6 N*m behind a 10 ms delay, so the estimator sees no input and the redesigned controller grows
without bound), and a relay without hysteresis in front of the link through a plant change."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.cli_verdict import failed_line, run_cli

SPEC = Path(__file__).resolve().parents[3] / "specs" / "selftune-speed.yaml"


def _spec(duration: float, element: str, extra: str = "", change: bool = True) -> str:
    text = SPEC.read_text().replace("  duration: 30\n", f"  duration: {duration}\n  nonlinearity: {element}\n{extra}")
    if not change:
        text = re.sub(r"  plant_change: .*\n", "", text)
    assert f"duration: {duration}" in text
    return text + "studies: {budget: 1}\n"


def test_diverging_run_is_a_fail_naming_the_instant(tmp_path, capsys):
    """The run stops being finite: ``finite_run`` fails with the instant, the other checks and the report's
    study cope with records that are not finite (exit 1, the report written)."""
    text = _spec(10, "{kind: saturation, limit: 1.0e-6}", "  delay: 0.01\n", change=False)
    code, out, _ = run_cli(tmp_path, capsys, text, synth=True)
    assert code == 1, out
    line = failed_line(out, "finite_run")
    at = float(re.search(r"diverged at t = ([0-9.e+-]+) s", line).group(1))
    assert 0 < at < 10
    assert "finite_run" in next(ln for ln in out.splitlines() if ln.startswith("NOT VERIFIED: "))
    assert (tmp_path / "out" / "selftune-speed" / "report.html").is_file()


@pytest.mark.slow
def test_relay_without_hysteresis_through_a_plant_change(tmp_path, capsys):
    """A relay of zero hysteresis: the estimates blow up; judged and reported (the study's re-runs included)."""
    text = _spec(16, "{kind: relay, amplitude: 1.0, hysteresis: 0}")
    code, out, _ = run_cli(tmp_path, capsys, text, synth=True)
    assert code == 1, out
    assert (tmp_path / "out" / "selftune-speed" / "report.html").is_file()
