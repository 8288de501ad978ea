"""The Dormand--Prince pair with a law's resets (``Law.project_resets``: the adaptive computed torque's projection
with hysteresis): applied at every grid instant, the integration started again where it moved the state.  Checked
against the fixed-step route, which applies the same projection after every RK4 step (its own code,
simulation/step.py), and against the interpreted driver."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from designkit.families import synthesize
from designkit.families.adaptive_computed_torque.laws import estimates
from designkit.models.codegen import find_compiler
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build

SPECS = Path(__file__).resolve().parents[2] / "specs"
LOW = 6.2
"""The lower bound of m1 here: the estimate, from 7 kg towards the true 5 kg, leaves it by delta within 1.2 s."""


def _run(extra: str = ""):
    text = (SPECS / "adaptive-ct-simnog.yaml").read_text()
    text = text.replace("m1: [4.0, 10.0]", f"m1: [{LOW}, 10.0]").replace("duration: 20.0", "duration: 2.0")
    spec = parse_spec(text + extra)
    sim = build(spec, synthesize(spec))
    return sim, sim.run()


@pytest.mark.skipif(find_compiler() is None, reason="the compiled pair")
def test_resets_at_grid_instants_agree_with_the_fixed_step_route():
    sim, pair = _run()
    assert str(sim.settings["integrator"]).startswith("dopri5")
    assert "projection applied at every grid instant" in str(sim.settings["integrator"])
    _, rk4 = _run("numerics: {integrator: rk4}\n")
    m1 = estimates(pair, ("m1", "m2"))[:, 0]
    resets = np.flatnonzero(m1 == LOW)
    assert resets.size >= 3  # the projection acted, more than once
    assert np.all(m1 > LOW - 0.05)  # never left by delta at a grid instant
    np.testing.assert_array_equal(resets, np.flatnonzero(estimates(rk4, ("m1", "m2"))[:, 0] == LOW))
    # the same run within the fixed step's own error (RK4 at dt = 0.25 ms: about 1e-7 here)
    np.testing.assert_allclose(np.asarray(pair.state), np.asarray(rk4.state), rtol=0, atol=1e-6)
    np.testing.assert_allclose(estimates(pair, ("m1", "m2")), estimates(rk4, ("m1", "m2")), rtol=0, atol=1e-6)


@pytest.mark.skipif(find_compiler() is None, reason="the compiled pair")
def test_the_interpreted_driver_resets_at_the_same_instants():
    _, compiled = _run()
    _, interpreted = _run("numerics: {compile: never}\n")
    a, b = estimates(compiled, ("m1", "m2")), estimates(interpreted, ("m1", "m2"))
    np.testing.assert_array_equal(np.flatnonzero(a[:, 0] == LOW), np.flatnonzero(b[:, 0] == LOW))
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-11)
    np.testing.assert_allclose(np.asarray(compiled.state), np.asarray(interpreted.state), rtol=0, atol=1e-11)
