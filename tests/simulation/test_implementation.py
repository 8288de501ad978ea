"""The controller as implemented (``implementation:``): each part of the implemented loop against a route of its
own -- the sampled sliding-mode link against its exact zero-order-hold discretisation, the actuator lag against
scipy's response of the linear closed loop with the lag in series, the quantised measurement against our own
rounding, the computation delay against ``simulation.delay``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import signal
from scipy.linalg import expm

from designkit.schema.loader import parse_spec
from designkit.schema.spec import Spec
from designkit.simulation.run import build, simulate
from tests.simulation.helpers import NOMINAL, POSSPEED, design_of

ROOT = Path(__file__).resolve().parents[2]
KM, TAU = 2.0, 0.5


def _spec(implementation: dict | None = None, controller: dict | None = None, **simulation) -> Spec:
    data = {"name": "impl-test", "plant": NOMINAL, "controller": controller or POSSPEED, "simulation": simulation}
    if implementation is not None:
        data["implementation"] = implementation
    return Spec.model_validate(data)


def _sliding_spec(implementation: dict) -> Spec:
    data = yaml.safe_load((ROOT / "specs" / "sliding-mode-link.yaml").read_text())
    data["implementation"] = implementation
    return parse_spec(yaml.safe_dump(data)).spec


# ----------------------------------------------------------------------------- (a) sampled sliding-mode link


def _zoh_sliding_loop(gains: dict, n_samples: int, ts: float, xd: float, xi_time: float, xi: float):
    """The sliding-mode law ``u = -psi e - M sign(s)``, ``s = x2 + c e``, ``psi = alpha if e s > 0 else beta``,
    computed here per sample and applied through the exact zero-order hold of the link ``x1' = x2,
    x2' = -x2/tau + Km/tau (u + xi)`` (scipy ``expm`` of the augmented matrix)."""
    F = np.array([[0.0, 1.0], [0.0, -1.0 / TAU]])
    b = np.array([[0.0], [KM / TAU]])
    M_ = expm(np.block([[F, b], [np.zeros((1, 3))]]) * ts)
    A, B = M_[:2, :2], M_[:2, 2]
    al, be, M, c = (float(gains[k]) for k in ("alpha", "beta", "M", "c"))
    x, xs, us = np.zeros(2), [], []
    for k in range(n_samples):
        xs.append(x.copy())
        e = x[0] - xd
        s = x[1] + c * e
        psi = al if e * s > 0 else be
        u = -psi * e - M * np.sign(s)
        us.append(u)
        d = xi if k * ts >= xi_time - 1e-12 else 0.0
        x = A @ x + B * (u + d)
    return np.asarray(xs), np.asarray(us)


def test_a_sampled_sliding_mode_link_is_its_exact_zero_order_hold_loop():
    ts = 1e-3
    spec = _sliding_spec({"sampling_period": ts})
    design = design_of(spec)
    res = simulate(spec, design)
    assert res.settings["sampling_period"] == ts
    assert res.settings["sampling_period_source"] == "implementation.sampling_period"
    per = int(res.settings["steps_per_sample"])
    assert per >= 1 and abs(per * res.settings["dt"] - ts) < 1e-12
    n = (len(res.time) - 1) // per
    x_ref, u_ref = _zoh_sliding_loop(dict(design.gains.items()), n, ts, 1.0, 1.0, 1.0)
    x_run = np.asarray(res.state)[::per][:n]
    u_run = np.asarray(res.u_command)[::per, 0][:n]
    np.testing.assert_allclose(u_run, u_ref, rtol=0, atol=1e-9)  # the same switching sequence, sample for sample
    np.testing.assert_allclose(x_run, x_ref, rtol=0, atol=1e-9)
    held = np.asarray(res.u_command)[: per * n, 0].reshape(n, per)
    assert np.max(np.ptp(held, axis=1)) == 0.0  # held between samples
    assert "sampled at 1 kHz" in res.settings["implementation"]


# ----------------------------------------------------------------------------- (b) actuator lag


