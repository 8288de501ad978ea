"""Control laws: the CasADi Functions implement the formulas of designkit.synthesis.pid."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.errors import SpecError
from designkit.simulation.laws import LAWS, law_for
from designkit.spec.schema import AntiWindup
from designkit.synthesis.design import Design
from tests.simulation.helpers import TRACKING, design_of, make_spec

value = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False)


@settings(max_examples=40, deadline=None)
@given(y1=value, y2=value, x3=value, xD=value, xDd=value, xDdd=value)
def test_servo_and_tracking_commands(y1, y2, x3, xD, xDd, xDdd):
    y, r = [y1, y2], [xD, xDd, xDdd]
    servo = design_of(make_spec())
    g = servo.gains
    expected = -g["K1"] * (y1 - xD) - g["K2"] * y2 - g["K3"] * x3 + g["K3"] * g["K4"] * xD
    assert float(law_for(servo).command(y, x3, r)) == pytest.approx(expected, rel=1e-12, abs=1e-9)
    track = design_of(make_spec(TRACKING))
    g, km, tau = track.gains, track.plant.Km, track.plant.tau
    expected = (tau / km) * xDdd + y2 / km - g["K1"] * (y1 - xD) - g["K2"] * (y2 - xDd) - g["K3"] * x3
    law = law_for(track)
    assert float(law.command(y, x3, r)) == pytest.approx(expected, rel=1e-12, abs=1e-9)
    assert float(law.derivative(y, x3, r, 1.0)) == pytest.approx(y1 - xD, abs=1e-12)
    assert float(law.derivative(y, x3, r, 0.0)) == 0.0


def test_anti_windup_gate_and_clamp():
    design = design_of(make_spec())
    k3 = design.gains["K3"]
    gated = law_for(design, AntiWindup(kind="threshold", value=0.2))
    assert float(gated.gate([1.1, 0.0], 0.0, [1.0, 0, 0])) == 1.0
    assert float(gated.gate([1.3, 0.0], 0.0, [1.0, 0, 0])) == 0.0
    assert float(gated.project(123.0)) == 123.0
    clamped = law_for(design, AntiWindup(kind="saturation", value=7.0))
    assert float(clamped.project(1.0)) == pytest.approx(7.0 / k3)
    assert float(clamped.project(-1.0)) == pytest.approx(-7.0 / k3)
    assert float(clamped.project(0.01)) == 0.01
    assert float(law_for(design).gate([5.0, 0.0], 0.0, [0.0, 0, 0])) == 1.0


def test_registry_covers_every_controller_family_and_rejects_unknown_kinds():
    from designkit.synthesis.registry import FAMILIES

    assert set(FAMILIES) <= set(LAWS)
    design = design_of(make_spec())
    other = Design(kind="sliding_mode", plant=design.plant, gains={}, poles=(), zeros=(),
                   closed_loop=design.closed_loop)
    with pytest.raises(SpecError, match="controller.kind"):
        law_for(other)


def test_functions_are_named():
    law = law_for(design_of(make_spec()))
    assert law.command.name() == "pid_servo_command" and law.command.name_in() == ["y", "xc", "r"]
    assert np.isclose(float(law.derivative([2.0, 0.0], 0.0, [0.5, 0, 0], 1.0)), 1.5)
