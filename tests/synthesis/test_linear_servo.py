"""The PID servo of a linear plant (:mod:`designkit.synthesis.linear_servo`).

Independent routes: the characteristic map against ``numpy.poly`` of the closed-loop matrix built by hand; the
placed poles against ``numpy.roots`` of ``s den(s) + num(s) (K2 s^2 + K1 s + K3)`` (polynomial arithmetic, relative
degree 2) and against the eigenvalues of the loop closed on python-control's own realisation (``control.tf2ss``)
of the same transfer function (relative degree 1); the zero against ``control.zeros`` of that loop.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from designkit.errors import SpecError
from designkit.models.linear_plant import state_space_plant, transfer_function_plant
from designkit.synthesis.linear_servo import characteristic_map, linear_servo_design

POLES = [-4.0, -5.0, -20.0]


def _sorted(z):
    z = np.asarray(z, complex)
    return z[np.lexsort((z.imag, z.real))]


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_characteristic_map_is_the_closed_loop_polynomial(n):
    rng = np.random.default_rng(n)
    A, b, c, r = rng.normal(size=(n, n)), rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
    a0, M = characteristic_map(A, b, c, r)
    for _ in range(3):
        K1, K2, K3 = rng.normal(size=3)
        Acl = np.zeros((n + 1, n + 1))
        Acl[:n, :n] = A - np.outer(b, K1 * c + K2 * r)
        Acl[:n, n] = -b * K3
        Acl[n, :n] = c
        assert np.allclose(a0 + M @ [K1, K2, K3], np.real(np.poly(np.linalg.eigvals(Acl)))[1:], rtol=1e-9,
                           atol=1e-9)


def test_second_order_transfer_function_of_relative_degree_two():
    num, den = [50.0], [0.2, 1.0, 0.0]  # the DC motor Km/(s (tau s + 1)), Km = 50, tau = 0.2
    plant = transfer_function_plant(["Kt"], ["J", "B", 0], {"Kt": 0.05, "J": 2e-4, "B": 1e-3})
    d = linear_servo_design(plant, [-20, -25, -60], -15.0, kind="pid_servo")
    K1, K2, K3, K4 = (float(d.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    char = np.polyadd(np.polymul([1.0, 0.0], den), np.polymul(num, [K2, K1, K3]))
    assert np.allclose(_sorted(np.roots(char)), [-60, -25, -20], rtol=1e-9)
    assert np.allclose(_sorted(d.closed_loop.poles), [-60, -25, -20], rtol=1e-9)
    # the zero of y/xD: (K1 + K3 K4) s + K3 = 0
    assert pytest.approx(-15.0, rel=1e-12) == -K3 / (K1 + K3 * K4)
    # the link's closed forms (designkit.synthesis.pid, notes 3.2) give the same gains on Km, tau
    from designkit.synthesis.pid import servo_pid_gains

    assert np.allclose([K1, K2, K3], servo_pid_gains(50.0, 0.2, [-20, -25, -60]), rtol=1e-9)


def test_second_order_transfer_function_of_relative_degree_one_on_python_controls_realisation():
    num, den = [1.0, 3.0], [1.0, 2.0, 5.0]
    plant = transfer_function_plant(num, den)
    d = linear_servo_design(plant, POLES, -2.0, kind="pid_servo")
    K1, K2, K3, K4 = (float(d.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    sys = control.tf2ss(control.tf(num, den))
    A, B, C = np.asarray(sys.A), np.asarray(sys.B)[:, 0], np.asarray(sys.C)[0]
    n = A.shape[0]
    Acl = np.zeros((n + 1, n + 1))  # u = -K1 y - K2 (C A x) - K3 x_I + (K1 + K3 K4) xD, x_I' = y - xD
    Acl[:n, :n] = A - np.outer(B, K1 * C + K2 * C @ A)
    Acl[:n, n] = -B * K3
    Acl[n, :n] = C
    Bcl = np.concatenate([B * (K1 + K3 * K4), [-1.0]])
    loop = control.ss(Acl, Bcl[:, None], np.concatenate([C, [0.0]])[None, :], 0.0)
    assert np.allclose(_sorted(control.poles(loop)), _sorted(POLES), rtol=1e-8)
    assert np.allclose(_sorted(control.zeros(loop)), _sorted([-3.0, -2.0]), rtol=1e-8)  # the plant's and the placed
    assert control.dcgain(loop) == pytest.approx(1.0, rel=1e-10)
    assert _sorted(d.zeros) == pytest.approx(_sorted([-2.0, -3.0]), rel=1e-9)


def test_a_second_order_state_space_plant_whose_output_is_a_combination():
    A, B, C = [[0, 1], [-2, -3]], [[0], [1]], [[1, 0.25]]  # y = x1 + x2/4: G = (s/4 + 1)/(s^2 + 3 s + 2)
    d = linear_servo_design(state_space_plant(A, B, C), POLES, None, kind="pid_servo")
    K1, K2, K3 = (float(d.gains[k]) for k in ("K1", "K2", "K3"))
    Am, Bm, Cm = np.array(A, float), np.array(B, float)[:, 0], np.array(C, float)[0]
    Acl = np.zeros((3, 3))
    Acl[:2, :2] = Am - np.outer(Bm, K1 * Cm + K2 * Cm @ Am)
    Acl[:2, 2] = -Bm * K3
    Acl[2, :2] = Cm
    assert np.allclose(_sorted(np.linalg.eigvals(Acl)), _sorted(POLES), rtol=1e-8)


def _feedback_poles(num, den, K1, K2, K3):
    """Closed-loop poles of python-control's ``feedback(C P, 1)`` with ``C = K1 + K2 s + K3/s`` (``r x = y'`` on an
    all-pole plant of relative degree 2 or more; ``K2 = 0`` on a first-order one)."""
    C = control.tf([K2, K1, K3], [1.0, 0.0]) if K2 else control.tf([K1, K3], [1.0, 0.0])
    return _sorted(control.poles(control.feedback(C * control.tf(num, den), 1)))


def test_a_first_order_plant_places_two_poles_with_a_pi():
    num, den = [2.0], [0.5, 1.0]
    d = linear_servo_design(transfer_function_plant(num, den), [-4.0, -5.0], -2.0, kind="pid_servo")
    K1, K2, K3 = (float(d.gains[k]) for k in ("K1", "K2", "K3"))
    assert K2 == 0.0
    assert np.allclose(_feedback_poles(num, den, K1, K2, K3), [-5.0, -4.0], rtol=1e-9)
    assert np.allclose(_sorted(d.closed_loop.poles), [-5.0, -4.0], rtol=1e-9)
    with pytest.raises(SpecError) as info:
        linear_servo_design(transfer_function_plant(num, den), POLES, None, kind="pid_servo")
    assert info.value.path == "controller.poles" and "give 2 poles" in info.value.message


def test_two_poles_on_a_second_order_plant_are_refused():
    with pytest.raises(SpecError) as info:
        linear_servo_design(transfer_function_plant([1.0], [1.0, 1.0, 0.0]), [-1.0, -2.0], None, kind="pid_servo")
    assert info.value.path == "controller.poles" and "give 3 poles" in info.value.message


@pytest.mark.parametrize("den", [[0.002, 0.21, 1.0, 0.0], [1.0, 12.0, 54.0, 108.0, 81.0]])
def test_higher_order_places_three_poles_and_states_where_the_others_are_left(den):
    num = [50.0]
    placed = [-3.0 + 2.0j, -3.0 - 2.0j, -6.0] if len(den) == 5 else [-20.0, -30.0, -40.0]
    d = linear_servo_design(transfer_function_plant(num, den), placed, None, kind="pid_servo")
    K1, K2, K3 = (float(d.gains[k]) for k in ("K1", "K2", "K3"))
    cl = _feedback_poles(num, den, K1, K2, K3)
    assert len(cl) == len(den)  # order n + 1
    for p in placed:  # every requested pole is a pole of python-control's loop
        assert np.min(np.abs(cl - p)) < 1e-6 * abs(p)
    assert np.allclose(_sorted(d.poles), cl, rtol=1e-7, atol=1e-9)  # the design states the left ones too
    assert np.allclose(_sorted(d.closed_loop.poles), cl, rtol=1e-7, atol=1e-9)
    left = [p for p in cl if np.min(np.abs(np.asarray(placed) - p)) > 1e-6 * abs(p)]
    assert len(left) == len(den) - 3
    assert "left where the quotient puts them" in d.notes[0]
    # the sum of the loop's poles is fixed by the plant on a relative degree 3 plant (the s^n coefficient)
    assert np.sum(cl).real == pytest.approx(-den[1] / den[0], rel=1e-9)


def test_a_placement_that_leaves_an_unstable_pole_says_so():
    num, den = [400.0], [1.0, 2.0, 400.0, 0.0]  # sum of the loop's poles fixed at -2
    d = linear_servo_design(transfer_function_plant(num, den), [-3.0, -4.0, -5.0], None, kind="pid_servo")
    cl = _feedback_poles(num, den, *(float(d.gains[k]) for k in ("K1", "K2", "K3")))
    assert max(cl.real) == pytest.approx(10.0, rel=1e-9)
    assert "UNSTABLE" in d.notes[0]


def test_a_plant_zero_cancelling_a_pole_is_refused():
    # y = x1 + x2/2: G = (s/2 + 1)/((s + 1)(s + 2)) = 1/(2 (s + 1)), a first-order loop in disguise
    plant = state_space_plant([[0, 1], [-2, -3]], [[0], [1]], [[1, 0.5]])
    with pytest.raises(SpecError) as info:
        linear_servo_design(plant, POLES, None, kind="pid_servo")
    assert info.value.path == "controller.poles" and "plant zero" in info.value.message
