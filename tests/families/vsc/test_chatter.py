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


LIMIT = 0.5
"""A chatter limit (N*m) below the relay's delta = 1.2 N*m."""


def _limited(text: str) -> str:
    return text.replace("steady_state_error: 0.005}", f"steady_state_error: 0.005, max_chatter_amplitude: {LIMIT}}}")


@pytest.mark.parametrize("text", [LINK_SPEC.read_text(), SAMPLED], ids=["continuous", "sampled"])
def test_requirement_fails_and_the_layer_fixes_it(text):
    """Over the limit: the chattering check is required and fails with the amplitude counted here; the diagnosis
    proposes a boundary layer whose re-run passes every required check, the chatter amplitude under the limit."""
    from designkit.analysis.diagnosis import diagnose

    result = run_text(_limited(text))
    chat = check(result, "vsc_chattering")
    meas = chat.certificate["limit_cycle"]["measured"]
    sim = result.simulation
    t = np.asarray(sim.time)
    w = (t >= meas["window_s"][0]) & (t <= meas["window_s"][1])
    u = np.asarray(sim.u_command[:, 0])[w]
    assert chat.required and chat.passed is False and chat.unit == "N*m"
    assert chat.achieved == pytest.approx((u.max() - u.min()) / 2) and chat.achieved > LIMIT
    assert chat.achieved == pytest.approx(float(result.design.data.delta), rel=0.02)
    d = diagnose(result)
    finding = next(f for f in d.findings if f.check == "vsc_chattering")
    assert "boundary layer" in finding.fix and "critical gain" in finding.fix
    trials = [tr for p in d.proposed for tr in p.trials if tr.remedy.changes[0][0] == "controller.boundary_layer"]
    assert len(trials) == 1 and trials[0].passed and not trials[0].error, trials
    again = next(o for o in trials[0].outcomes if o.name == "vsc_chattering")
    assert again.failed_before and again.value is not None and again.value < 0.01 * LIMIT
    # the layer's gain delta/eps at most half the critical gain of the held loop at the box's fastest corner:
    # sigma' ~ b v over a hold h (b = Km/tau up to 2.6/0.35) is stable for gains below 2/(b h)
    eps = trials[0].remedy.changes[0][1]
    hold = float(sim.settings.get("sampling_period") or sim.settings["dt"])
    assert float(result.design.data.delta) / eps <= 0.5 * 2 / (2.6 / 0.35 * hold) * 1.05


def test_requirement_not_read_without_it():
    result = run_text(LINK_SPEC.read_text())
    chat = check(result, "vsc_chattering")
    assert chat.required is False and "limit" not in chat.certificate
