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
