"""Time-domain metrics against python-control's step_info, and requirement checks that can fail."""

from __future__ import annotations

import control
import numpy as np
import pytest
from hypothesis import assume, given, settings

from designkit.families import pid_servo
from designkit.models.link import LinkPlant
from designkit.schema.spec import Requirements
from designkit.verification.time_domain import response_metrics, time_domain_checks
from tests.verification.helpers import pole_sets, real_pole, step_result

PLANT = LinkPlant(Km=2.0, tau=0.5)


def _linear_step(design, amplitude=1.0, n=6001):
    """Step response of the linear servo (x1 and u) as a SimulationResult, via python-control."""
    sys = design.closed_loop.to_control()
    slowest = min(abs(p.real) for p in design.poles)
    T = np.linspace(0.0, 20.0 / slowest, n)
    resp = control.step_response(sys, T=T, input=0)
    y = np.asarray(resp.outputs).reshape(2, -1)
    x1, u = amplitude * y[0], amplitude * y[1]
    return sys, T, step_result(T, x1, u, amplitude=amplitude)


@settings(max_examples=25, deadline=None)
@given(poles=pole_sets(), zero=real_pole)
def test_step_metrics_match_step_info(poles, zero):
    design = pid_servo.design(PLANT, poles, zero)
    sys, T, sim = _linear_step(design)
    info = control.step_info(sys[0, 0], T=T)
    m = response_metrics(sim)
    dt = T[1] - T[0]
    assume(np.isfinite(info["SettlingTime"]))
    # overshoot: same sample maximum, relative to the commanded step (DC gain is 1)
    assert m.overshoot == pytest.approx(info["Overshoot"], abs=1e-6)
    # crossing instants are interpolated here, taken at the next sample by step_info
    assert abs(m.rise_time - info["RiseTime"]) <= dt + 1e-12
    assert abs(m.settling_time - info["SettlingTime"]) <= dt + 1e-12
    times = np.asarray(T)
    window = times >= times[-1] - 0.05 * (times[-1] - times[0])
    assert m.steady_state_error == pytest.approx(np.mean(np.abs(sim.position[window] - 1.0)), rel=1e-12)
    assert m.steady_state_error < 1e-3
    assert m.peak_u_command == pytest.approx(np.max(np.abs(sim.u_command)))


@pytest.mark.parametrize("amplitude", [1.0, -0.5, 3.0])
def test_metrics_are_relative_to_the_commanded_step(amplitude):
    design = pid_servo.design(PLANT, [-2 + 3j, -2 - 3j, -10], -10.0)
    _, _, sim1 = _linear_step(design, 1.0)
    _, _, sima = _linear_step(design, amplitude)
    m1, ma = response_metrics(sim1), response_metrics(sima)
    assert ma.overshoot == pytest.approx(m1.overshoot, rel=1e-9)
    assert ma.rise_time == pytest.approx(m1.rise_time, rel=1e-9)
    assert ma.settling_time == pytest.approx(m1.settling_time, rel=1e-9)
    assert ma.peak_u_command == pytest.approx(abs(amplitude) * m1.peak_u_command, rel=1e-9)


def test_checks_have_targets_margins_and_fail_when_violated():
    design = pid_servo.design(PLANT, [-2 + 3j, -2 - 3j, -10], -10.0)  # zeta = 0.55: ~12.6 % overshoot
    _, _, sim = _linear_step(design)
    m = response_metrics(sim)
    req = Requirements(overshoot=10, settling_time=5.0, rise_time=1.0, steady_state_error=1e-3,
                       max_control=m.peak_u_command * 0.9)
    checks = {c.name: c for c in time_domain_checks(req, sim)}
    assert list(checks) == ["overshoot", "settling_time", "rise_time", "steady_state_error", "max_control"]
    assert checks["overshoot"].passed is False
    assert checks["overshoot"].margin == pytest.approx(10 - m.overshoot)
    assert checks["overshoot"].target == "<= 10 %"
    assert "exceeds" in checks["overshoot"].detail
    assert checks["settling_time"].passed is True and checks["settling_time"].margin > 0
    assert checks["rise_time"].passed is True
    assert checks["steady_state_error"].passed is True
    assert checks["max_control"].passed is False and checks["max_control"].unit == "N*m"


