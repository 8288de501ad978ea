"""The identification on the SIMNOG arm: V non-increasing outside the residual band (property test on random arms,
servo and adaptation gains in a box), convergence to the base parameters computed independently (sympy's
Euler-Lagrange torque, its coordinates in the base columns), re-convergence after a step of the forearm's mass,
the reconstructed acceleration and the observer's band from the record, the failing example, bad input.

The true base parameters come from :mod:`tests.families.sliding_mode_identification.two_link` (sympy), the record
is read with NumPy; nothing expected is taken from the family's own analysis."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from designkit.cli import main
from designkit.families.sliding_mode_identification.arm import base_of
from designkit.families.sliding_mode_identification.checks import diagnose
from designkit.pipeline import run
from designkit.schema.loader import load_spec, parse_spec
from tests.cli_input import assert_bad_input
from tests.families.sliding_mode_identification import two_link
from tests.families.sliding_mode_identification.conftest import SPECS

NAMES = ("mcx1R", "mcy1", "Izz1R", "mcx2R", "mcy2", "Izz2R", "fv1", "fc1", "fv2", "fc2")
DEFAULTS = {"m1": 5.0, "m2": 3.0, "d1": 0.5, "d2": 0.4, "I1": 5.0 * 0.5**2 / 12, "I2": 3.0 * 0.4**2 / 12,
            "f1": 2.0, "f2": 1.0, "g": 9.81}
GAINS = {"mcx1R": 0.04, "mcy1": 0.5, "Izz1R": 0.075, "mcx2R": 0.0052, "mcy2": 0.059, "Izz2R": 0.009, "fv1": 2.4,
         "fc1": 7.3, "fv2": 1.0, "fc2": 7.3}


def _beta(values: dict[str, float], plant) -> np.ndarray:
    """The base parameters of the arm ``values``, independently: sympy's torque in the base columns."""
    beta, residual = two_link.base_by_least_squares(values, base_of(plant).W_base)
    assert residual < 1e-9
    return beta


def _record(result):
    sim = result.simulation
    t = np.asarray(sim.time)
    est = np.stack([np.asarray(sim.signals[f"{x}_hat"]) for x in NAMES], axis=1)
    return t, est


