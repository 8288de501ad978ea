"""The PID/sliding-mode link's chatter predicted on the sampled ``g/(p - p3)`` along slm and measured on the run,
against numbers of our own."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
SAMPLED = (ROOT / "specs" / "pid-sm-link.yaml").read_text().replace(
    "  duration: 3.0\n", "  duration: 3.0\n  sampling_period: 0.001\n")


@pytest.fixture(scope="module")
def sampled():
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    return run(parse_spec(SAMPLED))


def test_pid_sm_link_prediction_and_measurement(sampled):
    chat = next(c for c in sampled.checks if c.name == "pid_sm_chattering")
    cyc = chat.certificate["limit_cycle"]
    pred, meas = cyc["predicted"], cyc["measured"]
    info = sampled.design.data
    m, p3, g, ts = float(info.M), float(info.p3), float(info.g_nominal), 1e-3
    # slm_{j+1} = q slm_j - (g/|p3|)(1 - q) M sign(slm_j), q = exp(p3 Ts): the 2-periodic orbit
    # slm = +-(g/|p3|) M (1 - q)/(1 + q)
    q = math.exp(p3 * ts)
    assert pred["kind"] == "sampled" and pred["half_period_samples"] == 1
    assert pred["frequency_hz"] == pytest.approx(500.0)
    assert pred["s_amplitude"] == pytest.approx(g / abs(p3) * m * (1 - q) / (1 + q), rel=1e-9)
    assert pred["command_amplitude"] == pytest.approx(m)
    sim = sampled.simulation
    t = np.asarray(sim.time)
    a, b = meas["window_s"]
    w = (t >= a) & (t <= b)
    slm = np.asarray(sim.signals["slm"])[w]
    u = np.asarray(sim.u_command[:, 0])[w]
    flips = np.count_nonzero(np.diff(np.sign(slm[slm != 0])) != 0)
    assert meas["frequency_hz"] == pytest.approx(flips / 2 / (b - a))
    assert meas["chatter_amplitude"] == pytest.approx((u.max() - u.min()) / 2)
    # the load (0.5 N*m) biases the relay by r = |u_eq|/M: 500 (1 - r) Hz and the swing A (1 + r), to first order
    r = abs(meas["equivalent_control"]) / m
    assert meas["frequency_hz"] == pytest.approx(500 * (1 - r), rel=0.05)
    assert meas["s_amplitude"] == pytest.approx(pred["s_amplitude"] * (1 + r), rel=0.05)
    assert "slm" in chat.detail and "500 Hz" in chat.detail


LIMIT = 0.5
"""A chatter limit (N*m) below the relay M (about 5.7 N*m)."""


def _limited(text: str) -> str:
    return text.replace("steady_state_error: 0.005}", f"steady_state_error: 0.005, max_chatter_amplitude: {LIMIT}}}")


@pytest.mark.parametrize("text", [(ROOT / "specs" / "pid-sm-link.yaml").read_text(), SAMPLED],
                         ids=["continuous", "sampled"])
def test_requirement_fails_and_the_layer_fixes_it(text):
    """Over the limit: pid_sm_chattering is required and fails with the amplitude counted here (the whole command
    u = u0 + du on the window); the diagnosis proposes sat(slm/eps) whose re-run passes every required check, the
    chatter amplitude under the limit."""
    from designkit.analysis.diagnosis import diagnose
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    result = run(parse_spec(_limited(text)))
    chat = next(c for c in result.checks if c.name == "pid_sm_chattering")
    meas = chat.certificate["limit_cycle"]["measured"]
    sim = result.simulation
    t = np.asarray(sim.time)
    w = (t >= meas["window_s"][0]) & (t <= meas["window_s"][1])
    u = np.asarray(sim.u_command[:, 0])[w]
    assert chat.required and chat.passed is False
    assert chat.achieved == pytest.approx((u.max() - u.min()) / 2) and chat.achieved > LIMIT
    m = float(result.design.data.M)
    # the relay switches by M; the PID part u0 follows the chatter of the state by a few per cent more (sampled)
    assert 0.99 * m <= chat.achieved <= 1.05 * m
    d = diagnose(result)
    finding = next(f for f in d.findings if f.check == "pid_sm_chattering")
    assert "controller.epsilon" in finding.fix and "critical gain" in finding.fix
    trials = [tr for p in d.proposed for tr in p.trials if tr.remedy.changes[0][0] == "controller.epsilon"]
    assert len(trials) == 1 and trials[0].passed and not trials[0].error, trials
    again = next(o for o in trials[0].outcomes if o.name == "pid_sm_chattering")
    assert again.failed_before and again.value is not None and again.value < 0.01 * LIMIT
    # the layer's gain M/eps at most half the critical gain of the held g/(p - p3) at the largest g on the box
    # (a2 Km/tau up to a2 2.6/0.35): for |p3| h small it is stable below 2/(g h)
    eps = trials[0].remedy.changes[0][1]
    hold = float(sim.settings.get("sampling_period") or sim.settings["dt"])
    g_max = float(result.design.data.a2) * 2.6 / 0.35
    assert m / eps <= 0.5 * 2 / (g_max * hold) * 1.05


@pytest.mark.parametrize("where", ["elastic", "robot"])
def test_requirement_refused_off_the_link(where):
    """Measured on the link only: on the elastic joint and the robot the key is refused, named (exit code 2)."""
    from designkit.errors import SpecError
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec
    from tests.families.pid_sliding_mode.cases import ROBOT
    from tests.families.pid_sliding_mode.test_elastic import SPEC

    body = (SPEC.replace("requirements: {", "requirements: {max_chatter_amplitude: 1.0, ", 1) if where == "elastic"
            else ROBOT.replace("simulation:", "requirements: {max_chatter_amplitude: 1.0}\nsimulation:", 1))
    assert "max_chatter_amplitude" in body
    with pytest.raises(SpecError, match="requirements.max_chatter_amplitude"):
        run(parse_spec(body))
