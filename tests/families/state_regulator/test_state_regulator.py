"""The state_regulator family: K against python-control, N and the load offset against a simulation of the
closed loop (scipy), the loop margins against python-control, bad input (exit 2 with the key path)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from designkit.cli import main
from designkit.families.state_regulator.gains import reference_gain
from designkit.models.elastic import elastic_state_space
from designkit.models.robots.elastic_link import DEFAULTS, elastic_link
from designkit.synthesis.pole_placement import ackermann
from tests.cli_input import assert_bad_input

SPEC = Path(__file__).resolve().parents[3] / "specs" / "state-regulator-elastic-joint.yaml"
POLES = [-8, -10, -12, -15]


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    out = tmp_path_factory.mktemp("sr")
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["synth", str(SPEC), "--json", "--no-studies", "--out", str(out)])
    return code, json.loads(buf.getvalue())


def test_K_equals_python_control_acker_and_place():
    control = pytest.importorskip("control")
    A, B = elastic_state_space(DEFAULTS)
    K = ackermann(A, B, POLES)
    assert pytest.approx(np.asarray(control.acker(A, B, POLES)).ravel(), rel=1e-9) == K
    assert pytest.approx(np.asarray(control.place(A, B, POLES)).ravel(), rel=1e-7) == K
    assert np.sort(np.linalg.eigvals(A - B @ K[None, :]).real) == pytest.approx(sorted(POLES), rel=1e-9)


@pytest.mark.parametrize("poles", [[-5, -5, -5, -5], [-6 + 3j, -6 - 3j, -20, -20], [-3, -40 + 1j, -40 - 1j, -9]])
def test_repeated_and_complex_poles_at_other_plants(poles):
    control = pytest.importorskip("control")
    params = elastic_link(J2=0.3, KR=80.0, tau2=0.7)
    A, B = elastic_state_space(params)
    K = ackermann(A, B, poles)
    assert pytest.approx(np.asarray(control.acker(A, B, poles)).ravel(), rel=1e-8) == K
    # characteristic polynomial (well conditioned for repeated roots) against numpy's
    assert np.poly(A - B @ K[None, :]) == pytest.approx(np.poly(np.asarray(poles, complex)).real, rel=1e-7)


def test_reference_gain_gives_unit_static_gain_in_a_simulation():
    from scipy.signal import lsim

    A, B = elastic_state_space(DEFAULTS)
    K = ackermann(A, B, POLES)
    N = reference_gain(A, B, K, 2)
    assert pytest.approx(K[0] + K[2], rel=1e-9) == N  # the rest state [xD, 0, xD, 0] has A x* = 0
    t = np.linspace(0, 5, 2001)
    _, y, _ = lsim((A - B @ K[None, :], B * N, np.eye(4)[[2]], [[0.0]]), np.ones_like(t), t)
    assert y[-1] == pytest.approx(1.0, abs=1e-6)


def test_json_contract_and_checks(data):
    code, d = data
    assert code == 0 and d["verified"] is True
    A, B = elastic_state_space(DEFAULTS)
    K = np.asarray(d["state_regulator"]["K"])
    assert pytest.approx(ackermann(A, B, POLES), rel=1e-9) == K
    assert [d["gains"][f"K{i}"] for i in range(1, 5)] == pytest.approx(K.tolist())
    # load offset per N*m: the closed loop's static gain from w (enters x4' with R2/J2)
    D = np.array([0, 0, 0, DEFAULTS.R2 / DEFAULTS.J2])
    expected = -np.linalg.solve(A - B @ K[None, :], D)[2]
    assert d["state_regulator"]["load_offset_per_unit"] == pytest.approx(expected, rel=1e-9)
    names = {c["name"]: c["status"] for c in d["checks"]}
    for n in ("pole_placement", "lyapunov", "loop_margins", "designed_loop", "robust_vertices", "overshoot",
              "settling_time", "steady_state_error"):
        assert names[n] == "PASS", n


def test_loop_margins_against_python_control(data):
    control = pytest.importorskip("control")
    _, d = data
    A, B = elastic_state_space(DEFAULTS)
    K = np.asarray(d["state_regulator"]["K"])
    L = control.ss(A, B, K[None, :], [[0.0]])
    gm, pm, *_ = control.stability_margins(L)
    check = next(c for c in d["checks"] if c["name"] == "loop_margins")
    text = check["detail"]
    assert f"PM {pm:.1f}°" in text or f"PM {pm:.3g}°" in text, (pm, text)
    assert f"GM {gm:.3g}" in text, (gm, text)


def test_simulated_load_offset(data):
    _, d = data
    # the run's final error equals the predicted offset of the 0.2 N*m load (no integral action)
    sse = next(c for c in d["checks"] if c["name"] == "steady_state_error")
    predicted = 0.2 * d["state_regulator"]["load_offset_per_unit"]
    assert sse["achieved"] == pytest.approx(abs(predicted), rel=0.02)


BASE = SPEC.read_text()


@pytest.mark.parametrize(("old", "new", "message"), [
    ("poles: [-8, -10, -12, -15]", "poles: [-8, -10, 0.5, -15]", "controller.poles[2]"),
    ("poles: [-8, -10, -12, -15]", "poles: [-8, -10, -12]", "controller.poles: the elastic_joint plant has 4"),
    ("kind: elastic_joint\n", "kind: elastic_joint\n  KR: 1.0e-6\n", "plant.KR: makes the plant uncontrollable"),
    ("kind: elastic_joint\n", "kind: elastic_joint\n  mgl: 2.0\n", "plant.mgl"),
])
def test_bad_input_exits_2_with_the_key_path(old, new, message, tmp_path, capsys):
    assert old in BASE
    assert_bad_input(tmp_path, capsys, BASE.replace(old, new, 1), message)
