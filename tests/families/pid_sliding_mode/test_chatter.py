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