def _pid_with_lag(gains: dict, bw: float) -> signal.StateSpace:
    """The POSSPEED PID loop with the lag ``ua' = bw (u - ua)`` in series, written here from the law
    ``u = -K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD``, ``x3' = x1 - xD``; state ``(x1, x2, x3, ua)``, input ``xD``."""
    K1, K2, K3, K4 = (float(gains[k]) for k in ("K1", "K2", "K3", "K4"))
    A = np.array([[0.0, 1.0, 0.0, 0.0],
                  [0.0, -1.0 / TAU, 0.0, KM / TAU],
                  [1.0, 0.0, 0.0, 0.0],
                  [-bw * K1, -bw * K2, -bw * K3, -bw]])
    B = np.array([[0.0], [0.0], [-1.0], [bw * (K1 + K3 * K4)]])
    return signal.StateSpace(A, B, np.eye(4), np.zeros((4, 1)))


def test_the_actuator_lag_is_the_linear_loop_with_the_lag_in_series():
    bw = 60.0
    spec = _spec({"actuator": {"bandwidth": bw}}, duration=2.0)
    design = design_of(spec)
    res = simulate(spec, design)
    assert res.settings["integrator"].startswith("dopri5")  # the lag is a smooth state: the loop stays smooth
    assert res.settings["dt"] <= 0.02 / bw  # the default step resolves the lag
    t = np.asarray(res.time)
    _, y, _ = signal.lsim(_pid_with_lag(dict(design.gains.items()), bw), np.ones_like(t), t)
    np.testing.assert_allclose(res.state, y[:, :2], rtol=0, atol=1e-6)
    np.testing.assert_allclose(res.controller_state[:, 0], y[:, 2], rtol=0, atol=1e-6)
    np.testing.assert_allclose(res.u_applied[:, 0], y[:, 3], rtol=0, atol=1e-6)  # the applied input is the lag's
    K1, K2, K3, K4 = (float(design.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    u = -K1 * (y[:, 0] - 1.0) - K2 * y[:, 1] - K3 * y[:, 2] + K3 * K4
    np.testing.assert_allclose(res.u_command[:, 0], u, rtol=0, atol=1e-5)  # the recorded command is the law's


def test_the_actuator_saturates_before_its_lag():
    limit, bw = 5.0, 200.0
    res = simulate(_spec({"actuator": {"limit": limit, "bandwidth": bw}}, duration=3.0), design_of(_spec()))
    u_c, u_a, t = res.u_command[:, 0], res.u_applied[:, 0], np.asarray(res.time)
    assert np.max(np.abs(u_c)) > 5 * limit  # the law asks for more than the actuator gives
    assert np.max(np.abs(u_a)) <= limit * (1 + 1e-9)
    # where the command stays beyond the limit, the lag converges to the limit: ua = limit (1 - exp(-bw t))
    beyond = np.flatnonzero(u_c < limit)[0]
    k = np.arange(beyond)
    np.testing.assert_allclose(u_a[k], limit * (1 - np.exp(-bw * t[k])), rtol=0, atol=1e-6)
    assert abs(res.position[-1] - 1.0) < 5e-3


def test_the_nonlinear_element_acts_before_the_actuator():
    """``simulation.nonlinearity`` (a saturation at 3 N*m) first, then the actuator (limit 5, lag 200 rad/s): the lag
    rises towards the element's 3, not the actuator's 5."""
    bw = 200.0
    spec = _spec({"actuator": {"limit": 5.0, "bandwidth": bw}}, duration=2.0,
                 nonlinearity={"kind": "saturation", "limit": 3.0})
    res = simulate(spec, design_of(_spec()))
    t, u_a = np.asarray(res.time), res.u_applied[:, 0]
    k = np.arange(int(0.02 / res.settings["dt"]))  # the command stays far above 3 N*m over the first 20 ms
    assert np.all(res.u_command[k, 0] > 3.0)
    np.testing.assert_allclose(u_a[k], 3.0 * (1 - np.exp(-bw * t[k])), rtol=0, atol=1e-6)


def test_the_lag_starts_where_the_loop_rests_under_gravity():
    """The two-link arm held still at (0.3, 0.2) rad against gravity: the lag starts at the holding torque, so the
    arm stays where it is (a lag started at zero would let it fall for the first milliseconds)."""
    text = ("name: r\nplant: {kind: robot, robot: planar2r}\n"
            "controller: {kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}\n"
            "simulation: {duration: 0.5, step: [0.0, 0.0], initial_position: [0.3, 0.2]}\n"
            "implementation: {actuator: {bandwidth: 200}}\n")
    spec = parse_spec(text).spec
    res = simulate(spec, design_of(spec))
    assert np.max(np.abs(res.u_applied[0])) > 1.0  # gravity needs a torque
    assert np.max(np.abs(np.asarray(res.state)[:, :2] - [0.3, 0.2])) < 1e-9
    np.testing.assert_allclose(res.u_applied[0], res.u_command[0], rtol=1e-12)


# ----------------------------------------------------------------------------- (c) quantised measurements


def test_the_law_reads_the_quantised_measurement():
    q = [0.01, 0.05]
    spec = _spec({"quantization": q}, duration=1.5)
    design = design_of(spec)
    res = simulate(spec, design)
    x, y = np.asarray(res.state), np.asarray(res.measured)
    own = np.round(x / np.asarray(q)) * np.asarray(q)
    ties = np.abs(np.abs(x / np.asarray(q) - np.floor(x / np.asarray(q))) - 0.5) < 1e-9  # rounding is ambiguous there
    assert np.all((np.abs(y - own) < 1e-12) | ties)
    assert len(np.unique(y[:, 0])) < len(np.unique(x[:, 0])) / 10  # a staircase, not the state
    K1, K2, K3, K4 = (float(design.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    xc = np.asarray(res.controller_state)[:, 0]
    u = -K1 * (own[:, 0] - 1.0) - K2 * own[:, 1] - K3 * xc + K3 * K4
    ok = ~np.any(ties, axis=1)
    np.testing.assert_allclose(res.u_command[ok, 0], u[ok], rtol=0, atol=1e-9)
    k = int(np.argmax(np.abs(x[:, 0] - own[:, 0])))  # a sample where quantising moves the measurement
    assert abs(x[k, 0] - own[k, 0]) > 1e-3 and abs(y[k, 0] - own[k, 0]) < 1e-12
    assert "measurements quantised to x1: 0.01 rad, x2: 0.05 rad/s" in res.settings["implementation"]


# ----------------------------------------------------------------------------- (d) computation delay


def test_the_computation_delay_is_the_simulation_delay():
    a = simulate(_spec({"delay": 0.01}, duration=1.5), design_of(_spec()))
    b = simulate(_spec(None, duration=1.5, delay=0.01), design_of(_spec()))
    assert a.settings["delay_steps"] == b.settings["delay_steps"] > 0
    np.testing.assert_array_equal(a.state, b.state)
    np.testing.assert_array_equal(a.u_applied, b.u_applied)
    assert "10 ms computation delay" in a.settings["implementation"]
    same = simulate(_spec({"delay": 0.01}, duration=1.5, delay=0.01), design_of(_spec()))  # the same value twice
    np.testing.assert_array_equal(same.state, b.state)


def test_the_same_sampling_period_in_both_sections_is_accepted():
    a = simulate(_spec({"sampling_period": 0.005}, duration=1.0, sampling_period=0.005), design_of(_spec()))
    b = simulate(_spec(None, duration=1.0, sampling_period=0.005), design_of(_spec()))
    np.testing.assert_array_equal(a.state, b.state)


def test_the_settings_say_what_the_verdict_is_on():
    impl = {"sampling_period": 1e-3, "delay": 2e-4, "quantization": 1e-4, "actuator": {"limit": 5, "bandwidth": 300}}
    res = build(_spec(impl, duration=1.0), design_of(_spec())).settings["implementation"]
    assert res == ("as implemented: sampled at 1 kHz (every 1 ms, the command held between samples), 0.2 ms "
                   "computation delay, measurements quantised to x1: 0.0001 rad, x2: 0.0001 rad/s, actuator limited "
                   "to ±5 N*m with a 300 rad/s first-order lag (time constant 3.333 ms)")


# ----------------------------------------------------------------------------- a switching law without the section


def test_a_switching_law_without_implementation_says_it_is_a_continuous_time_switch():
    spec = parse_spec((ROOT / "specs" / "sliding-mode-link.yaml").read_text().replace(
        "duration: 3.0", "duration: 0.5")).spec
    sim = build(spec, design_of(spec))
    words = sim.settings["scope"]
    assert "continuous-time switch" in words and "implementation" not in sim.settings
    rate = 1.0 / sim.settings["dt"]
    shown = float(words.split("integration step, at ")[1].split(" ")[0]) * (1e3 if " kHz" in words else 1.0)
    assert shown == pytest.approx(rate, rel=1e-3)
    linear = build(_spec(None, duration=1.0), design_of(_spec())).settings
    assert "scope" not in linear and "implementation" not in linear  # a continuous law has no such note
