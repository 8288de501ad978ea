"""The linear plant kinds (``transfer_function``, ``state_space``) against python-control.

Independent routes: python-control's own realisation of the same transfer function (``control.tf`` /
``control.ss``) simulated with ``control.forced_response``, against the plant's CasADi ODE integrated by SciPy's
``solve_ivp`` (tight tolerances); transfer functions compared by frequency response at a handful of points; the
matrices of an uncertainty corner against python-control systems built from numbers computed here by hand.
"""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.errors import ModelError
from designkit.models.linear_plant import state_space_plant, transfer_function_plant

T = np.linspace(0.0, 3.0, 601)
DENSE = np.linspace(0.0, 3.0, 30001)
"""python-control holds the input linearly between samples: a sine sampled this densely is followed to ~1e-9."""
FREQS = 1j * np.array([0.1, 0.7, 2.0, 9.0, 40.0])


def _simulate(plant, u_of_t, t=T):
    """The plant's own ODE (nominal parameters, no disturbance) from rest, integrated by SciPy; its first output."""
    f = plant.ode_at()
    m = plant.n_inputs

    def rhs(time, x):
        return np.asarray(f(x, np.atleast_1d(u_of_t(time)) * np.ones(m), np.zeros(plant.n_disturbances)),
                          float).ravel()

    sol = solve_ivp(rhs, (t[0], t[-1]), np.zeros(plant.n_states), t_eval=t, rtol=1e-10, atol=1e-12, method="LSODA")
    return sol.y[plant.positions[0]]


def _response(sys, s):
    return np.array([complex(np.squeeze(sys(si))) for si in s])


def test_transfer_function_ode_follows_python_controls_forced_response():
    # a third-order plant with a zero: 3 (s + 2) / (2 s^3 + 3 s^2 + 4 s + 1), driven by a sine
    plant = transfer_function_plant([3, 6], [2, 3, 4, 1])
    u = np.sin(2.0 * DENSE)
    ref = control.forced_response(control.tf([3, 6], [2, 3, 4, 1]), DENSE, u).outputs
    y = _simulate(plant, lambda t: np.sin(2.0 * t), DENSE)
    assert np.max(np.abs(y - ref)) < 1e-6 * (1 + np.max(np.abs(ref)))


def test_transfer_function_realisation_is_observability_canonical_with_the_output_and_its_rate_as_states():
    plant = transfer_function_plant(["b"], [1, "a", 0], {"a": 3.0, "b": 5.0})
    A, B, C, D = plant.matrices()
    # x1' = x2, x2' = -a x2 + b u (the link's form): written out by hand for a = 3, b = 5
    assert np.array_equal(A, [[0.0, 1.0], [0.0, -3.0]]) and np.array_equal(B.ravel(), [0.0, 5.0])
    assert np.array_equal(C, [[1.0, 0.0]]) and plant.positions == (0,) and plant.velocities == (1,)
    assert [s.unit for s in plant.states] == ["rad", "rad/s"]


def test_the_rate_state_is_the_outputs_derivative_for_every_parameter_value():
    # relative degree 2: x2 = y' exactly, so the first row of A is [0, 1, 0] and B[0] = 0 at any parameters
    plant = transfer_function_plant(["k", "k*z"], [1, "a", "b", "c"], {"k": 2.0, "z": 3.0, "a": 6.0, "b": 11.0,
                                                                       "c": 6.0})
    for values in ({}, {"k": -1.0, "a": 0.5}, {"z": 0.0, "c": -2.0, "b": 0.1}):
        A, B, C, _ = plant.with_params(**values).matrices()
        assert np.array_equal(A[0], [0.0, 1.0, 0.0]) and B[0, 0] == 0.0
    # relative degree 1: the input reaches y' directly, no state is the rate
    assert transfer_function_plant([1, 2], [1, 3, 2]).velocities == ()


def test_a_transfer_function_and_its_state_space_realisation_give_the_same_step_response():
    num, den = [4.0, 1.0], [1.0, 2.5, 3.0, 0.5]
    sys = control.tf2ss(num, den)
    A, B, C, D = sys.A, sys.B, sys.C, sys.D
    tf_plant = transfer_function_plant(num, den)
    ss_plant = state_space_plant(A.tolist(), B.tolist(), C.tolist(), D.tolist())
    step = control.step_response(control.tf(num, den), T).outputs
    y_tf, y_ss = _simulate(tf_plant, lambda t: 1.0), _simulate(ss_plant, lambda t: 1.0)
    scale = 1 + np.max(np.abs(step))
    assert np.max(np.abs(y_tf - step)) < 1e-6 * scale
    assert np.max(np.abs(y_ss - step)) < 1e-6 * scale


