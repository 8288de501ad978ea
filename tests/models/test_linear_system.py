"""LinearSystem <-> python-control: round trip, named signals, transfer coefficients against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.models.linear_system import LinearSystem

control = pytest.importorskip("control")


def _random_system(seed: int, n: int = 4, m: int = 2, p: int = 3) -> LinearSystem:
    rng = np.random.default_rng(seed)
    return LinearSystem(A=rng.normal(size=(n, n)), B=rng.normal(size=(n, m)), C=rng.normal(size=(p, n)),
                        D=rng.normal(size=(p, m)), states=tuple(f"z{k}" for k in range(n)),
                        inputs=tuple(f"r{k}" for k in range(m)), outputs=tuple(f"y{k}" for k in range(p)))


def _assert_same(a: LinearSystem, b: LinearSystem) -> None:
    for name in ("A", "B", "C", "D"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert (a.states, a.inputs, a.outputs) == (b.states, b.inputs, b.outputs)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_round_trip_through_python_control_is_exact(seed):
    ls = _random_system(seed)
    sys = ls.to_control(name="plant")
    assert isinstance(sys, control.StateSpace)
    assert sys.name == "plant"
    assert sys.state_labels == list(ls.states) and sys.input_labels == list(ls.inputs)
    assert sys.output_labels == list(ls.outputs)
    _assert_same(LinearSystem.from_control(sys), ls)


def test_from_control_rejects_discrete_time():
    with pytest.raises(ValueError, match="continuous-time"):
        LinearSystem.from_control(control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], dt=0.1))


def test_from_transfer_function_keeps_the_poles():
    # 1 / ((s + 1)(s + 2)(s + 5))
    ls = LinearSystem.from_control(control.tf([1.0], [1.0, 8.0, 17.0, 10.0]))
    np.testing.assert_allclose(np.sort(ls.poles.real), [-5.0, -2.0, -1.0], rtol=1e-10)


def test_transfer_coefficients_of_a_mass_spring_damper():
    # m q'' + c q' + k q = f, y = q and y = q': q/f = 1/(m s^2 + c s + k), q'/f = s/(m s^2 + c s + k)
    m, c, k = 2.0, 3.0, 10.0
    ls = LinearSystem(A=[[0.0, 1.0], [-k / m, -c / m]], B=[[0.0], [1.0 / m]], C=[[1.0, 0.0], [0.0, 1.0]],
                      D=[[0.0], [0.0]], states=("q", "qd"), inputs=("f",), outputs=("q", "qd"))
    num, den = ls.transfer_coefficients("q", "f")
    np.testing.assert_allclose(den, [1.0, c / m, k / m], rtol=1e-12)
    np.testing.assert_allclose(num, [1.0 / m], rtol=1e-12)
    num, _ = ls.transfer_coefficients("qd", "f")
    np.testing.assert_allclose(num, [1.0 / m, 0.0], rtol=1e-12, atol=0)  # exact zero at the origin


def test_transfer_coefficients_with_feedthrough_and_integrator():
    # y = x + 3 r, x' = r: G(s) = 1/s + 3 = (3 s + 1)/s, whose denominator root is exactly 0
    ls = LinearSystem(A=[[0.0]], B=[[1.0]], C=[[1.0]], D=[[3.0]], states=("x",), inputs=("r",), outputs=("y",))
    num, den = ls.transfer_coefficients()
    assert den.tolist() == [1.0, 0.0]
    np.testing.assert_allclose(num, [3.0, 1.0], rtol=1e-12)


@pytest.mark.parametrize("seed", [3, 4])
def test_to_transfer_matches_the_state_space_frequency_response(seed):
    ls = _random_system(seed, n=3, m=2, p=2)
    tf = ls.to_transfer()
    assert tf.input_labels == list(ls.inputs) and tf.output_labels == list(ls.outputs)
    for w in (0.1, 1.0, 7.0):
        s = 1j * w
        direct = ls.C @ np.linalg.solve(s * np.eye(3) - ls.A, ls.B) + ls.D
        np.testing.assert_allclose(tf(s), direct, rtol=1e-8, atol=1e-10)


# ----------------------------------------------------------------------------- NumPy-only helpers vs python-control

LOOPS = {  # L(s) = num/den, highest power first
    "pid on the link": ([27.0, 200.0, 400.0], [1.0, 2.0, 0.0, 0.0]),
    "third-order lag": ([8.0], [1.0, 3.0, 3.0, 1.0]),  # 8/(s+1)^3: GM 1, on the edge
    "lag with gain 4": ([4.0], [1.0, 3.0, 3.0, 1.0]),  # GM 2 at w = sqrt(3)
    "integrator and lags": ([10.0], np.polymul([1.0, 0.0], np.polymul([1.0, 1.0], [0.1, 1.0]))),
    "conditionally stable": ([1.0, 3.0, 10.0], [1.0, 0.5, 1.0, 0.0]),
    "no crossover": ([0.1], [1.0, 2.0]),
}


@pytest.mark.parametrize("name", sorted(LOOPS))
def test_siso_margins_equal_python_control(name):
    from designkit.models.linear_system import siso_margins

    num, den = LOOPS[name]
    ours = siso_margins(num, den)
    theirs = control.stability_margins(control.tf(num, den))
    for a, b in zip(ours, theirs, strict=True):
        if np.isnan(b):
            assert np.isnan(a)
        elif np.isinf(b):
            assert a == b
        else:
            assert a == pytest.approx(float(b), rel=1e-9, abs=1e-12)


def test_lag_margin_matches_the_closed_form():
    # 4/(s+1)^3: phase -180 deg where 3 atan(w) = pi, w = sqrt(3); |L| = 4/(1+3)^(3/2) = 1/2, GM 2
    from designkit.models.linear_system import siso_margins

    gm, _pm, _sm, wpc, _wgc, _wms = siso_margins([4.0], [1.0, 3.0, 3.0, 1.0])
    assert gm == pytest.approx(2.0, rel=1e-12) and wpc == pytest.approx(np.sqrt(3.0), rel=1e-12)


def test_dc_gain_equals_python_control():
    ls = _random_system(5)  # any non-singular A will do for the DC gain
    np.testing.assert_allclose(ls.dc_gain(), control.dcgain(ls.to_control()), rtol=1e-10)


def test_forced_response_equals_python_control():
    ls = LinearSystem(A=[[0.0, 1.0, 0.0], [-200.0, -29.0, -400.0], [1.0, 0.0, 0.0]], B=[[0.0, 0.0], [133.3, 4.0],
                      [-1.0, 0.0]], C=[[1.0, 0.0, 0.0], [-50.0, -6.75, -100.0]], D=[[0.0, 0.0], [33.3, 0.0]],
                      states=("x1", "x2", "x3"), inputs=("xD", "xi"), outputs=("x1", "u"))
    t = np.linspace(0.0, 2.0, 801)
    u = np.vstack([np.minimum(t / 0.1, 1.0), np.where(t >= 1.0, 0.5, 0.0)])
    y, x = ls.forced_response(t, u)
    ref = control.forced_response(ls.to_control(), T=t, U=u, return_x=True)
    np.testing.assert_allclose(y, ref.outputs, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(x, ref.states, rtol=1e-9, atol=1e-9)
    with pytest.raises(ValueError, match="evenly spaced"):
        ls.forced_response(np.array([0.0, 0.1, 0.3]), np.zeros((2, 3)))
