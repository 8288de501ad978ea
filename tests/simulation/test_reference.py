"""References: analytic derivatives, boundary conditions, dispatch."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.errors import SpecError
from designkit.simulation.reference import quintic, reference_for, sine, step_reference
from designkit.spec.schema import Simulation


@pytest.mark.parametrize("ref", [quintic(0.8, 1.5), sine(0.3, 0.7)], ids=["quintic", "sine"])
def test_derivatives_match_finite_differences(ref):
    t = np.linspace(0.05, 1.4, 50)
    h = 1e-5
    fwd, bwd, mid = ref.evaluate(t + h), ref.evaluate(t - h), ref.evaluate(t)
    np.testing.assert_allclose((fwd[:, 0] - bwd[:, 0]) / (2 * h), mid[:, 1], rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose((fwd[:, 1] - bwd[:, 1]) / (2 * h), mid[:, 2], rtol=1e-6, atol=1e-7)


def test_quintic_is_rest_to_rest():
    ref = quintic(2.0, 1.0).evaluate(np.array([0.0, 1.0, 3.0]))
    np.testing.assert_allclose(ref, [[0, 0, 0], [2, 0, 0], [2, 0, 0]], atol=1e-12)


def test_dispatch():
    sim = Simulation(step=0.4)
    assert reference_for("step", sim).evaluate(np.zeros(2))[:, 0].tolist() == [0.4, 0.4]
    assert step_reference(1.0).horizon == 0.0
    assert reference_for("trajectory", sim).settings == {"kind": "quintic", "amplitude": 1.0, "duration": 1.0}
    with pytest.raises(SpecError, match="controller.kind"):
        reference_for("ramp", sim)
