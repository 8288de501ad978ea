"""Arm identification carried to a verdict when the run diverges: a 1e6 N*m perturbation on the SIMNOG arm."""

from __future__ import annotations

import re
from pathlib import Path

from tests.cli_verdict import failed_line, run_cli

SPEC = Path(__file__).resolve().parents[3] / "specs" / "smid-simnog.yaml"


def test_diverging_arm_run_is_a_fail_naming_the_instant(tmp_path, capsys):
    """The perturbation from t = 0.5 s throws the arm off: ``finite_run`` fails from that instant on, and the
    identification checks (excitation, convergence) judge records that are not finite without an exception."""
    text = SPEC.read_text()
    text = re.sub(r"  plant_change: .*\n", "", text.replace("  duration: 70\n", "  duration: 2\n"))
    text += "  perturbation: {value: 1.0e6, time: 0.5}\n"
    assert "duration: 2\n" in text and "plant_change" not in text
    code, out, _ = run_cli(tmp_path, capsys, text)
    assert code == 1, out
    at = float(re.search(r"diverged at t = ([0-9.e+-]+) s", failed_line(out, "finite_run")).group(1))
    assert 0.5 <= at < 2
    assert "identification_convergence" in out
