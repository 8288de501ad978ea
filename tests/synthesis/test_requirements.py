"""Poles from overshoot and settling time, checked on exact second-order responses."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.families import synthesize
from designkit.schema.loader import parse_spec
from designkit.synthesis.requirements import damping_from_overshoot, dominant_poles


@given(st.floats(min_value=0.5, max_value=60.0))
@settings(max_examples=40, deadline=None)
def test_damping_reproduces_overshoot(overshoot):
    zeta = damping_from_overshoot(overshoot)
    wn = 3.0
    sys = control.tf([wn**2], [1, 2 * zeta * wn, wn**2])
    t = np.linspace(0, 5, 10001)  # the peak comes before 2.1 s for any overshoot >= 0.5 % at wn = 3 rad/s
    y = control.step_response(sys, T=t).outputs
    assert np.argmax(y) < t.size - 1
    assert 100 * (np.max(y) - 1) == pytest.approx(overshoot, rel=1e-3, abs=1e-3)


@given(st.floats(min_value=0.0, max_value=40.0), st.floats(min_value=0.2, max_value=5.0))
@settings(max_examples=30, deadline=None)
def test_settling_time_bound_holds_for_the_dominant_pair(overshoot, ts):
    dom = dominant_poles(overshoot, ts)
    p1 = dom.poles[0]
    sys = control.zpk([], [p1, p1.conjugate()], abs(p1) ** 2)
    t = np.linspace(0, 3 * ts, 30001)
    y = control.step_response(sys, T=t).outputs
    outside = np.nonzero(np.abs(y - 1) > 0.02)[0]
    settling = t[outside[-1] + 1] if outside.size else 0.0
    assert settling == pytest.approx(ts, rel=2e-3)
    assert dom.poles[2].real == pytest.approx(5 * p1.real)


def test_requirements_driven_servo_cancels_third_pole():
    spec = parse_spec(
        "name: r\nplant: {kind: link, Km: 2.0, tau: 0.5}\ncontroller: {kind: pid_servo}\n"
        "requirements: {overshoot: 5, settling_time: 1.5}\n"
    ).spec
    design = synthesize(spec)
    assert design.zeros[0].real == pytest.approx(design.poles[2].real)
    mp = 0.9 * 0.05  # design margin 0.1 tightens the 5 % requirement
    assert design.extra["zeta"] == pytest.approx(-math.log(mp) / math.sqrt(math.pi**2 + math.log(mp) ** 2))
    tf = control.ss2tf(design.closed_loop.to_control()[0, 0])
    info = control.step_info(tf, T=np.linspace(0, 6, 60001), SettlingTimeThreshold=0.02)
    assert info["Overshoot"] == pytest.approx(4.5, rel=1e-3)
    assert info["SettlingTime"] == pytest.approx(0.9 * 1.5, rel=1e-3)
