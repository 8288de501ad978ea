"""The output contract checked from outside: ``designkit synth spec.yaml --json`` reports K1, K2, psi (one per
joint) and a check whose name contains ``spr``; K1, K2, psi may be given directly in place of poles."""

from __future__ import annotations

import json

import pytest

from designkit.cli import main

SPEC = """\
name: contract
plant: {kind: robot, robot: planar2r}
controller: {kind: adaptive_computed_torque, CTRL, adapt: [m1, m2], initial: {m1: 7.0, m2: 4.5}, gain: 5.0,
             bounds: {m1: [4.0, 10.0], m2: [2.5, 6.0]}, delta: 0.05}
simulation: {duration: 3.0, trajectory: {kind: sine, amplitude: [1.0, 1.2], frequency: 0.5}}
"""


def _synth(tmp_path, capsys, ctrl: str) -> tuple[int, dict]:
    path = tmp_path / "spec.yaml"
    path.write_text(SPEC.replace("CTRL", ctrl))
    code = main(["synth", str(path), "--json", "--no-studies", "--out", str(tmp_path / "out")])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(("ctrl", "K1", "K2", "psi"), [
    ("poles: [[-10, -10], [-8, -12]]", [100.0, 96.0], [20.0, 20.0], [0.1, 0.1]),  # psi = 2/K2 when not given
    ("K1: [64, 144], K2: [16, 24], psi: [0.2, 0.05]", [64.0, 144.0], [16.0, 24.0], [0.2, 0.05]),
])
def test_json_reports_gains_per_joint_and_an_spr_check(tmp_path, capsys, ctrl, K1, K2, psi):
    code, out = _synth(tmp_path, capsys, ctrl)
    assert out["gains"]["K1"] == pytest.approx(K1)
    assert out["gains"]["K2"] == pytest.approx(K2)
    assert out["gains"]["psi"] == pytest.approx(psi)
    spr = [c for c in out["checks"] if "spr" in c["name"]]
    assert len(spr) == 1 and spr[0]["status"] == "PASS"
    # the margin is psi K2 - 1 at the worst joint, computed here from the gains
    assert spr[0]["achieved"] == pytest.approx(min(p * k - 1 for p, k in zip(psi, K2, strict=True)))
    assert out["adaptation"]["parameters"] == ["m1", "m2"]
    assert code in (0, 1)


def test_json_spr_fails_below_one_over_k2(tmp_path, capsys):
    code, out = _synth(tmp_path, capsys, "K1: [100, 100], K2: [20, 20], psi: [0.1, 0.04]")
    spr = next(c for c in out["checks"] if "spr" in c["name"])
    assert spr["status"] == "FAIL" and spr["achieved"] == pytest.approx(0.04 * 20 - 1)
    assert code == 1
