"""The state regulator on the linear plant kinds, with and without an observer.

Independent routes: the third-order drive of ``specs/state-space-third-order.yaml`` written here with numbers at its
nominal parameters (``wn = 40``, ``zeta = 0.05``, ``K = 1``) -- ``K`` against python-control's ``acker``, the
closed-loop poles against ``control.poles`` of ``A - B K``, the static gain against ``control.dcgain``; on a
second-order transfer function the loop ``N P(s) / (1 + K (sI - A)^-1 B)`` against ``numpy.roots`` of the
characteristic polynomial formed with python-control from the plant's matrices.
"""

from __future__ import annotations

import json
from pathlib import Path

import control
import numpy as np
import pytest

from designkit.cli import main
from designkit.pipeline import design as synthesize
from designkit.schema.loader import load_spec, parse_spec

SPEC = Path(__file__).resolve().parents[3] / "specs" / "state-space-third-order.yaml"
POLES = [-10.0, -12.0, -15.0]


def _sorted(z):
    z = np.asarray(z, complex)
    return z[np.lexsort((z.imag, z.real))]


def test_third_order_state_space_poles_against_python_control():
    loaded = load_spec(SPEC)
    d = synthesize(loaded)
    K = np.array([float(d.gains[k]) for k in ("K1", "K2", "K3")])
    N = float(d.gains["N"])
    wn, zeta = 40.0, 0.05
    A = np.array([[0, 1, 0], [0, 0, 1], [0, -wn**2, -2 * zeta * wn]])
    B = np.array([[0.0], [0.0], [wn**2]])
    C = np.array([[1.0, 0.0, 0.0]])
    assert np.allclose(K, np.asarray(control.acker(A, B, POLES)).ravel(), rtol=1e-9)
    loop = control.ss(A - B @ K[None, :], B * N, C, 0.0)
    assert np.allclose(_sorted(control.poles(loop)), _sorted(POLES), rtol=1e-9)
    assert control.dcgain(loop) == pytest.approx(1.0, rel=1e-9)
    # the example measures angle and speed through an observer: its poles join the regulator's
    assert np.allclose(_sorted(d.closed_loop.poles), _sorted([*POLES, -40, -45, -50]), rtol=1e-8)


def test_second_order_transfer_function_loop_against_numpy_roots():
    text = ("name: tf-regulator\nplant: {kind: transfer_function, num: [2, 6], den: [1, 1, 0]}\n"
            "controller: {kind: state_regulator, poles: [-5, -7]}\n")
    d = synthesize(parse_spec(text))
    K = np.array([float(d.gains["K1"]), float(d.gains["K2"])])
    A, B, C, _ = d.plant.matrices()
    # 1 + K (sI - A)^-1 B = num_K(s)/den(s): the closed loop's characteristic polynomial is den + num_K
    kb = control.ss2tf(control.ss(A, B, K[None, :], 0.0))
    num_k, den = np.ravel(kb.num[0][0]), np.ravel(kb.den[0][0])
    char = np.polyadd(den, num_k)
    assert np.allclose(_sorted(np.roots(char)), _sorted([-7, -5]), rtol=1e-9)
    # y/xD = N (2 s + 6) / char: the plant's zero -3 stays, the static gain is 1
    assert _sorted(d.zeros) == pytest.approx([-3.0], rel=1e-9)
    assert float(d.gains["N"]) * 6.0 / np.polyval(char, 0.0) == pytest.approx(1.0, rel=1e-9)


def test_third_order_example_is_verified_and_its_plant_is_described(tmp_path, capsys):
    code = main(["synth", str(SPEC), "--json", "--no-studies", "--out", str(tmp_path)])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["verified"] is True
    html = (tmp_path / "state-space-third-order" / "report.html").read_text()
    assert "theta" in html and "Luenberger observer reading the outputs theta_load, omega_load" in html


