"""The PID families' CasADi laws against their documented formulas.

These tests compare each law with the formula its docstring and the report print, so a change
to one without the other fails here; they re-type the formula and therefore pin nothing about
the design itself.  The independent checks are elsewhere: the laws composed with the plant give
the hand-derived closed loops of ``tests/oracles.py`` and python-control's interconnection
(``tests/synthesis/test_closed_loop.py``, ``tests/synthesis/test_pid.py``).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.families import pid_servo, pid_tracking
from designkit.spec.sections import AntiWindup
from tests.simulation.helpers import TRACKING, design_of, make_spec

value = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False)
NO_MEMORY = np.zeros(0)


@settings(max_examples=40, deadline=None)
@given(y1=value, y2=value, x3=value, xD=value, xDd=value, xDdd=value)
def test_servo_and_tracking_commands(y1, y2, x3, xD, xDd, xDdd):
    y, r = [y1, y2], [xD, xDd, xDdd]
    servo = design_of(make_spec())
    g = servo.gains
    expected = -g["K1"] * (y1 - xD) - g["K2"] * y2 - g["K3"] * x3 + g["K3"] * g["K4"] * xD
    assert float(pid_servo.law(servo).command(y, x3, NO_MEMORY, r)) == pytest.approx(expected, rel=1e-12, abs=1e-9)
    track = design_of(make_spec(TRACKING))
    g, km, tau = track.gains, track.plant.Km, track.plant.tau
    expected = (tau / km) * xDdd + y2 / km - g["K1"] * (y1 - xD) - g["K2"] * (y2 - xDd) - g["K3"] * x3
    law = pid_tracking.law(track)
    assert float(law.command(y, x3, NO_MEMORY, r)) == pytest.approx(expected, rel=1e-12, abs=1e-9)
    assert float(law.derivative(y, x3, NO_MEMORY, r, 1.0)) == pytest.approx(y1 - xD, abs=1e-12)
    assert float(law.derivative(y, x3, NO_MEMORY, r, 0.0)) == 0.0


def test_anti_windup_gate_and_clamp():
    design = design_of(make_spec())
    k3 = design.gains["K3"]
    gated = pid_servo.law(design, AntiWindup(kind="threshold", value=0.2))
    assert float(gated.gate([1.1, 0.0], 0.0, NO_MEMORY, [1.0, 0, 0])) == 1.0
    assert float(gated.gate([1.3, 0.0], 0.0, NO_MEMORY, [1.0, 0, 0])) == 0.0
    assert float(gated.project(123.0)) == 123.0
    clamped = pid_servo.law(design, AntiWindup(kind="saturation", value=7.0))
    assert float(clamped.project(1.0)) == pytest.approx(7.0 / k3)
    assert float(clamped.project(-1.0)) == pytest.approx(-7.0 / k3)
    assert float(clamped.project(0.01)) == 0.01
    assert float(pid_servo.law(design).gate([5.0, 0.0], 0.0, NO_MEMORY, [0.0, 0, 0])) == 1.0


def test_functions_are_named_and_the_memory_is_empty():
    law = pid_servo.law(design_of(make_spec()))
    assert law.command.name() == "pid_servo_command" and law.command.name_in() == ["y", "xc", "m", "r"]
    assert law.n_memory == 0 and law.update.size1_out(0) == 0
    assert np.isclose(float(law.derivative([2.0, 0.0], 0.0, NO_MEMORY, [0.5, 0, 0], 1.0)), 1.5)
