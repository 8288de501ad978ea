"""The variable structure regulator's chatter predicted on the sampled link along sigma and measured on the run,
against numbers of our own."""

from __future__ import annotations

import numpy as np
import pytest

from tests.families.vsc.common import LINK_SPEC, check, run_text

SAMPLED = LINK_SPEC.read_text().replace("  duration: 3.0\n", "  duration: 3.0\n  sampling_period: 0.001\n")
KM, TAU = 2.0, 0.5


@pytest.fixture(scope="module")
def sampled():
    return run_text(SAMPLED)


def test_vsc_link_prediction_and_measurement(sampled):
    chat = check(sampled, "vsc_chattering")
    cyc = chat.certificate["limit_cycle"]
    pred, meas = cyc["predicted"], cyc["measured"]
    info = sampled.design.data
    sim = sampled.simulation
    t = np.asarray(sim.time)
    w = (t >= meas["window_s"][0]) & (t <= meas["window_s"][1])
    # the relay's amplitude on the window: delta and the structure switch's sum |alpha_i - beta_i|/2 |x~_i|, with
    # x~ = x - xD [1, 0] on the link (the rest state at the reference)
    xt = np.asarray(sim.state)[w] - np.outer(np.asarray(sim.reference[:, 0, 0])[w], [1.0, 0.0])
    h = np.abs(np.asarray(info.alpha) - np.asarray(info.beta)) / 2
    amplitude = float(info.delta) + float(np.mean(np.abs(xt) @ h))
    assert pred["kind"] == "sampled" and pred["half_period_samples"] == 1
    assert pred["frequency_hz"] == pytest.approx(500.0)
    assert pred["command_amplitude"] == pytest.approx(amplitude, rel=1e-9)
    # one sample at each sign: sigma' ~ b v, so sigma swings by +-b v Ts/2 (b = Km/tau)
    assert pred["s_amplitude"] == pytest.approx(KM / TAU * amplitude * 1e-3 / 2, rel=0.05)
    sigma = np.asarray(sim.signals["sigma"])[w]
    u = np.asarray(sim.u_command[:, 0])[w]
    flips = np.count_nonzero(np.diff(np.sign(sigma[sigma != 0])) != 0)
    assert meas["frequency_hz"] == pytest.approx(flips / 2 / (meas["window_s"][1] - meas["window_s"][0]))
    assert meas["chatter_amplitude"] == pytest.approx((u.max() - u.min()) / 2)
    # the settled orbit under the 1 N*m perturbation: the first-order estimate 500 (1 - r) Hz, r = |u_eq|/amplitude
    r = abs(meas["equivalent_control"]) / amplitude
    assert meas["frequency_hz"] == pytest.approx(500 * (1 - r), rel=0.05)
    assert "σ" in chat.detail and "500 Hz" in chat.detail