def test_two_inputs_robust_placement_against_numpy_and_python_control():
    text = ("name: mimo\nplant: {kind: state_space, A: [[0, 1, 0], [0, 0, 1], [-1, -2, '-a']], "
            "B: [[0, 0], [1, 0], [0, 1]], C: [[1, 0, 0]], parameters: {a: 3}}\n"
            "controller: {kind: state_regulator, poles: [-2, -4, -5]}\n")
    d = synthesize(parse_spec(text))
    K = np.array([[float(d.gains[f"K{j}_{i}"]) for i in (1, 2, 3)] for j in (1, 2)])
    N = np.array([float(d.gains["N1"]), float(d.gains["N2"])])
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -2.0, -3.0]])
    B = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert np.allclose(_sorted(np.linalg.eigvals(A - B @ K)), _sorted([-5, -4, -2]), rtol=1e-9)
    loop = control.ss(A - B @ K, (B @ N)[:, None], [[1.0, 0.0, 0.0]], 0.0)
    assert control.dcgain(loop) == pytest.approx(1.0, rel=1e-9)
    assert np.allclose(_sorted(d.zeros), _sorted(control.zeros(loop)), rtol=1e-7)
    # N is the least-norm choice: orthogonal to the null space of g = C (A - BK)^-1 B
    g = np.linalg.solve(A - B @ K, B)[0]
    assert abs(float(g[0] * N[1] - g[1] * N[0])) < 1e-12 * np.linalg.norm(g) * np.linalg.norm(N)


OBSERVED = ("name: observed\nplant: {kind: state_space, A: [[0, 1, 0], [0, 0, 1], [0, '-wn*wn', '-2*zeta*wn']], "
            "B: [[0], [0], ['K*wn*wn']], C: [[1, 0, 0]], parameters: {K: 1.0, wn: 40.0, zeta: 0.05}}\n"
            "controller: {kind: state_regulator, poles: [-10, -12, -15]OBSERVER}\nsimulation: {duration: 1.0}\n")


def test_observer_loop_has_the_regulator_and_observer_poles_and_the_same_step():
    from designkit.pipeline import run

    observed = run(parse_spec(OBSERVED.replace("OBSERVER", ", observer_poles: [-40, -45, -50]")))
    full = run(parse_spec(OBSERVED.replace("OBSERVER", "")))
    d = observed.design
    K = np.array([float(d.gains[f"K{i}"]) for i in (1, 2, 3)])
    L = np.array([float(d.gains[f"L{i}_1"]) for i in (1, 2, 3)])
    wn, zeta = 40.0, 0.05
    A = np.array([[0, 1, 0], [0, 0, 1], [0, -wn**2, -2 * zeta * wn]])
    B = np.array([0.0, 0.0, wn**2])
    C = np.array([1.0, 0.0, 0.0])
    assert np.allclose(_sorted(np.linalg.eigvals(A - np.outer(L, C))), _sorted([-50, -45, -40]), rtol=1e-8)
    Acl = np.block([[A, -np.outer(B, K)], [np.outer(L, C), A - np.outer(B, K) - np.outer(L, C)]])
    assert np.allclose(_sorted(np.linalg.eigvals(Acl)), _sorted([-50, -45, -40, -15, -12, -10]), rtol=1e-7)
    # separation: started at rest with x̂ = x, the estimation error stays 0 on the nominal plant, so the observed
    # loop's step is the full-state regulator's
    t_obs, t_full = np.asarray(observed.simulation.time), np.asarray(full.simulation.time)
    common = np.intersect1d(np.round(t_obs, 9), np.round(t_full, 9))
    assert common.size > 100
    y_obs = np.asarray(observed.simulation.state)[np.isin(np.round(t_obs, 9), common), 0]
    y_full = np.asarray(full.simulation.state)[np.isin(np.round(t_full, 9), common), 0]
    assert np.max(np.abs(y_obs - y_full)) < 1e-6
    assert observed.verified


@pytest.mark.parametrize(("plant", "controller", "message"), [
    ("{kind: link, Km: 2.0, tau: 0.5}", "{kind: state_regulator, poles: [-6, -8], observer_poles: [-20, -30]}",
     "controller.observer_poles: the state_regulator controller reads it on a transfer_function or state_space"),
    ("{kind: transfer_function, num: [1], den: [1, 1, 0]}",
     "{kind: state_regulator, poles: [-6, -8], observer_poles: [-20]}", "controller.observer_poles: the observer"),
    ("{kind: state_space, A: [[-1, 0], [0, -2]], B: [[1], [1]], C: [[1, 0]]}",
     "{kind: state_regulator, poles: [-6, -8], observer_poles: [-20, -30]}", "plant.C: (A, C) is not observable"),
])
def test_observer_refusals(plant, controller, message, tmp_path, capsys):
    from tests.cli_input import assert_bad_input

    assert_bad_input(tmp_path, capsys, f"name: bad\nplant: {plant}\ncontroller: {controller}\n", message)
