"""The control delay line: ``u_applied(t) = u_command(t - delay)``, for a delay of one integration step (the line
keeps no older sample) as for longer ones, and a delay shorter than the default step (the step shrinks to it)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from designkit.pipeline import run
from designkit.schema.loader import load_spec
from tests.cli_verdict import run_cli

SPECS = Path(__file__).resolve().parents[2] / "specs"


@pytest.mark.parametrize("delay, dt", [(1e-3, 1e-3), (2e-3, 1e-3), (3e-3, 1e-3), (1e-6, None)])
def test_applied_input_is_the_command_delayed(delay, dt, tmp_path):
    step = f", dt: {dt}" if dt is not None else ""
    spec = tmp_path / "spec.yaml"
    spec.write_text("name: delay\nplant: {kind: link, Km: 2.0, tau: 0.5}\ncontroller: {kind: pid_servo}\n"
                    "requirements: {overshoot: 5, settling_time: 0.3}\n"
                    f"simulation: {{duration: 0.05, delay: {delay}{step}}}\n")
    sim = run(load_spec(spec)).simulation
    n = delay / sim.settings["dt"]
    assert n == pytest.approx(round(n), rel=1e-9) and round(n) >= 1
    n = round(n)
    uc, ua = np.asarray(sim.u_command)[:, 0], np.asarray(sim.u_applied)[:, 0]
    assert np.all(ua[:n] == 0.0)  # nothing has come out of the line yet
    np.testing.assert_array_equal(ua[n:], uc[:-n])
    assert np.ptp(uc) > 0  # the comparison compares something


def test_delay_shorter_than_the_step_is_judged(tmp_path, capsys):
    """``specs/infeasible-requirements.yaml`` with a 1e-6 s delay (a one-step line on the step it sets), shortened
    to 0.02 s: judged (its requirements cannot be met: exit 1)."""
    text = (SPECS / "infeasible-requirements.yaml").read_text()
    text = text.replace("  duration: 2.0\n", "  duration: 0.02\n  delay: 1.0e-6\n")
    assert "delay: 1.0e-6" in text
    code, out, _ = run_cli(tmp_path, capsys, text)
    assert code == 1, out
