"""The examples through ``designkit synth --json`` and the bad-input contract (exit 2, the key path)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from designkit.cli import main
from tests.cli_input import assert_bad_input

ROOT = Path(__file__).resolve().parents[3]
LINK = (ROOT / "specs" / "pid-sm-link.yaml").read_text()


def _synth(path: Path, tmp_path: Path, capsys) -> tuple[int, dict]:
    code = main(["synth", str(path), "--json", "--no-studies", "--out", str(tmp_path / "out")])
    return code, json.loads(capsys.readouterr().out)


def test_link_example_gives_the_pid_gains_and_M_with_the_bound_it_covers(tmp_path, capsys):
    code, data = _synth(ROOT / "specs" / "pid-sm-link.yaml", tmp_path, capsys)
    assert code == 0 and data["verified"] is True
    psm = data["pid_sliding_mode"]
    # poles -4, -5, -20 on Km = 2, tau = 0.5 (pid_servo's own example gives the same K1..K3); zero on -20
    assert psm["gains"] == pytest.approx({"K1": 50.0, "K2": 6.75, "K3": 100.0, "K4": -0.45})
    assert psm["a1"] == pytest.approx(0.45) and psm["a2"] == pytest.approx(0.05) and psm["zero"] == -20.0
    # section 5.4 at the corner Km = 1.4, tau = 0.65, at the step (x2 = 0, u0 = K1 + K3 K4 = 5 N*m):
    # xi = (1 - Km0 tau/(tau0 Km)) u0 = (1 - 2*0.65/(0.5*1.4)) 5
    xi_p = abs(1 - 2 * 0.65 / (0.5 * 1.4)) * 5.0
    assert psm["bound"]["parameter_change"] == pytest.approx(xi_p, rel=1e-9)
    assert psm["bound"]["total"] == pytest.approx(xi_p + 0.5)
    assert psm["M"] == [pytest.approx(1.2 * (xi_p + 0.5))]
    statuses = {c["name"]: c["status"] for c in data["checks"]}
    assert all(statuses[n] == "PASS" for n in ("pid_sm_dynamics", "pid_sm_relay", "pid_sm_band", "pid_sm_in_band"))


def test_weak_relay_fails_and_says_by_how_much_and_what_M_would_do(tmp_path, capsys):
    code, data = _synth(ROOT / "specs" / "pid-sm-link-weak-relay.yaml", tmp_path, capsys)
    assert code == 1 and data["verified"] is False
    checks = {c["name"]: c for c in data["checks"]}
    detail = checks["pid_sm_relay"]["detail"]
    assert checks["pid_sm_relay"]["status"] == "FAIL"
    assert "M = 3 N*m is below sup|ξ| = 5.774 N*m" in detail and "by 2.77 N*m" in detail
    assert "M = 6.929 N*m keeps the 20 % margin" in detail
    assert checks["pid_sm_in_band"]["status"] == "FAIL"


@pytest.mark.parametrize(("old", "new", "message"), [
    ("  margin: 0.2\n", "  margin: 0.2\n  epsilon: 0\n", "controller.epsilon"),
    ("  margin: 0.2\n", "  margin: 0.2\n  epsilon: -0.01\n", "controller.epsilon"),
    ("  margin: 0.2\n", "  margin: 0.2\n  M: 0\n", "controller.M"),
    ("  margin: 0.2\n", "  margin: 0.2\n  M: -1\n", "controller.M"),
    ("poles: [-4, -5, -20]", "poles: [-4, -5, 0]", "controller.poles"),
    ("poles: [-4, -5, -20]", "poles: [1+2j, 1-2j, -20]", "controller.poles"),
    ("poles: [-4, -5, -20]", "poles: [-4, 3, -20]", "controller.poles[1]: must have negative real part"),
])
def test_bad_input_exits_2_with_the_key_path(tmp_path, capsys, old, new, message):
    assert old in LINK
    assert_bad_input(tmp_path, capsys, LINK.replace(old, new), message)
