"""The sliding-mode servo's chatter: predicted on the sampled link along s, measured on the run with counts of our
own, ``requirements.max_chatter_amplitude`` checked, and the boundary layer the diagnosis proposes re-simulated."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.errors import SpecError
from tests.families.sliding_mode.common import LINK_SPEC, check, run_text

SAMPLED = LINK_SPEC.read_text().replace("  duration: 3.0\n", "  duration: 3.0\n  sampling_period: 0.001\n")
LIMITED = SAMPLED.replace("steady_state_error: 0.005}", "steady_state_error: 0.005, max_chatter_amplitude: 0.5}")
KM, TAU, C = 2.0, 0.5, 5.0


@pytest.fixture(scope="module")
def sampled():
    return run_text(SAMPLED)


@pytest.fixture(scope="module")
def limited():
    return run_text(LIMITED)


def test_prediction_on_the_sampled_link(sampled):
    chat = check(sampled, "chattering")
    pred = chat.certificate["limit_cycle"]["predicted"]
    meas = chat.certificate["limit_cycle"]["measured"]
    g = sampled.design.gains
    # the relay's amplitude on the window: M and the structure switch's (alpha - beta)/2 |e|, e from the run
    sim = sampled.simulation
    t = np.asarray(sim.time)
    w = (t >= meas["window_s"][0]) & (t <= meas["window_s"][1])
    e = (np.asarray(sim.state[:, 0]) - np.asarray(sim.reference[:, 0, 0]))[w]
    m = float(g["M"]) + (float(g["alpha"]) - float(g["beta"])) / 2 * float(np.mean(np.abs(e)))
    # one sample at each sign: 1/(2 Ts); at that speed the link along s is s' ~ b v (b = Km/tau), so s swings by
    # b M Ts about 0: +-b M Ts/2, the a x2 and c e terms a few per cent of it over one sample
    assert pred["kind"] == "sampled" and pred["half_period_samples"] == 1
    assert pred["frequency_hz"] == pytest.approx(500.0)
    assert pred["s_amplitude"] == pytest.approx(KM / TAU * m * 1e-3 / 2, rel=0.03)
    assert pred["command_amplitude"] == pytest.approx(m)
    assert "500 Hz" in chat.detail and "N·m" in chat.detail and chat.required is False


def test_measured_against_counts_of_our_own(sampled):
    chat = check(sampled, "chattering")
    meas = chat.certificate["limit_cycle"]["measured"]
    sim = sampled.simulation
    t = np.asarray(sim.time)
    a, b = meas["window_s"]
    w = (t >= a) & (t <= b)
    s = np.asarray(sim.signals["s"])[w]
    u = np.asarray(sim.u_command[:, 0])[w]
    flips = np.count_nonzero(np.diff(np.sign(s[s != 0])) != 0)
    assert meas["frequency_hz"] == pytest.approx(flips / 2 / (b - a))
    assert meas["chatter_amplitude"] == pytest.approx((u.max() - u.min()) / 2)
    m = float(sampled.design.gains["M"])
    # the relay switches by M about the equivalent control (-psi e and the perturbation, 1 N*m from t = 1 s)
    assert meas["chatter_amplitude"] == pytest.approx(m, rel=0.01)
    assert meas["equivalent_control"] == pytest.approx(-1.0, abs=0.02)
    # the settled orbit is asymmetric: with r = |u_eq|/M the minority side keeps its one sample and the other
    # lengthens to (1 + r)/(1 - r): the frequency is 500 (1 - r) Hz
    r = abs(meas["equivalent_control"]) / m
    assert meas["frequency_hz"] == pytest.approx(500 * (1 - r), rel=0.05)
    assert meas["s_amplitude"] == pytest.approx(KM / TAU * m * 1e-3 / 2 * (1 + r), rel=0.15)


def test_continuous_switch_has_no_finite_cycle(link_result):
    chat = check(link_result, "chattering")
    assert chat.certificate["limit_cycle"]["predicted"]["kind"] == "none"
    assert "no finite limit cycle" in chat.detail and "integration step" in chat.detail


def test_requirement_fails_with_the_relay_and_the_layer_fixes_it(limited):
    from designkit.analysis.diagnosis import diagnose

    chat = check(limited, "chattering")
    m = float(limited.design.gains["M"])
    assert chat.required and chat.passed is False
    assert chat.achieved == pytest.approx(m, rel=0.01) and chat.margin == pytest.approx(0.5 - chat.achieved)
    d = diagnose(limited)
    finding = next(f for f in d.findings if f.check == "chattering")
    assert "boundary layer" in finding.fix
    trials = [t for p in d.proposed for t in p.trials if t.remedy.changes[0][0] == "controller.boundary_layer"]
    assert len(trials) == 1 and trials[0].passed, trials
    eps = trials[0].remedy.changes[0][1]
    # the layer's gain M/eps at most half the critical gain of the held link at the box's fastest corner
    # (b = 2.6/0.35): s' ~ b v held over Ts is stable for gains below 2/(b Ts)
    assert m / eps <= 0.5 * 2 / (2.6 / 0.35 * 1e-3) * 1.02
    # the re-simulated run, measured by our own pipeline run: the command settles (no chatter left)
    fixed = run_text(LIMITED.replace("  margin: 0.2\n", f"  margin: 0.2\n  boundary_layer: {eps}\n"))
    again = check(fixed, "chattering")
    assert again.passed and again.achieved < 0.01 * m
    assert all(c.passed is not False for c in fixed.checks if c.required)


def test_requirement_refused_by_a_family_that_does_not_measure_it():
    from designkit.schema.loader import parse_spec

    body = (LINK_SPEC.parent / "infeasible-requirements.yaml").read_text()
    body = body.replace("requirements: {", "requirements: {max_chatter_amplitude: 1.0, ", 1)
    assert "max_chatter_amplitude" in body
    with pytest.raises(SpecError, match="requirements.max_chatter_amplitude"):
        parse_spec(body)


@pytest.mark.slow
def test_continuous_switch_layer_keeps_the_step_and_the_error():
    """Without a hold the relay has no finite cycle; the layer proposed keeps the required steady-state error:
    inside it |e| -> eps sup|xi|/(M c), at most half the requirement."""
    from designkit.analysis.diagnosis import diagnose

    text = LINK_SPEC.read_text().replace("steady_state_error: 0.005}",
                                         "steady_state_error: 0.005, max_chatter_amplitude: 0.5}")
    result = run_text(text)
    assert check(result, "chattering").passed is False
    d = diagnose(result)
    trials = [t for p in d.proposed for t in p.trials if t.remedy.changes[0][0] == "controller.boundary_layer"]
    assert len(trials) == 1 and trials[0].passed, trials
    eps = trials[0].remedy.changes[0][1]
    m, c, xi = float(result.design.gains["M"]), 5.0, 1.0
    assert eps * xi / (m * c) <= 0.5 * 0.005 * (1 + 1e-3)
    assert "no finite limit cycle" in next(f for f in d.findings if f.check == "chattering").cause


LAGGED = (LINK_SPEC.read_text().replace("  duration: 3.0\n", "  duration: 1.5\n")
          .replace("  perturbation: {value: 1.0, time: 1.0}\n", "")
          .replace("  margin: 0.2\n", "  margin: 0.2\n  perturbation_bound: 1.0\n")
          .replace("requirements:", "implementation: {delay: 0.0005, actuator: {bandwidth: 300}}\nrequirements:"))


def test_continuous_relay_behind_the_lag_and_a_delay():
    """The law computed continuously, applied 0.5 ms late through a 300 rad/s lag, no load (the equivalent control
    near 0, the orbit symmetric): the exact orbit of the loop with the lag and the delay is predicted; the run
    reads sign(s) at each step dt, so it switches between L and L + dt after s crosses 0: its frequency and
    swings, counted here on the run's own signals, lie between the exact orbits for those two delays (1 % slack
    for the sampled peaks), and so does our own RK4 run of the same loop."""
    from designkit.families.sliding_mode.chatter import loop_of
    from designkit.verification.limit_cycle import continuous_orbit
    from tests.verification.helpers import rk4_relay_lag

    result = run_text(LAGGED)
    chat = check(result, "chattering")
    cyc = chat.certificate["limit_cycle"]
    pred, meas = cyc["predicted"], cyc["measured"]
    assert pred["kind"] == "continuous" and cyc["compared"] and cyc["actuator_bandwidth_rad_s"] == 300.0
    sim = result.simulation
    dt = float(sim.settings["dt"])
    t = np.asarray(sim.time)
    a, b = meas["window_s"]
    w = (t >= a) & (t <= b)
    s, ua, tw = np.asarray(sim.signals["s"])[w], np.asarray(sim.u_applied[:, 0])[w], t[w]
    up = np.flatnonzero((s[:-1] < 0) & (s[1:] >= 0))
    freq = (len(up) - 1) / (tw[up[-1]] - tw[up[0]])
    assert abs(meas["equivalent_control"]) < 0.05
    # the relay's amplitude on the window: M and the structure switch's (alpha - beta)/2 mean|e|
    g = result.design.gains
    e = (np.asarray(sim.state[:, 0]) - np.asarray(sim.reference[:, 0, 0]))[w]
    m = float(g["M"]) + (float(g["alpha"]) - float(g["beta"])) / 2 * float(np.mean(np.abs(e)))
    loop = loop_of(KM, TAU, C).with_lag(300.0)
    on_time, late = (continuous_orbit(loop, m, delay=d) for d in (5e-4, 5e-4 + dt))
    assert pred["frequency_hz"] == pytest.approx(on_time.frequency, rel=1e-9)
    assert pred["command_amplitude"] == pytest.approx(on_time.peak("actuator"), rel=1e-9)
    assert late.frequency * 0.99 <= freq <= on_time.frequency * 1.01
    assert on_time.amplitude * 0.99 <= meas["s_amplitude"] <= late.amplitude * 1.01
    assert on_time.peak("actuator") * 0.99 <= float(np.ptp(ua)) / 2 <= late.peak("actuator") * 1.01
    own_f, own_s, own_ua = rk4_relay_lag(1 / TAU, KM / TAU, C, m, 300.0, dt, 5e-4, 0.4)
    assert own_f == pytest.approx(freq, rel=0.02) and own_ua == pytest.approx(float(np.ptp(ua)) / 2, rel=0.02)
    assert "112.9 Hz" in chat.detail and "300 rad/s" in chat.detail


def test_lag_alone_predicts_no_finite_cycle():
    """The lag without a delay: the link along s behind it has relative degree two, so no finite orbit; the words
    name the run's step as what sets the chatter."""
    result = run_text(LAGGED.replace("delay: 0.0005, ", ""))
    chat = check(result, "chattering")
    cyc = chat.certificate["limit_cycle"]
    assert cyc["predicted"]["kind"] == "none" and cyc["compared"] and cyc["actuator_bandwidth_rad_s"] == 300.0
    assert "relative degree two" in chat.detail and f"{float(result.simulation.settings['dt']):.3g} s" in chat.detail
