"""Design -> python-control: the closed loop and the loop transfer at the plant input.

Independent expectations for the one-link PID servo (notes §3.2, spec ``posspeed-link``:
``Km = 2``, ``tau = 0.5``, poles -4, -5, -20, zero -3).  Plant ``x1' = x2``,
``x2' = -x2/tau + (Km/tau) u``, so ``x1/u = P(s) = Km / (s (tau s + 1))``.  Law
``u = -K1 (x1 - xD) - K2 x2 - K3 int(x1 - xD) + K3 K4 xD``.

* Gains by matching ``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3`` with
  ``tau (s + 4)(s + 5)(s + 20) = 0.5 s^3 + 14.5 s^2 + 100 s + 200``: ``K2 = 6.75``, ``K1 = 50``,
  ``K3 = 100``; ``K4`` puts the zero of ``x1/xD`` at -3: ``K1 + K3 K4 = K3/3``, ``K4 = -1/6``.
* Loop broken at the plant input (``xD = 0``, negative feedback ``u = -C(s) x1``):
  ``C(s) = K1 + K2 s + K3/s`` and

      ``L(s) = C(s) P(s) = Km (K2 s^2 + K1 s + K3) / (s^2 (tau s + 1)) = (27 s^2 + 200 s + 400) / (s^3 + 2 s^2)``

  (monic), and ``1 + L = 0`` gives ``s^3 + 29 s^2 + 200 s + 400 = (s + 4)(s + 5)(s + 20)``.
* Reference to position: ``x1/xD = Km ((K1 + K3 K4) s + K3) / (tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3)``
  ``= (133.33 s + 400) / (s^3 + 29 s^2 + 200 s + 400)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

import designkit as dk
from designkit.models.linear_system import LinearSystem

control = pytest.importorskip("control")

SPECS = Path(__file__).resolve().parents[2] / "specs"
KM, TAU = 2.0, 0.5
K1, K2, K3, K4 = 50.0, 6.75, 100.0, -1.0 / 6.0
PID_LINK_SPECS = ("posspeed-link", "stiff-link", "requirements-driven", "tracking-pid", "posspeed-saturation")


def _hand_loop(s: complex) -> complex:
    return KM * (K2 * s**2 + K1 * s + K3) / (s**2 * (TAU * s + 1.0))


@pytest.fixture(scope="module")
def result():
    return dk.run(dk.load_spec(SPECS / "posspeed-link.yaml"))


@pytest.fixture(scope="module")
def design(result):
    return result.design


def test_hand_gains_are_the_designs(design):
    for name, value in {"K1": K1, "K2": K2, "K3": K3, "K4": K4}.items():
        assert float(design.gains[name]) == pytest.approx(value, rel=1e-12)


def test_closed_loop_state_space_has_named_signals_and_the_design_poles(design):
    sys = design.to_control()
    assert isinstance(sys, control.StateSpace)
    assert sys.input_labels == ["xD", "xDd", "xDdd", "xi"]
    assert sys.output_labels == ["x1", "u"]
    assert sys.state_labels == list(design.closed_loop.states)
    np.testing.assert_allclose(np.sort_complex(sys.poles()), np.sort_complex([-20, -5, -4]), rtol=1e-10)
    back = LinearSystem.from_control(sys)
    for name in ("A", "B", "C", "D"):
        np.testing.assert_array_equal(getattr(back, name), getattr(design.closed_loop, name))


def test_closed_loop_transfer_matches_the_hand_derived_reference_transfer(design):
    g = design.to_control(form="tf")
    assert isinstance(g, control.TransferFunction)
    num = np.asarray(g.num_array[0][0], float)  # x1 / xD
    den = np.asarray(g.den_array[0][0], float)
    np.testing.assert_allclose(den, [1.0, 29.0, 200.0, 400.0], rtol=1e-10)
    np.testing.assert_allclose(num, [KM * (K1 + K3 * K4) / TAU, KM * K3 / TAU], rtol=1e-10)


def test_unknown_form_is_refused(design):
    with pytest.raises(ValueError, match="form"):
        design.to_control(form="zpk")
    with pytest.raises(ValueError, match="form"):
        design.loop_transfer(form="zpk")


@pytest.mark.parametrize("name", PID_LINK_SPECS)
def test_closed_loop_poles_equal_the_designs_poles(name):
    d = dk.synthesize(dk.load_spec(SPECS / f"{name}.yaml").spec)
    poles = np.sort_complex(control.poles(d.to_control()))
    wanted = np.sort_complex(np.asarray(d.poles, complex))
    scale = float(np.max(np.abs(wanted)))
    assert len(poles) == len(wanted)
    np.testing.assert_allclose(poles, wanted, rtol=0, atol=1e-8 * scale)
    # 1 + L = 0 at the closed-loop poles: den(L) + num(L) is the closed-loop characteristic polynomial
    L = d.loop_transfer()
    num, den = np.asarray(L.num_array[0][0], float), np.asarray(L.den_array[0][0], float)
    char = np.polyadd(den, num)
    np.testing.assert_allclose(np.sort_complex(np.roots(char)), wanted, rtol=0, atol=1e-6 * scale)


def test_loop_transfer_is_the_hand_derived_pid_loop(design):
    L = design.loop_transfer(channel=0)
    assert isinstance(L, control.TransferFunction)
    assert L.input_labels == ["u"] and L.output_labels == ["-u"]
    num, den = np.asarray(L.num_array[0][0], float), np.asarray(L.den_array[0][0], float)
    np.testing.assert_allclose(den, [1.0, 1.0 / TAU, 0.0, 0.0], rtol=1e-12, atol=0)  # double integrator exact
    np.testing.assert_allclose(num, [KM * K2 / TAU, KM * K1 / TAU, KM * K3 / TAU], rtol=1e-10)
    for w in (0.3, 3.0, 27.0, 300.0):
        assert complex(L(1j * w)) == pytest.approx(_hand_loop(1j * w), rel=1e-10)
    ss = design.loop_transfer("u", form="ss")
    assert isinstance(ss, control.StateSpace)
    assert complex(np.squeeze(ss(2j))) == pytest.approx(_hand_loop(2j), rel=1e-10)


def test_loop_transfer_margins_equal_the_loop_margins_check(result, design):
    check = next(c for c in result.checks if c.name == "loop_margins")
    row = check.certificate["loops"][0]
    gm, pm, _sm, _wpc, wgc, _wms = control.stability_margins(design.loop_transfer())
    assert pm == pytest.approx(row["phase_margin_deg"], rel=1e-6)
    assert wgc == pytest.approx(row["gain_crossover_rad_s"], rel=1e-6)
    assert row["gain_margin"] is None and np.isinf(gm)  # the phase never reaches -180 deg
    # independent: |L(jw)| = 1 solved on the hand formula, PM = 180 deg + arg L(jw_c)
    wc = brentq(lambda w: abs(_hand_loop(1j * w)) - 1.0, 1.0, 1e3, xtol=1e-13)
    pm_hand = 180.0 + np.degrees(np.angle(_hand_loop(1j * wc)))
    assert wc == pytest.approx(row["gain_crossover_rad_s"], rel=1e-6)
    assert pm_hand == pytest.approx(row["phase_margin_deg"], rel=1e-6)
    # arg L = -180 + atan(K2 w^2 ...) never crosses -180: check the phase stays above it on a grid
    w = np.logspace(-3, 4, 2000)
    assert np.all(np.degrees(np.angle(_hand_loop(1j * w))) > -180.0)


def test_loop_channel_errors(design):
    with pytest.raises(ValueError, match="no plant input"):
        design.loop_system("tau")
    with pytest.raises(ValueError, match="channel"):
        design.loop_system(3)


def test_design_without_closed_loop_is_refused(design):
    import dataclasses

    bare = dataclasses.replace(design, closed_loop=None, input_loop=None)
    with pytest.raises(ValueError, match="no nominal closed loop"):
        bare.to_control()
    with pytest.raises(ValueError, match="no loop at the plant input"):
        bare.loop_transfer()
