"""Learning on a linear plant: Moore's discrete two-state plant (the textbook case) at two gains, a continuous plant
sampled by the zero-order hold, the filter update, and what is refused.

Every expected value comes from an independent computation: the lifted matrix built here by a loop over the
Markov parameters ``C A^m B``, its norms from ``numpy.linalg.norm`` and ``numpy.linalg.eigvals``, the trials from
the iteration ``e_(k+1) = (I - gamma H) e_k`` run here, and the zero-order hold from ``scipy.signal.cont2discrete``.
"""

from __future__ import annotations

import numpy as np
import pytest

from designkit.pipeline import run
from designkit.schema.loader import load_spec, parse_spec
from tests.cli_input import assert_bad_input
from tests.families.ilc.common import SPECS

A = np.array([[-0.8, -0.22], [1.0, 0.0]])
B = np.array([0.5, 1.0])
C = np.array([1.0, 0.5])
L = 50  # a trial of 51 samples: u_0 .. u_49 move y_1 .. y_50


def _lifted(A: np.ndarray, B: np.ndarray, C: np.ndarray, L: int) -> np.ndarray:
    """The lifted matrix by a plain loop: ``H[i, j] = C A^(i-j) B`` for ``i >= j``."""
    h, x = [], B.copy()
    for _ in range(L):
        h.append(float(C @ x))
        x = A @ x
    H = np.zeros((L, L))
    for i in range(L):
        for j in range(i + 1):
            H[i, j] = h[i - j]
    return H


H = _lifted(A, B, C, L)


@pytest.fixture(scope="module", params=[("ilc-moore-monotone", 0.5), ("ilc-moore-asymptotic", 1.5)])
def moore(request):
    name, gamma = request.param
    return run(load_spec(SPECS / f"{name}.yaml")), gamma


def test_moore_figures_by_hand():
    T = np.eye(L) - 1.5 * H
    assert float(C @ B) == 1.0
    assert np.max(np.abs(np.linalg.eigvals(T))) == pytest.approx(0.5, abs=1e-12)
    assert np.linalg.norm(T, 2) == pytest.approx(1.149, abs=5e-4)  # the published 1.149 at this horizon
    assert np.linalg.norm(np.eye(L) - 0.5 * H, 2) == pytest.approx(0.646, abs=5e-4)


def test_moore_certificate_against_numpy(moore):
    result, gamma = moore
    T = np.eye(L) - gamma * H
    norm, radius = np.linalg.norm(T, 2), np.max(np.abs(np.linalg.eigvals(T)))
    out = result.to_json()
    assert out["rho"] == pytest.approx(norm, rel=1e-9)
    assert out["spectral_radius"] == pytest.approx(radius, abs=1e-12)
    lo, hi = out["rho_bounds"]
    assert lo <= norm * (1 + 1e-12) and norm <= hi * (1 + 1e-12)
    check = next(c for c in result.checks if c.name == "ilc_convergence")
    assert check.passed is bool(norm < 1)  # 0.646: monotone, proved; 1.149: proved above 1, a FAIL
    spectral = next(c for c in result.checks if c.name == "ilc_spectral_radius")
    assert spectral.passed is True and spectral.achieved == pytest.approx(0.5, abs=1e-12)


def test_moore_trials_against_own_iteration(moore):
    result, gamma = moore
    trials = result.trials.results
    e = None
    for k, trial in enumerate(trials):
        measured = trial.reference[1:, 0, 0] - trial.state[1:, list(trial.positions)[0]]
        if e is None:  # trial 0: no input, y = 0, e = yD
            e = trial.reference[1:, 0, 0].copy()
        assert measured == pytest.approx(e, abs=1e-10 * max(1.0, float(np.max(np.abs(e))))), k
        e = (np.eye(L) - gamma * H) @ e
    norms = result.trials.error_norms
    if gamma == 0.5:  # monotone: every trial at least by rho
        assert np.all(norms[1:] <= np.linalg.norm(np.eye(L) - 0.5 * H, 2) * norms[:-1] + 1e-12)
        assert result.verified
    else:  # asymptotic only: the error norm falls, then grows for many trials
        assert np.argmin(norms) < 5 and norms[-1] > 10 * norms.min()
        assert not result.verified


def test_a_continuous_plant_is_sampled_by_the_zero_order_hold():
    from scipy.signal import cont2discrete

    text = ("name: zoh\nplant: {kind: transfer_function, num: [2], den: [1, 3, 2]}\n"
            "controller: {kind: ilc, trials: 4, learning: {kind: adjoint}}\n"
            "simulation: {duration: 2.0, dt: 0.02, trajectory: {kind: quintic, amplitude: 1.0, duration: 1.5}}\n")
    result = run(parse_spec(text))
    Ac = np.array([[0.0, 1.0], [-2.0, -3.0]])
    Bc = np.array([[0.0], [2.0]])
    Ad, Bd, *_ = cont2discrete((Ac, Bc, np.array([[1.0, 0.0]]), np.zeros((1, 1))), 0.02, method="zoh")
    N = 101
    Hd = _lifted(Ad, Bd[:, 0], np.array([1.0, 0.0]), N - 1)
    sv = np.linalg.svd(Hd, compute_uv=False)
    alpha = 1.0 / sv[0] ** 2
    out = result.to_json()
    assert out["learning"]["value"] == pytest.approx(alpha, rel=1e-8)
    assert out["rho"] == pytest.approx(max(abs(1 - alpha * sv[0] ** 2), abs(1 - alpha * sv[-1] ** 2)), rel=1e-8)
    e = result.trials.results[0].reference[1:, 0, 0]
    for trial in result.trials.results:  # the trials are the sampled plant's: e_(k+1) = (I - alpha H H^T) e_k
        assert trial.reference[1:, 0, 0] - trial.state[1:, 0] == pytest.approx(e, abs=1e-9)
        e = e - alpha * Hd @ (Hd.T @ e)


