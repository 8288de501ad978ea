"""Link identification carried to a verdict when its estimates blow up (measurement noise of 100 rad and rad/s)."""

from __future__ import annotations

from pathlib import Path

from tests.cli_verdict import failed_line, run_cli

SPEC = Path(__file__).resolve().parents[3] / "specs" / "smid-link.yaml"


def test_estimates_that_blow_up_fail_the_lyapunov_check(tmp_path, capsys):
    """Noise of standard deviation 100 on every measured state: the estimates leave every bound, V = (a - â)²/γa
    + (b - b̂)²/γb overflows, and the Lyapunov check fails on a V that is not finite, without a warning."""
    text = SPEC.read_text().replace("  duration: 20\n", "  duration: 6\n  noise: {std: 100, seed: 1}\n")
    assert "noise" in text
    code, out, _ = run_cli(tmp_path, capsys, text)
    assert code == 1, out
    assert "V = (a − â)²/γa + (b − b̂)²/γb from" in failed_line(out, "identification_lyapunov")