def test_never_settling_is_an_undefined_metric_and_fails():
    T = np.linspace(0.0, 2.0, 201)
    x1 = 1.0 - np.exp(-T) * np.cos(20 * T)  # still oscillating by 13 % at the end
    sim = step_result(T, x1, np.zeros_like(T))
    req = Requirements(settling_time=10.0, rise_time=5.0)
    checks = {c.name: c for c in time_domain_checks(req, sim)}
    assert checks["settling_time"].passed is False
    assert checks["settling_time"].achieved is None
    assert "undefined" in checks["settling_time"].detail and "end of the run" in checks["settling_time"].detail


def test_never_rising_fails():
    T = np.linspace(0.0, 1.0, 101)
    sim = step_result(T, 0.5 * (1 - np.exp(-5 * T)), np.zeros_like(T))
    c = time_domain_checks(Requirements(rise_time=10.0), sim)[0]
    assert c.passed is False and "never reaches 90 %" in c.detail


def test_zero_step_and_diverged_runs_fail_with_a_reason():
    T = np.linspace(0.0, 1.0, 11)
    zero = step_result(T, np.zeros_like(T), np.zeros_like(T), amplitude=0.0)
    assert time_domain_checks(Requirements(overshoot=5), zero)[0].passed is False
    bad = step_result(T, np.where(T > 0.5, np.nan, T), np.zeros_like(T))
    c = time_domain_checks(Requirements(overshoot=5, steady_state_error=1.0), bad)
    assert all(x.passed is False for x in c)
    assert "not finite" in c[0].detail


def test_max_control_bounds_the_commanded_not_the_saturated_control():
    T = np.linspace(0.0, 1.0, 101)
    u = 50.0 * np.exp(-10 * T)
    sim = step_result(T, 1 - np.exp(-10 * T), u, u_applied=np.clip(u, -5.0, 5.0))
    c = time_domain_checks(Requirements(max_control=10.0), sim)[0]
    assert c.passed is False and c.achieved == pytest.approx(50.0)
    assert c.certificate["peak_u_applied"] == pytest.approx(5.0)


def test_steady_state_error_is_averaged_over_the_last_five_percent():
    T = np.linspace(0.0, 10.0, 1001)
    x1 = np.where(T >= 9.5, 1.02, 1.0)
    m = response_metrics(step_result(T, x1, np.zeros_like(T)))
    assert m.steady_state_error == pytest.approx(0.02)


def test_trajectory_runs_use_tracking_error():
    T = np.linspace(0.0, 2.0, 2001)
    s = np.clip(T, 0.0, 1.0)
    xd = 10 * s**3 - 15 * s**4 + 6 * s**5  # quintic rest-to-rest, 1 rad in 1 s
    ref = np.column_stack([xd, np.gradient(xd, T), np.gradient(np.gradient(xd, T), T)])
    err = 0.03 * np.sin(np.pi * s) * (T <= 1.0) + 1e-4
    sim = step_result(T, xd + err, np.ones_like(T), kind="trajectory", reference=ref)
    req = Requirements(overshoot=5.0, rise_time=0.5, steady_state_error=1e-3, settling_time=1.5)
    checks = {c.name: c for c in time_domain_checks(req, sim)}
    assert checks["overshoot"].achieved == pytest.approx(3.01, rel=1e-3)  # max |e| / move, %
    assert checks["overshoot"].passed is True
    assert checks["rise_time"].passed is False and "trajectory" in checks["rise_time"].detail
    assert checks["steady_state_error"].achieved == pytest.approx(1e-4)
    assert checks["settling_time"].passed is True
    # |e| = 0.03 sin(pi t) + 1e-4 last enters 2 % of the 1 rad move at t = 1 - asin(0.0199/0.03)/pi
    expected = 1.0 - np.arcsin((0.02 - 1e-4) / 0.03) / np.pi
    assert checks["settling_time"].achieved == pytest.approx(expected, abs=T[1] - T[0])
