"""dynamic_law and the initial state of a law: what the simulator and the linearization read from a Law."""

from __future__ import annotations

import dataclasses

import casadi as ca
import control
import numpy as np
import pytest

from designkit.models.link import LinkPlant
from designkit.synthesis.closed_loop import linearize, rest_state
from designkit.synthesis.law import State, dynamic_law
from tests.tolerances import TOL

PLANT = LinkPlant(Km=2.0, tau=0.5)


def _filtered_pd(wf: float = 10.0, kp: float = 20.0, kd: float = 2.0):
    """u = -kp (x1 - xf) - kd x2, with the reference filter xf' = wf (xD - xf)."""
    return dynamic_law(
        "demo", PLANT,
        states=[State("xf", lambda s: wf * (s.qD[0] - s.state("xf")))],
        command=lambda s: -kp * (s.q[0] - s.state("xf")) - kd * s.qd[0],
        signals={"error": lambda s: s.q[0] - s.state("xf")}, signal_units=("rad",),
    )


def test_the_builder_gives_the_law_functions_their_expressions():
    law = _filtered_pd()
    assert law.state_names == ("xf",) and law.rest_start == ("xf",) and law.initial_state == (0.0,)
    y, xc, r = np.array([0.3, -1.0]), np.array([0.1]), np.array([1.0, 0.0, 0.0])
    m = np.zeros(0)
    assert float(law.command(y, xc, m, r)) == pytest.approx(-20 * (0.3 - 0.1) + 2.0)
    assert float(law.derivative(y, xc, m, r, np.ones(1))) == pytest.approx(10 * (1.0 - 0.1))
    assert float(law.signals(y, xc, m, r)) == pytest.approx(0.2)
    assert law.signal_names == ("error",) and law.signal_units == ("rad",)


def test_a_law_declares_its_integral_states():
    assert _filtered_pd().integral_states == ()
    pi = dynamic_law("demo", PLANT, states=[State("z", lambda s: s.q[0] - s.qD[0], integral=True)],
                     command=lambda s: -20 * (s.q[0] - s.qD[0]) - 5 * s.state("z") - 2 * s.qd[0])
    assert pi.integral_states == ("z",) and pi.rest_start == ("z",)
    with pytest.raises(ValueError, match="integral_states names unknown states"):
        dataclasses.replace(pi, integral_states=("w",))


def test_the_linearized_loop_is_python_controls_interconnection():
    """Plant (Km/tau)/(s (s + 1/tau)), filter wf/(s + wf), PD: the closed loop from xD to x1 by python-control."""
    law = _filtered_pd()
    closed, _, _ = linearize(PLANT, law, [0.0, 0.0, 0.0])
    s = control.tf("s")
    P = (2.0 / 0.5) / (s * (s + 2.0))
    F = 10.0 / (s + 10.0)
    C = 20.0 + 2.0 * s  # acting on (xf - x1) for the proportional part and on -x2 for the derivative part
    expected = control.minreal(F * 20.0 * P / (1 + C * P), verbose=False)
    got = closed.to_transfer()[0, 0]
    w = np.logspace(-1, 2, 30)
    assert np.allclose(np.asarray(got(1j * w)).ravel(), np.asarray(expected(1j * w)).ravel(), rtol=1e-9)


def test_rest_start_solves_the_integral_that_holds_the_plant_still():
    """u = -K1 e - K2 x2 - K3 x3 + K3 K4 xD at rest at q0 = 0.7 with e = 0: x3 = K4 q0 (hand-solved)."""
    from designkit.families.pid_servo import design

    d = design(PLANT, [-4, -5, -20], -3.0)
    rest = rest_state(PLANT, d.law, PLANT.rest_state([0.7]), [0.7, 0.0, 0.0])
    assert rest.at_rest and rest.solved == ("x3",)
    assert rest.xc[0] == pytest.approx(float(d.gains["K4"]) * 0.7, rel=TOL["algebra"])


def test_a_loop_that_cannot_start_at_rest_is_said_so():
    """A PD law without integral on a link with a constant input offset: no controller state can hold it."""
    law = dynamic_law("offset", PLANT, command=lambda s: -20 * (s.q[0] - s.qD[0]) - 2 * s.qd[0] + 1.0)
    rest = rest_state(PLANT, law, PLANT.rest_state([0.0]), [0.0, 0.0, 0.0])
    assert not rest.at_rest and rest.residual == pytest.approx(2.0 / 0.5 * 1.0)  # x2' = (Km/tau) u = 4


def test_law_declarations_are_validated():
    with pytest.raises(ValueError, match="max_step"):
        dynamic_law("x", PLANT, command=lambda s: -s.q[0], max_step=0.0)
    law = dynamic_law("x", PLANT, command=lambda s: -s.q[0], discontinuous=True, max_step=1e-3,
                      max_step_reason="band")
    assert law.discontinuous and law.max_step == 1e-3 and law.n_state == 0 and law.signals is None


def test_feedforward_enters_the_command_through_the_declared_map():
    law = dynamic_law("x", PLANT, command=lambda s: ca.SX(0.0), feedforward=lambda s, v: 3.0 * v)
    assert float(law.feedforward(np.zeros(2), np.zeros(0), np.zeros(0), np.zeros(3), np.array([2.0]))) == 6.0
