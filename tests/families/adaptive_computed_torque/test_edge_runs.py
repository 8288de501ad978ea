"""Adaptive computed torque carried to a verdict and a report when the run diverges (a 1e6 N*m perturbation)."""

from __future__ import annotations

import re
from pathlib import Path

from tests.cli_verdict import failed_line, run_cli

SPEC = Path(__file__).resolve().parents[3] / "specs" / "adaptive-ct-simnog.yaml"


def test_diverging_run_is_a_fail_and_its_report_is_written(tmp_path, capsys):
    """From t = 0.5 s the arm is thrown off: ``finite_run`` names the instant, the tracking and Lyapunov checks
    say when their signals stopped being finite, and the report's answers say so instead of reading numbers that
    the failed checks do not have."""
    text = SPEC.read_text().replace("  duration: 20.0\n",
                                    "  duration: 2.0\n  perturbation: {value: 1.0e6, time: 0.5}\n")
    assert "perturbation" in text
    code, out, _ = run_cli(tmp_path, capsys, text + "studies: {budget: 1}\n", synth=True)
    assert code == 1, out
    at = float(re.search(r"diverged at t = ([0-9.e+-]+) s", failed_line(out, "finite_run")).group(1))
    assert 0.5 <= at < 2
    assert "stopped being finite at t = " in failed_line(out, "tracking_convergence")
    html = (tmp_path / "out" / "adaptive-ct-simnog" / "report.html").read_text()
    assert "the run diverged" in html
