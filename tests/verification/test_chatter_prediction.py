"""The chatter predicted for a relay loop held as a run holds it (:mod:`designkit.verification.chatter_prediction`),
against a NumPy/scipy simulation of our own of the sampled relay and the actuator lag."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.signal import cont2discrete

from designkit.verification.chatter_prediction import (
    ChatterMeasured,
    Timing,
    layer_fix,
    measure,
    predict,
    timing_of,
    words,
)
from designkit.verification.limit_cycle import Loop
from tests.verification.helpers import rk4_relay_lag

A_, B_, C_ = 2.0, 4.0, 5.0
"""The link along s = x2 + c e: b (p + c)/(p (p + a)), a = 1/tau, b = Km/tau."""


def link() -> Loop:
    return Loop.of([[0, 1], [0, -A_]], [0, B_], [C_, 1], {"output": [1, 0]})


def _relay_and_lag(m: float, ts: float, bandwidth: float, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """``s = 3/((p + 0.5)(p + 1)(p + 2)) u_a`` behind ``u_a' = bandwidth (v - u_a)``, ``v = -M sign(s_j)`` computed
    every ``ts`` and held: the augmented state (companion form, lag last) written here, stepped by scipy's
    ``cont2discrete``; returns ``s_j`` and ``u_a`` at the samples."""
    a = np.array([[0, 1, 0, 0], [0, 0, 1, 0], [-1, -3.5, -3.5, 1], [0, 0, 0, -bandwidth]], float)
    b = np.array([[0], [0], [0], [bandwidth]], float)
    ad, bd, *_ = cont2discrete((a, b, np.eye(4), np.zeros((4, 1))), ts)
    x = np.array([0.01, 0.0, 0.0, 0.0])
    s_out, ua = [], []
    for _ in range(samples):
        s = 3 * x[0]
        s_out.append(s)
        ua.append(x[3])
        x = ad @ x + bd[:, 0] * (-m * np.sign(s))
    return np.array(s_out), np.array(ua)


def test_sampled_relay_behind_a_lag_against_own_simulation():
    from designkit.verification.limit_cycle import sampled_orbits

    m, ts, bw = 1.0, 0.1, 5.0
    s, ua = _relay_and_lag(m, ts, bw, 3000)
    tail = s[-1000:]
    n = next(n for n in range(1, 400) if np.max(np.abs(tail[n:] - tail[:-n])) < 1e-10)
    loop = Loop.transfer([3.0], [1, 3.5, 3.5, 1])
    orbits = {2 * o.half_period: o for o in sampled_orbits(loop.with_lag(bw), m, ts)}
    assert n in orbits, (n, sorted(orbits))
    # the lag's output is monotone over a sample: its peak on the orbit is the run's, to round-off, below M
    assert orbits[n].peak("actuator") == pytest.approx(float(np.max(np.abs(ua[-n:]))), rel=1e-9)
    assert orbits[n].peak("actuator") < m
    pred = predict(loop, m, Timing(ts, 0.0, bw, True, ts / 10), "rad", "N·m")
    smallest = min(orbits)
    assert pred.kind == "sampled" and 2 * pred.half_period == smallest
    assert pred.command == pytest.approx(orbits[smallest].peak("actuator"), rel=1e-12)
    assert pred.frequency == pytest.approx(1 / (smallest * ts))


def test_no_hold_no_lag_no_cycle():
    pred = predict(link(), 1.2, Timing(0.0, 0.0, None, False, 5e-5), "rad/s", "N·m")
    assert pred.kind == "none" and pred.frequency is None
    assert "no finite limit cycle" in pred.sentence and "5e-05 s" in pred.sentence


def test_continuous_delay_uses_the_exact_orbit():
    # the first-order K/(T p + 1) with a delay L: |s| = K M (1 - exp(-L/T)) (tests/verification/test_limit_cycle.py)
    loop = Loop.of([[-2.0]], [4.0], [1.0])
    pred = predict(loop, 1.0, Timing(0.0, 0.1, None, False, 1e-4), "rad", "N·m")
    assert pred.kind == "continuous"
    assert pred.s_amplitude == pytest.approx(2.0 * (1 - math.exp(-0.2)), rel=1e-6)


def test_measure_counts_of_our_own():
    t = np.arange(0, 1.0, 1e-3)
    u = np.where((np.arange(t.size) // 3) % 2 == 0, 1.5, -0.5)  # 3 samples high, 3 low: 1/6e-3 Hz
    s = -u + 0.5
    m = measure(t, s, u)
    assert m.command == pytest.approx(1.0) and m.equivalent == pytest.approx(np.mean(u))
    assert m.s_amplitude == pytest.approx(1.0)
    # a drift across the window does not enter the half swing: +-1 about a mean drifting by 0.5 (half the
    # peak-to-peak would be 1.25)
    drift = np.where(s > 0, 1.0, -1.0) + 0.5 * t
    assert measure(t, drift, u).s_amplitude == pytest.approx(1.0, abs=0.01)
    changes = int(np.count_nonzero(np.diff(np.sign(s)) != 0))
    assert m.frequency == pytest.approx(changes / 2 / (t[-1] - t[0]))


def test_lag_not_in_the_run_is_not_compared():
    pred = predict(link(), 1.2, Timing(1e-3, 0.0, 300.0, False, 1e-4), "rad/s", "N·m")
    meas = ChatterMeasured(0.0, 1.0, 1e-3, 1.0, 100.0, 0.0)
    assert "not compared" in words(pred, meas, 1.2, "rad/s", "N·m", compared=False)
    assert "not compared" not in words(pred, meas, 1.2, "rad/s", "N·m", compared=True)


def test_timing_reads_the_run_and_the_implementation():
    sim = SimpleNamespace(settings={"dt": 1e-4, "sampling_period": 1e-3, "delay": 0.0})
    spec = SimpleNamespace(implementation=SimpleNamespace(actuator=SimpleNamespace(bandwidth=[200.0])))
    t = timing_of(spec, sim)
    assert (t.period, t.bandwidth, t.lag_in_run) == (1e-3, 200.0, False)
    sim.settings["implementation"] = "as implemented: sampled every 1 ms, a 200 rad/s first-order lag"
    assert timing_of(spec, sim).lag_in_run


def test_layer_fix_on_the_held_link():
    # at the chatter's frequency the link is s' ~ b v: the held gain K is critical near 2/(b Ts) (exact for a = 0)
    ts, m = 1e-3, 1.2
    eps, k_c = layer_fix([link()], m, Timing(ts, 0.0, None, False, 1e-4))
    assert k_c == pytest.approx(2 / (B_ * ts), rel=0.02)
    assert eps == pytest.approx(m / (0.5 * k_c), rel=1e-12)
    # the linear loop at the layer's gain is stable: our own discretisation, closed with v = -(M/eps) s
    a = np.array([[0, 1], [0, -A_]])
    ad, bd, *_ = cont2discrete((a, np.array([[0], [B_]]), np.array([[C_, 1]]), np.zeros((1, 1))), ts)
    closed = ad - bd @ np.array([[C_, 1]]) * (m / eps)
    assert np.max(np.abs(np.linalg.eigvals(closed))) < 1
    closed = ad - bd @ np.array([[C_, 1]]) * (1.05 * k_c)
    assert np.max(np.abs(np.linalg.eigvals(closed))) > 1


def _rk4_relay_lag(bandwidth: float, dt: float, delay: float, span: float) -> tuple[float, float, float]:
    return rk4_relay_lag(A_, B_, C_, 1.2, bandwidth, dt, delay, span)


def test_continuous_lag_and_delay_exact_orbit_against_own_run():
    """A continuous relay behind a 300 rad/s lag with a 0.5 ms delay: our RK4 run reads sign(s) at the start of
    each 20 µs step, so it switches between L and L + dt after s crosses 0; its frequency and swings lie between
    the exact orbits for those two delays (0.5 % slack for the sampled peaks).  The describing function is the
    approximation: 6 % off the exact orbit here."""
    from designkit.verification.limit_cycle import continuous_orbit, describing_function

    dt, late = 2e-5, 5e-4
    pred = predict(link(), 1.2, Timing(0.0, late, 300.0, True, dt), "rad/s", "N·m")
    assert pred.kind == "continuous"
    slow = continuous_orbit(link().with_lag(300.0), 1.2, delay=late + dt)
    f, s_amp, ua_amp = _rk4_relay_lag(300.0, dt, late, 0.4)
    assert slow.frequency * 0.995 <= f <= pred.frequency * 1.005
    assert pred.s_amplitude * 0.995 <= s_amp <= slow.amplitude * 1.005
    assert pred.command * 0.995 <= ua_amp <= slow.peak("actuator") * 1.005
    df = describing_function(link().with_lag(300.0), 1.2, delay=late)
    assert df.hertz == pytest.approx(pred.frequency, rel=0.10) and df.hertz != pytest.approx(pred.frequency, rel=0.02)


def test_lag_alone_has_no_finite_cycle_and_the_step_sets_the_chatter():
    """Relative degree two (the link along s behind the lag): no orbit predicted; in our own RK4 run the frequency
    grows and the swing of s shrinks as the step shrinks (no finite cycle the step would converge to)."""
    pred = predict(link(), 1.2, Timing(0.0, 0.0, 300.0, True, 2e-5), "rad/s", "N·m")
    assert pred.kind == "none" and "relative degree two" in pred.sentence and "2e-05 s" in pred.sentence
    coarse, fine = _rk4_relay_lag(300.0, 4e-5, 0.0, 0.2), _rk4_relay_lag(300.0, 1e-5, 0.0, 0.2)
    assert fine[0] > 1.5 * coarse[0] and fine[1] < 0.5 * coarse[1]


def test_bias_estimate_only_for_the_sampled_orbit():
    """Behind a lag and a delay the load's equivalent control does not scale the orbit by (1 - r): the words say
    the orbit is not the symmetric one rather than give the held-integrator estimate."""
    meas = ChatterMeasured(0.0, 1.0, 3e-3, 1.2, 57.0, -1.0)
    lagged = predict(link(), 1.2, Timing(0.0, 5e-4, 300.0, True, 2e-5), "rad/s", "N·m")
    said = words(lagged, meas, 1.2, "rad/s", "N·m")
    assert "not the symmetric one" in said and "first-order estimate is" not in said
    held = predict(link(), 1.2, Timing(1e-3, 0.0, None, False, 1e-4), "rad/s", "N·m")
    assert f"first-order estimate is {held.frequency * (1 - 1 / 1.2):.4g} Hz" in words(held, meas, 1.2, "rad/s", "N·m")