def test_state_space_with_a_combined_first_output_is_realised_with_that_output_as_a_state():
    A = [[0, 1, 0], [0, 0, 1], [-6, -11, -6]]
    B = [[0], [0], [1]]
    C = [[1, 1, 0], [0, 0, 1]]  # y1 = x1 + x2: G = (s + 1)/((s + 1)(s + 2)(s + 3)) before cancellation
    plant = state_space_plant(A, B, C, outputs=["pos", "acc"])
    assert plant.states[plant.positions[0]].name == "pos"
    ref = control.ss(np.array(A, float), np.array(B, float), np.array(C[:1], float), 0.0)
    Az, Bz, Cz, _ = plant.matrices()
    mine = control.ss(Az, Bz, np.eye(3)[[plant.positions[0]]], 0.0)
    assert np.allclose(_response(mine, FREQS), _response(ref, FREQS), rtol=1e-10, atol=1e-12)
    # the second output is unchanged by the change of state
    ref2 = control.ss(np.array(A, float), np.array(B, float), np.array(C[1:], float), 0.0)
    assert np.allclose(_response(control.ss(Az, Bz, Cz[1:], 0.0), FREQS), _response(ref2, FREQS), rtol=1e-10)
    u = np.cos(3.0 * DENSE)
    y_ref = control.forced_response(ref, DENSE, u).outputs
    assert np.max(np.abs(_simulate(plant, lambda t: np.cos(3.0 * t), DENSE) - y_ref)) < 1e-7


def test_parameters_in_entries_follow_with_params_like_python_control_built_at_those_values():
    plant = state_space_plant([[0, 1], [0, "-1/tau"]], [[0], ["Km/tau"]], [[1, 0]], parameters={"Km": 2.0, "tau": 0.5})
    for Km, tau in [(1.6, 0.4), (1.6, 0.6), (2.4, 0.4), (2.4, 0.6)]:  # the corners of a box
        corner = plant.with_params(Km=Km, tau=tau)
        A, B, C, D = corner.matrices()
        ref = control.tf([Km], [tau, 1.0, 0.0])
        assert np.allclose(_response(control.ss(A, B, C, D), FREQS), _response(ref, FREQS), rtol=1e-12)
    assert plant.parameter("tau").value == 0.5  # the nominal plant is unchanged


def test_expressions_over_parameters_in_a_transfer_function():
    plant = transfer_function_plant(["2*k"], [1, "a + b", "a*b"], {"a": 1.0, "b": 3.0, "k": 1.5})
    ref = control.tf([3.0], [1.0, 4.0, 3.0])
    A, B, C, D = plant.matrices()
    assert np.allclose(_response(control.ss(A, B, C, D), FREQS), _response(ref, FREQS), rtol=1e-12)
    moved = plant.with_params(a=-0.5)  # a parameter may be negative: an unstable pole at 0.5
    assert np.allclose(sorted(np.linalg.eigvals(moved.matrices()[0]).real), [-3.0, 0.5])


def test_the_input_equivalent_disturbance_enters_through_b():
    plant = transfer_function_plant([2.0], [1.0, 1.0])
    assert np.allclose(plant.rhs([0.5], [1.0], [0.25]), -0.5 + 2.0 * 1.25)


