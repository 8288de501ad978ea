"""The ideal linear step response."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.simulation.linear import linear_step
from tests.simulation.helpers import TRACKING, design_of, make_spec


def test_servo_step_has_unit_dc_gain_and_starts_at_the_feedforward_control():
    design = design_of(make_spec())
    t, x1, u = linear_step(design, 5.0, n=1001)
    assert t.shape == (1001,) and x1.shape == u.shape == (1001, 1)
    x1, u = x1[:, 0], u[:, 0]
    assert x1[0] == 0.0 and x1[-1] == pytest.approx(1.0, abs=1e-6)
    g = design.gains
    assert u[0] == pytest.approx(g["K1"] + g["K3"] * g["K4"])  # D of the closed loop
    assert u[-1] == pytest.approx(0.0, abs=1e-5)


def test_tracking_step_and_amplitude():
    design = design_of(make_spec(TRACKING))
    _, x1, _ = linear_step(design, 3.0, amplitude=2.0)
    assert x1[-1, 0] == pytest.approx(2.0, abs=1e-4)
    assert np.all(np.isfinite(x1))
