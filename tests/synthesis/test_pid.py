"""PID gains against hand-derived values and an independent python-control interconnection."""

from __future__ import annotations

import control
import numpy as np
import pytest

from designkit.families import synthesize
from designkit.models.link import LinkPlant
from designkit.schema.loader import parse_spec
from designkit.synthesis import pid
from tests.problems import COMPLEX_YAML, POSSPEED_GAINS, POSSPEED_YAML, TRACKING_GAINS, TRACKING_YAML

REL = 1e-9


def _sorted(values):
    return np.array(sorted(np.asarray(values, complex), key=lambda z: (round(z.real, 6), round(z.imag, 6))))


def _assert_same_roots(actual, expected):
    a, e = _sorted(actual), _sorted(expected)
    assert a.shape == e.shape
    np.testing.assert_array_less(np.abs(a - e) / (1 + np.abs(e)), REL)


def _servo_by_interconnection(plant: LinkPlant, g: dict) -> control.TransferFunction:
    """x1/xD built from transfer functions, independently of pid.servo_closed_loop."""
    s = control.tf("s")
    P = plant.Km / (s * (plant.tau * s + 1))
    Cy = g["K1"] + g["K2"] * s + g["K3"] / s  # acts on -x1
    Cr = g["K1"] + g["K3"] / s + g["K3"] * g["K4"]  # acts on xD
    return control.minreal(P * Cr / (1 + P * Cy), verbose=False)


def test_posspeed_gains_hand_derived():
    design = synthesize(parse_spec(POSSPEED_YAML).spec)
    for k, v in POSSPEED_GAINS.items():
        assert design.gains[k] == pytest.approx(v, rel=REL)


def test_tracking_gains_hand_derived():
    design = synthesize(parse_spec(TRACKING_YAML).spec)
    for k, v in TRACKING_GAINS.items():
        assert design.gains[k] == pytest.approx(v, rel=REL)


@pytest.mark.parametrize("yaml_text", [POSSPEED_YAML, COMPLEX_YAML])
def test_servo_poles_zero_and_dc_gain_by_python_control(yaml_text):
    spec = parse_spec(yaml_text).spec
    design = synthesize(spec)
    tf = _servo_by_interconnection(design.plant, dict(design.gains))
    _assert_same_roots(control.poles(tf), spec.controller.poles)
    _assert_same_roots(control.zeros(tf), [spec.controller.zero])
    assert control.dcgain(tf) == pytest.approx(1.0, rel=REL)
    # the state-space closed loop agrees with the interconnection
    ss = design.closed_loop.to_control()
    _assert_same_roots(control.poles(ss), spec.controller.poles)


def test_notes_misprinted_K2_gives_wrong_poles():
    """The notes print K2 = -[(p1+p2+p3) tau - 1]/Km; that misplaces the poles."""
    plant, poles = LinkPlant(Km=2.0, tau=0.5), (-4.0, -5.0, -20.0)
    g = pid.servo_gains(plant, poles, -3.0)
    g_notes = dict(g, K2=-(sum(poles) * plant.tau - 1.0) / plant.Km)
    achieved = control.poles(_servo_by_interconnection(plant, g_notes))
    assert np.min(np.abs(_sorted(achieved) - _sorted(poles))) > 0.1


def test_tracking_error_dynamics_and_servo_gains_differ():
    """Tracking: dx1/xi = (Km/tau) s / prod(s - p); its K2 is the servo's K2 + 1/Km (notes say equal)."""
    spec = parse_spec(TRACKING_YAML).spec
    design = synthesize(spec)
    cl = design.closed_loop.to_control()
    xi_to_x1 = control.ss2tf(cl[0, 3])
    s = control.tf("s")
    expected = (2.0 / 0.5) * s / ((s + 10) * (s + 12) * (s + 15))
    w = np.logspace(-2, 3, 50)
    np.testing.assert_allclose(
        xi_to_x1.frequency_response(w).complex, expected.frequency_response(w).complex, rtol=1e-9
    )
    servo = pid.servo_gains(design.plant, spec.controller.poles, None)
    assert design.gains["K2"] - servo["K2"] == pytest.approx(1.0 / design.plant.Km, rel=REL)
    # perfect tracking: x1 = xD when xD, xD', xD'' are consistent (zero error transfer from the trajectory)
    t = np.linspace(0, 2, 2001)
    xd = np.sin(3 * t)
    u = np.vstack([xd, 3 * np.cos(3 * t), -9 * np.sin(3 * t), 0 * t])
    resp = control.forced_response(cl, T=t, U=u, X0=[0.0, 3.0, 0.0])
    np.testing.assert_allclose(resp.outputs[0], xd, atol=1e-6)


def test_servo_without_zero_sets_K4_zero_and_reports_the_zero():
    spec = parse_spec(POSSPEED_YAML.replace(", zero: -3", "")).spec
    design = synthesize(spec)
    assert design.gains["K4"] == 0.0
    tf = _servo_by_interconnection(design.plant, dict(design.gains))
    _assert_same_roots(control.zeros(tf), design.zeros)
    assert any("K4 = 0" in n for n in design.notes)


@pytest.mark.parametrize("Km", [2.0, -0.7])
def test_bare_number_gains_place_the_loop_for_either_sign_of_Km(Km):
    """servo_pid_gains (used by the self-tuning family on a running estimate) against python-control's closed
    loop u = -(K1 + K2 s + K3/s) x1 on Km / (s (tau s + 1)), a negative Km included (LinkPlant refuses it)."""
    tau, poles = 0.5, (-4.0, -5.0, -20.0)
    K1, K2, K3 = pid.servo_pid_gains(Km, tau, poles)
    L = control.tf([Km * K2, Km * K1, Km * K3], [tau, 1.0, 0.0, 0.0])
    np.testing.assert_allclose(np.sort(control.poles(control.feedback(L, 1)).real), sorted(poles), rtol=1e-8)
    if Km > 0:
        gains = pid.servo_gains(LinkPlant(Km=Km, tau=tau), poles, None)
        assert (gains["K1"], gains["K2"], gains["K3"]) == (K1, K2, K3)