@pytest.mark.parametrize(("build", "field", "words"), [
    (lambda: transfer_function_plant([1, 2, 3], [1, 2]), "num", "improper"),
    (lambda: transfer_function_plant([1, 2], [1, 2]), "num", "direct feedthrough"),
    (lambda: transfer_function_plant([1], [0, 1, 2]), "den[0]", "leading coefficient is 0"),
    (lambda: transfer_function_plant([0, 1], [1, 1, 2]), "num[0]", "leading coefficient is 0"),
    (lambda: transfer_function_plant([0], [1, 1]), "num", "zero"),
    (lambda: transfer_function_plant([1], [1]), "den", "at least two"),
    (lambda: transfer_function_plant(["c"], [1, 1], {"a": 1.0}), "num[0]", "unknown parameter 'c'"),
    (lambda: transfer_function_plant(["1/a"], [1, 1], {"a": 0.0}), "num[0]", "not finite"),
    (lambda: transfer_function_plant(["a +"], [1, 1], {"a": 1.0}), "num[0]", "cannot read"),
    (lambda: transfer_function_plant(["__import__"], [1, 1]), "num[0]", "unknown parameter"),
    (lambda: state_space_plant([[0, 1], [0]], [[0], [1]], [[1, 0]]), "A[1]", "needs 2 entries"),
    (lambda: state_space_plant([[0, 1], [0, 0]], [[0]], [[1, 0]]), "B", "needs 2 rows"),
    (lambda: state_space_plant([[0, 1], [0, 0]], [[0], [1]], [[1, 0, 0]]), "C[0]", "needs 2 entries"),
    (lambda: state_space_plant([[0, 1], [0, 0]], [[0], [1]], [[1, 0]], [[0, 0]]), "D[0]", "needs 1 entries"),
    (lambda: state_space_plant([[0, 1], [0, 0]], [[0], [1]], [[1, 0]], [[0.5]]), "D[0][0]", "feedthrough"),
    (lambda: state_space_plant([[0, 1], [0, 0]], [[0], [1]], [[0, 0]]), "C[0]", "measures nothing"),
    (lambda: state_space_plant([[0, 1], [0, 0]], [[0], [1]], [[1, 0]], states=["p"]), "states", "needs 2 names"),
    (lambda: state_space_plant([[0, float("inf")], [0, 0]], [[0], [1]], [[1, 0]]), "A[0][1]", "finite"),
])
def test_bad_linear_plants_are_refused_at_their_field(build, field, words):
    with pytest.raises(ModelError) as info:
        build()
    assert info.value.field == field
    assert words in info.value.message


def test_a_parameter_value_that_drops_the_order_is_refused_naming_the_parameter():
    plant = transfer_function_plant(["Km"], ["tau", 1, 0], {"Km": 2.0, "tau": 0.5})
    with pytest.raises(ModelError) as info:
        plant.with_params(tau=0.0)
    assert info.value.field == "tau" and "den[0]" in info.value.message
    with pytest.raises(ModelError) as info:
        plant.with_params(c=1.0)
    assert info.value.field == "c"


def test_a_discrete_transfer_function_responds_as_python_controls():
    """``num(z)/den(z)`` with ``dt``: the realisation's difference equation from rest against ``control.tf(num,
    den, dt)``'s forced response to the same input sequence."""
    plant = transfer_function_plant(["k", 0.3], [1, -1.2, 0.5], {"k": 2.0}, dt=0.1)
    assert plant.dt == 0.1 and plant.velocities == () and "discrete-time" in plant.describe()
    A, B, C, _ = plant.matrices()
    u = np.sin(0.7 * np.arange(60)) + 0.2
    x, y = np.zeros(A.shape[0]), []
    for uk in u:
        y.append(float(C[0] @ x))
        x = A @ x + B[:, 0] * uk
    ref = control.forced_response(control.tf([2.0, 0.3], [1, -1.2, 0.5], 0.1), T=0.1 * np.arange(60), U=u).outputs
    np.testing.assert_allclose(y, np.ravel(ref), rtol=1e-12, atol=1e-12)
    with pytest.raises(ModelError) as info:  # a difference equation has no ODE to integrate
        plant.ode()
    assert info.value.field == "dt"
    assert plant.with_params(k=3.0).dt == 0.1  # a parameter change keeps it discrete


def test_a_discrete_state_space_keeps_its_matrices():
    A = [[-0.8, -0.22], [1, 0]]
    plant = state_space_plant(A, [[0.5], [1]], [[1, 0.5]], dt=1.0)
    Az, Bz, Cz, _ = plant.matrices()
    # realised with y = x1 + 0.5 x2 as a state: the same Markov parameters C A^m B
    for m in range(6):
        direct = np.array([1, 0.5]) @ np.linalg.matrix_power(np.array(A), m) @ np.array([0.5, 1.0])
        assert float(Cz[0] @ np.linalg.matrix_power(Az, m) @ Bz[:, 0]) == pytest.approx(direct, abs=1e-14)
    assert any("[k+1]" in line for line in plant.equations())