def _V(est: np.ndarray, beta: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    return np.einsum("kp,p,kp->k", beta - est, 1.0 / gamma, beta - est)


def _two_point(result, beta, gamma, Ts, N):
    """Per sample, from the record: |e|, |r| of the two time points, the normalised step s and 1/m2 (the test's
    own reading of the law: regressors at the mean state of the last sample, the backward difference)."""
    sim = result.simulation
    Wb = base_of(result.design.plant).W_base
    x = np.asarray(sim.state)
    q, qd = x[:, list(sim.positions)], x[:, list(sim.velocities)]
    u = np.asarray(sim.u_command)
    _, est = _record(result)
    K = len(q)
    Y = np.zeros((K, 2, len(NAMES)))
    for k in range(1, K):
        Y[k] = np.asarray(Wb((q[k] + q[k - 1]) / 2, (qd[k] + qd[k - 1]) / 2, (qd[k] - qd[k - 1]) / Ts))
    before = np.vstack([est[:1] * np.nan, est[:-1]])
    e, r, s, inv = (np.zeros(K) for _ in range(4))
    for k in range(N + 1, K):
        rows = np.vstack([Y[k], Y[k - N]])
        torque = np.concatenate([u[k - 1], u[k - N - 1]])
        e[k] = np.linalg.norm(rows @ (beta - before[k]))
        r[k] = np.linalg.norm(torque - rows @ beta)
        m2 = max(1.0, Ts * float(np.sum(rows**2 @ gamma)))
        s[k] = Ts * np.linalg.eigvalsh((rows * gamma) @ rows.T)[-1] / m2
        inv[k] = Ts / m2
    return e, r, s, inv


SPEC = """\
name: smid-arm-property
plant: {{kind: robot, robot: planar2r, parameters: {{m1: {m1}, m2: {m2}, f1: {f1}, f2: {f2}}}}}
controller:
  kind: sliding_mode_identification
  servo: {{K1: [{K1a}, {K1b}], K2: [{K2a}, {K2b}]}}
  initial_estimates: {{mcx1R: {a0}, Izz1R: {b0}, fv1: {c0}}}
  adaptation_gains: {gains}
  switching_gain: [100, 300]
  window: {D}
  sampling_period: 0.002
simulation:
  duration: 5
  initial_position: [-0.2, 0.0]
  trajectory: {{kind: multisine, amplitude: [1.0, 1.2], period: 5, harmonics: 3}}
"""


@settings(max_examples=5, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True,
          phases=(Phase.explicit, Phase.generate))
@given(m1=st.floats(3.0, 7.0), m2=st.floats(2.0, 4.0), f1=st.floats(0.5, 3.0), f2=st.floats(0.2, 2.0),
       K1a=st.floats(100, 300), K1b=st.floats(30, 90), K2a=st.floats(15, 40), K2b=st.floats(4, 12),
       scale=st.floats(0.05, 3.0), D=st.sampled_from([0.05, 0.1, 0.2]), a0=st.floats(0.0, 4.0),
       b0=st.floats(-2.5, 0.0), c0=st.floats(0.0, 3.0))
def test_lyapunov_function_does_not_increase_outside_the_residual_band(tmp_path_factory, m1, m2, f1, f2, K1a, K1b,
                                                                      K2a, K2b, scale, D, a0, b0, c0):
    """Random arms, servo gains, adaptation gains (the SIMNOG gains times 0.05 to 3) and initial errors: at every
    sample V(k) - V(k-1) <= (Ts/m2)(-2|e|^2 + 2|e||r| + s(|e| + |r|)^2), so V does not rise where |e| >= x*(s)|r|,
    with e, r and V from the sympy base parameters; V ends below its start."""
    gains = {k: v * scale for k, v in GAINS.items()}
    path = tmp_path_factory.mktemp("smid-arm") / "spec.yaml"
    path.write_text(SPEC.format(m1=m1, m2=m2, f1=f1, f2=f2, K1a=K1a, K1b=K1b, K2a=K2a, K2b=K2b, D=D, a0=a0, b0=b0,
                                c0=c0, gains=json.dumps(gains)))
    result = run(load_spec(path))
    plant = result.design.plant
    values = {**DEFAULTS, "m1": m1, "m2": m2, "f1": f1, "f2": f2}
    beta = _beta(values, plant)
    gamma = np.array([gains[x] for x in NAMES])
    Ts, N = 0.002, int(round(D / 0.002))
    _, est = _record(result)
    V = _V(est, beta, gamma)
    e, r, s, inv = _two_point(result, beta, gamma, Ts, N)
    dV = np.diff(V)[N:]  # from sample N + 1 on, both time points counted
    e, r, s, inv = e[N + 1:], r[N + 1:], s[N + 1:], inv[N + 1:]
    assert np.all(s < 2)
    bound = inv * (-2 * e**2 + 2 * e * r + s * (e + r) ** 2)
    assert np.all(dV <= bound + 1e-9 * V[0]), float(np.max(dV - bound))
    xstar = ((1 + s) + np.sqrt((1 + s) ** 2 + s * (2 - s))) / (2 - s)
    outside = e >= xstar * r
    assert outside.mean() > 0.5  # the band is where the estimates have converged to the residual's size
    assert np.all(dV[outside] <= 1e-9 * V[0])
    assert V[-1] < V[0]
    assert {c.name: c.passed for c in result.checks}["identification_lyapunov"] is True


def test_estimates_converge_to_the_independent_base_parameters_and_after_the_step(simnog_result):
    """smid-simnog: the ten estimates at 40 s against the arm with m2 = 3 kg, at 70 s against m2 = 4 kg (sympy)."""
    plant = simnog_result.design.plant
    before, after = _beta(DEFAULTS, plant), _beta({**DEFAULTS, "m2": 4.0}, plant)
    t, est = _record(simnog_result)
    k = np.searchsorted(t, 40.0) - 1
    assert est[k] == pytest.approx(before, abs=2e-3)
    assert est[-1] == pytest.approx(after, abs=2e-3)
    changed = np.abs(after - before) > 1e-12
    assert {x for x, c in zip(NAMES, changed, strict=True) if c} == {"mcx1R", "Izz1R", "mcx2R", "Izz2R"}
    assert simnog_result.verified is True
    checks = {c.name: c for c in simnog_result.checks}
    assert checks["identification_convergence"].required and checks["identification_convergence"].passed


def test_the_step_raises_v_and_it_falls_again(simnog_result):
    """V with the true parameters of each instant: it jumps at the step (the truth moved), then falls by at least
    1e4 before the end; the family's Lyapunov check excludes the D after the step and passes."""
    plant = simnog_result.design.plant
    t, est = _record(simnog_result)
    beta = np.where((t >= 40.0)[:, None], _beta({**DEFAULTS, "m2": 4.0}, plant), _beta(DEFAULTS, plant))
    gamma = np.asarray(simnog_result.design.data.gamma)
    V = np.einsum("kp,p,kp->k", beta - est, 1.0 / gamma, beta - est)
    k = np.searchsorted(t, 40.0)
    assert V[k] > 100 * V[k - 1]
    assert V[-1] < 1e-4 * V[k]
    assert {c.name: c.passed for c in simnog_result.checks}["identification_lyapunov"] is True


def test_acceleration_and_observer_band_from_the_record(simnog_result):
    """The equivalent switching term gives the backward difference of the measured speed (the link's identity), and
    each observer's sliding variable stays within Ts (k_j + |model error|) < 2 Ts k_j once its condition holds."""
    sim = simnog_result.simulation
    qd = np.asarray(sim.state)[:, list(sim.velocities)]
    t = np.asarray(sim.time)
    for j, k in enumerate((30.0, 100.0)):
        acc = np.asarray(sim.signals[f"acc{j + 1}"])
        assert acc[1:] == pytest.approx(np.diff(qd[:, j]) / 0.002, abs=1e-7)
        slm = np.asarray(sim.signals[f"slm{j + 1}"])[t > 0.5]
        assert np.max(np.abs(slm)) <= 2 * 0.002 * k  # Ts (k + |model error|), the error below k


def test_subset_with_the_others_known(tmp_path):
    """Four parameters identified, six known at the model's values: each estimate within 1e-3 of sympy's."""
    text = (SPECS / "smid-simnog.yaml").read_text()
    data = yaml.safe_load(text)
    data["controller"]["identify"] = ["Izz1R", "Izz2R", "fv1", "fv2"]
    data["controller"]["initial_estimates"] = {"Izz1R": -1.2, "fv2": 0.7}
    data["simulation"]["duration"] = 15
    del data["simulation"]["plant_change"]
    result = run(parse_spec(yaml.safe_dump(data)))
    beta = dict(zip(NAMES, _beta(DEFAULTS, result.design.plant), strict=True))
    for x in ("Izz1R", "Izz2R", "fv1", "fv2"):
        assert result.simulation.signals[f"{x}_hat"][-1] == pytest.approx(beta[x], abs=1e-3)
    known = dict(result.design.data.identifier.known)
    assert {result.design.data.base_names[c]: v for c, v in known.items()} == pytest.approx(
        {x: beta[x] for x in NAMES if x not in ("Izz1R", "Izz2R", "fv1", "fv2")}, abs=1e-9)
    assert result.verified is True


def test_switching_gains_too_small_fail_their_check_but_not_the_estimates(tmp_path):
    data = yaml.safe_load((SPECS / "smid-simnog.yaml").read_text())
    data["controller"].update(identify=["Izz1R", "fv1"], switching_gain=[0.5, 0.5],
                              initial_estimates={"Izz1R": -1.2, "fv1": 1.5})
    data["simulation"]["duration"] = 10
    del data["simulation"]["plant_change"]
    result = run(parse_spec(yaml.safe_dump(data)))
    checks = {c.name: c for c in result.checks}
    assert checks["switching_condition"].passed is False
    beta = dict(zip(NAMES, _beta(DEFAULTS, result.design.plant), strict=True))
    assert result.simulation.signals["Izz1R_hat"][-1] == pytest.approx(beta["Izz1R"], abs=1e-3)
    cause, fix = diagnose(result, checks["switching_condition"])
    assert "switching_gain" in fix and "k1 >" in fix


def test_single_step_does_not_excite_and_says_what_would(simnog_single_step_result):
    result = simnog_single_step_result
    checks = {c.name: c for c in result.checks}
    det = checks["determinant_condition"]
    assert det.passed is False and det.achieved < 0.1
    assert checks["identification_convergence"].required is False
    assert result.verified is False
    cause, fix = diagnose(result, det)
    assert "multisine" in fix and "controller.identify" in fix
    # independently: after the transient the arm rests, so the two-point information matrices of the last 20 s
    # have the rank of one configuration's gravity rows, far below the ten parameters
    sim = result.simulation
    t = np.asarray(sim.time)
    x = np.asarray(sim.state)
    Wb = base_of(result.design.plant).W_base
    late = np.flatnonzero(t > 10.0)[::500]
    rows = np.vstack([np.asarray(Wb(x[k, :2], x[k, 2:], np.zeros(2))) for k in late])
    sv = np.linalg.svd(rows, compute_uv=False)
    assert np.sum(sv > 1e-6 * sv[0]) <= 4


def test_verify_json_gives_the_estimates_by_name(capsys):
    code = main(["verify", str(SPECS / "smid-simnog.yaml"), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert set(out["estimates"]) == set(NAMES)
    assert out["estimates"]["fv1"] == pytest.approx(2.0, abs=2e-3)
    assert out["estimates"]["mcx2R"] == pytest.approx(4.0 * 0.4 / 2, abs=2e-3)  # m2 d2/2 after the step
    assert out["identification"]["units"]["Izz1R"] == "kg*m^2"


HEAD = ("name: bad\nplant: {kind: robot, robot: planar2r}\n"
        "simulation: {duration: 4, trajectory: {kind: multisine, amplitude: [1.0, 1.2], period: 5, harmonics: 3}}\n"
        "controller: {kind: sliding_mode_identification, servo: {K1: [200, 60], K2: [30, 8]}, ")


@pytest.mark.parametrize("extra, message", [
    ("switching_gain: [30, 0]}", "controller.switching_gain[1]: "),
    ("switching_gain: -1}", "controller.switching_gain: "),
    ("switching_gain: 30, window: 0}", "controller.window: "),
    ("switching_gain: 30, window: -0.1}", "controller.window: "),
    ("switching_gain: 30, adaptation_gains: {Izz1R: 0}, identify: [Izz1R]}", "controller.adaptation_gains.Izz1R: "),
    ("switching_gain: 30, adaptation_gains: [1, -2], identify: [Izz1R, fv1]}", "controller.adaptation_gains[1]: "),
    ("switching_gain: 30, identify: [Izz1R, m2]}", "controller.identify[1]: the arm has no base parameter 'm2'"),
    ("switching_gain: 30, identify: [fv1, fv1]}", "controller.identify[1]: "),
    ("switching_gain: 30, initial_estimates: {Izz9: 1}}", "controller.initial_estimates.Izz9: not an identified"),
    ("switching_gain: 30, adaptation_gains: {fv1: 1}, identify: [Izz1R, fv1]}", "controller.adaptation_gains: no gain"),
    ("switching_gain: 30, adaptation_gains: {foo: 1}}", "controller.adaptation_gains.foo: not an identified"),
    ("switching_gain: 30, c: 2}", "controller.c: "),
    ("window: 0.1}", "controller.switching_gain: required on a robot"),
    ("switching_gain: 30, servo: {K1: 0}}", "controller.servo.K1: "),
])
def test_bad_input(extra, message, tmp_path, capsys):
    text = HEAD + extra + "\n"
    if "servo: {K1: 0}" in extra:
        text = text.replace("servo: {K1: [200, 60], K2: [30, 8]}, ", "")
    assert_bad_input(tmp_path, capsys, text, message)


def test_a_change_of_the_kinematics_is_refused(tmp_path, capsys):
    text = HEAD.replace("harmonics: 3}", "harmonics: 3}, plant_change: {time: 2, values: {d1: 0.6}}") + \
        "switching_gain: 30}\n"
    assert_bad_input(tmp_path, capsys, text, "simulation.plant_change.values.d1: d1 enters the regressor")


def test_link_fields_on_a_robot_and_robot_fields_on_the_link_are_refused(tmp_path, capsys):
    link = ("name: bad\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
            "simulation: {duration: 4, trajectory: {kind: square, amplitude: 0.5, period: 2}}\n"
            "controller: {kind: sliding_mode_identification, initial_estimates: [1, 1], error_bounds: {a: 3, b: 5}, ")
    assert_bad_input(tmp_path, capsys, link + "switching_gain: 30}\n", "controller.switching_gain: ")
    assert_bad_input(tmp_path, capsys, link.replace("period: 2}", "period: 2, harmonics: 2}").replace(
        "kind: square", "kind: multisine") + "window: 0.25}\n", "simulation.trajectory.kind: ")