def test_the_filter_update_against_numpy():
    num, den = [0.4, 0.2], [1.0, -0.3]
    text = (f"name: filt\nplant: {{kind: state_space, dt: 1.0, A: [[-0.8, -0.22], [1, 0]], B: [[0.5], [1]], "
            f"C: [[1, 0.5]]}}\ncontroller: {{kind: ilc, trials: 3, learning: {{kind: filter, num: {num}, "
            f"den: {den}}}}}\nsimulation: {{duration: 50, trajectory: {{kind: sine, amplitude: 1.0, "
            "frequency: 0.02}}\n")
    result = run(parse_spec(text))
    f = np.zeros(L)  # the filter's impulse response by its own recursion
    for i in range(L):
        f[i] = (num[i] if i < len(num) else 0.0) + (0.3 * f[i - 1] if i else 0.0)
    F = np.array([[f[i - j] if i >= j else 0.0 for j in range(L)] for i in range(L)])
    T = np.eye(L) - F @ H
    out = result.to_json()
    assert out["rho"] == pytest.approx(np.linalg.norm(T, 2), rel=1e-9)
    assert out["spectral_radius"] == pytest.approx(abs(1 - 0.4), abs=1e-12)


@pytest.mark.parametrize(("body", "message"), [
    ("plant: {kind: state_space, dt: 1.0, A: [[0.5]], B: [[1]], C: [[1]]}\n"
     "controller: {kind: ilc, poles: [-2, -2]}\nsimulation: {duration: 5}\n",
     "controller.poles: on a state_space plant the learned signal is the plant's input"),
    ("plant: {kind: state_space, dt: 1.0, A: [[0.5]], B: [[1]], C: [[1]]}\ncontroller: {kind: ilc}\n"
     "simulation: {duration: 5, dt: 0.5}\n", "simulation.dt: 0.5 s differs from the discrete-time plant's"),
    ("plant: {kind: state_space, dt: 1.0, A: [[0.5]], B: [[1]], C: [[1]]}\ncontroller: {kind: ilc}\n"
     "simulation: {duration: 5, delay: 0.1}\n", "simulation.delay: the learning trials on a state_space plant"),
    ("plant: {kind: robot, robot: planar2r}\ncontroller: {kind: ilc}\n",
     "controller.poles: computed torque on a robot"),
    ("plant: {kind: state_space, dt: 1.0, A: [[0.5]], B: [[1]], C: [[1]]}\n"
     "controller: {kind: ilc, learning: {kind: filter, num: [0, 1]}}\nsimulation: {duration: 5}\n",
     "controller.learning.num: num[0] must be nonzero"),
    ("plant: {kind: state_space, dt: 1.0, A: [[0.5]], B: [[1]], C: [[1]]}\n"
     "controller: {kind: pid_servo, poles: [-1, -2, -3]}\n", "plant.dt: the pid_servo controller does not use it"),
])
def test_refusals_exit_2_naming_the_key(body, message, tmp_path, capsys):
    assert_bad_input(tmp_path, capsys, "name: bad\n" + body, message)


def test_an_unstable_filter_is_undecided_not_a_crash():
    """``F(z) = 0.5/(1 - 3 z^-1)``: its coefficients 0.5 * 3^m overflow within 700 samples. The norm is not computed
    (UNDECIDED, said so), the trials diverge (FAIL), and the JSON stays strict."""
    import json

    text = ("name: unstable-filter\nplant: {kind: state_space, dt: 1.0, A: [[-0.8, -0.22], [1, 0]], B: [[0.5], [1]], "
            "C: [[1, 0.5]]}\ncontroller: {kind: ilc, trials: 3, learning: {kind: filter, num: [0.5], den: [1, -3]}}\n"
            "simulation: {duration: 700, trajectory: {kind: sine, amplitude: 1.0, frequency: 0.002}}\n")
    result = run(parse_spec(text))
    rho = next(c for c in result.checks if c.name == "ilc_convergence")
    assert rho.passed is None and "not finite" in rho.detail
    assert not result.verified
    json.dumps(result.to_json(), allow_nan=False)  # no NaN nor Infinity anywhere


def test_designkit_simulate_runs_the_trials_and_prints_the_last(capsys):
    from designkit.cli import main

    assert main(["simulate", str(SPECS / "ilc-moore-monotone.yaml")]) == 0
    out = capsys.readouterr().out
    assert "simulated 50 s in 50 steps" in out
    assert "max |y - xD| = 0.0002463" in out  # the 20th trial's largest error (the spec's tracking_error)
