"""The PID families on linear plants: the example specs against independent computations.

Independent routes: the closed-loop poles of python-control's ``feedback(C P, 1)`` with the PID written as the
transfer function ``C(s) = K1 + K2 s + K3/s`` (the rate ``c A x`` is ``y'`` on these all-pole plants); the run of
each example against ``scipy.integrate.solve_ivp`` of the closed loop written here in the plant's physical
coordinates (the motor's angle, speed and acceleration; the block's temperature) on a short run.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.errors import SpecError
from designkit.pipeline import design as synthesize
from designkit.pipeline import run
from designkit.schema.loader import load_spec, parse_spec

SPECS = Path(__file__).resolve().parents[2] / "specs"
SERVO = SPECS / "pid-servo-third-order.yaml"
TRACKING = SPECS / "pid-tracking-first-order.yaml"
Km, tau, tau_e = 50.0, 0.2, 0.01
R, C = 0.5, 40.0


def _sorted(z):
    z = np.asarray(z, complex)
    return z[np.lexsort((z.imag, z.real))]


def _gains(d, names):
    return [float(d.gains[k]) for k in names]


def test_third_order_servo_poles_against_python_control():
    d = synthesize(load_spec(SERVO))
    K1, K2, K3 = _gains(d, ("K1", "K2", "K3"))
    P = control.tf([Km], [tau * tau_e, tau + tau_e, 1.0, 0.0])
    loop = control.feedback(control.tf([K2, K1, K3], [1.0, 0.0]) * P, 1)
    cl = _sorted(control.poles(loop))
    for p in (-10.0, -12.0, -15.0):  # placed
        assert np.min(np.abs(cl - p)) < 1e-7 * abs(p)
    # the fourth: the poles' sum is fixed by the plant, -(tau + tau_e)/(tau tau_e)
    fourth = -(tau + tau_e) / (tau * tau_e) + 37.0
    assert np.min(np.abs(cl - fourth)) < 1e-7 * abs(fourth)
    assert np.allclose(_sorted(d.poles), cl, rtol=1e-8)
    assert any("-68 1/s" in n for n in d.notes)


def test_third_order_servo_run_against_solve_ivp():
    result = run(parse_spec(SERVO.read_text().replace("duration: 1.5", "duration: 0.4")))
    d = result.design
    K1, K2, K3, K4 = _gains(d, ("K1", "K2", "K3", "K4"))
    sim = result.simulation
    t = np.asarray(sim.time)
    xD = 1.0

    def loop(_t, z):
        th, om, al, xi_ = z
        u = -K1 * (th - xD) - K2 * om - K3 * xi_ + K3 * K4 * xD
        return [om, al, (Km * u - om - (tau + tau_e) * al) / (tau * tau_e), th - xD]

    x0 = [*np.asarray(sim.state)[0, :1], 0.0, 0.0, float(np.asarray(sim.controller_state)[0, 0])]
    ref = solve_ivp(loop, (0.0, t[-1]), x0, t_eval=t, rtol=1e-10, atol=1e-12, method="LSODA")
    theta = np.asarray(sim.state)[:, 0]
    assert np.max(np.abs(theta - ref.y[0])) < 1e-4
    assert theta[-1] == pytest.approx(1.0, abs=0.05)  # settled to 2 % at 0.41 s


def test_first_order_tracking_poles_against_python_control():
    d = synthesize(load_spec(TRACKING))
    K1, K2, K3 = _gains(d, ("K1", "K2", "K3"))
    assert K2 == 0.0
    loop = control.feedback(control.tf([K1, K3], [1.0, 0.0]) * control.tf([R], [R * C, 1.0]), 1)
    assert np.allclose(_sorted(control.poles(loop)), [-0.5, -0.4], rtol=1e-9)
    # the feedforward is the plant's inverse (R C s + 1)/R
    assert _gains(d, ("q0", "q1", "q2")) == pytest.approx([1.0 / R, C, 0.0], rel=1e-12, abs=1e-12)


def test_first_order_tracking_run_against_solve_ivp():
    result = run(parse_spec(TRACKING.read_text().replace("duration: 45.0", "duration: 8.0")))
    d = result.design
    K1, _, K3 = _gains(d, ("K1", "K2", "K3"))
    sim = result.simulation
    t = np.asarray(sim.time)

    def xD(s):  # the quintic 0 -> 20 K in 30 s and its rate
        x = s / 30.0
        return 20.0 * (10 * x**3 - 15 * x**4 + 6 * x**5), 20.0 * (30 * x**2 - 60 * x**3 + 30 * x**4) / 30.0

    def loop(s, z):
        T, xI = z
        TD, TDd = xD(s)
        P = (TD + R * C * TDd) / R - K1 * (T - TD) - K3 * xI
        return [(R * (P - 2.0) - T) / (R * C), T - TD]

    x0 = [float(np.asarray(sim.state)[0, 0]), float(np.asarray(sim.controller_state)[0, 0])]
    ref = solve_ivp(loop, (0.0, t[-1]), x0, t_eval=t, rtol=1e-10, atol=1e-12)
    T = np.asarray(sim.state)[:, 0]
    assert np.max(np.abs(T - ref.y[0])) < 1e-4
    # the 2 W loss is the only error source (the feedforward is exact): it stays small against the 20 K motion
    TD = xD(t)[0]
    assert 1e-4 < np.max(np.abs(T - TD)) < 0.2


@pytest.mark.parametrize(("num", "den", "poles", "message"), [
    ("[1]", "[1, 3, 3, 1]", "[-2, -3, -4]", "relative degree 3"),
    ("[1, -2]", "[1, 3, 2]", "[-2, -3, -4]", "not minimum phase"),
])
def test_trackers_the_inverse_cannot_feed_are_refused_at_controller_kind(num, den, poles, message):
    spec = parse_spec(f"""
name: refused
plant: {{kind: transfer_function, num: {num}, den: {den}}}
controller: {{kind: pid_tracking, poles: {poles}}}
simulation: {{duration: 1.0, trajectory: {{kind: quintic, amplitude: 1.0, duration: 0.5}}}}
""")
    with pytest.raises(SpecError) as info:
        synthesize(spec)
    assert info.value.path == "controller.kind" and message in info.value.message
