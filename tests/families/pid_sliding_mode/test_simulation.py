"""Runs of the family at random interior plants of ``plant.uncertainty`` (hypothesis): the loop reaches the band
around slm = 0 and stays in it after the reaching time (the invariant, not a pointwise trajectory), and the
position stays within ||s/N||_1 max|slm| of the plant-independent sliding motion."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from designkit.families.pid_sliding_mode.measure import measure
from designkit.pipeline import run
from designkit.schema.loader import parse_spec

SPEC = """\
name: pid-sm-random-plant
plant: {{kind: link, Km: 2.0, tau: 0.5, uncertainty: {{Km: [1.4, 2.6], tau: [0.35, 0.65]}}}}
controller: {{kind: pid_sliding_mode, poles: [-4, -5, -20], perturbation_bound: 0.5{layer}}}
simulation:
  duration: 2.0
  perturbation: {{value: {load}, time: 0.5}}
  plant_change: {{time: 0.0, values: {{Km: {Km}, tau: {tau}}}}}
"""


def _run(Km: float, tau: float, load: float, layer: str = ""):
    return run(parse_spec(SPEC.format(Km=Km, tau=tau, load=load, layer=layer)))


def _check(result, name):
    return next(c for c in result.checks if c.name == name)


interior = st.tuples(st.floats(1.45, 2.55), st.floats(0.36, 0.64), st.floats(-0.5, 0.5))


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(interior, st.sampled_from(["", ", epsilon: 0.002", ", epsilon: 0.002, layer: dead_zone"]))
def test_random_interior_plants_reach_the_band_and_stay_in_it(plant, layer):
    Km, tau, load = plant
    result = _run(round(Km, 4), round(tau, 4), round(load, 4), layer)
    m = measure(result.design, result.simulation)
    assert m.reach is not None
    slm = m.data["slm"][m.reach:]
    assert np.all(np.abs(slm) <= m.band * (1 + 1e-9))
    assert m.deviation <= m.deviation_bound * (1 + 1e-3) + 1e-12
    assert all(c.passed for c in result.checks if c.name.startswith("pid_sm_") and c.required)


def test_the_layer_leaves_slm_near_eps_xi_over_M_and_the_integral_removes_the_error():
    """With sat(slm/eps) and a constant load, slm settles at g xi/(|p3| + g M/eps) < eps xi/M, and the position
    returns onto the sliding motion (the integral is in slm)."""
    result = _run(2.0, 0.5, 0.5, ", epsilon: 0.002")
    info = result.design.data
    slm = np.asarray(result.simulation.signals["slm"], float)
    g = info.a2 * 2.0 / 0.5
    expected = g * 0.5 / (abs(info.p3) + g * info.M / 0.002)
    assert slm[-1] == pytest.approx(expected, rel=1e-3)
    assert abs(slm[-1]) < 0.002 * 0.5 / info.M
    data = measure(result.design, result.simulation).data
    assert abs(data["x1"][-1] - data["x1_ideal"][-1]) < 1e-4  # on the plant-independent motion to 0.1 mrad


def test_a_relay_below_the_bound_leaves_the_layer_after_the_plant_change():
    result = _run(1.4, 0.65, 0.0, ", epsilon: 0.002, M: 1.0")
    assert _check(result, "pid_sm_relay").passed is False
    assert _check(result, "pid_sm_in_band").passed is False


def test_tracking_form_follows_a_quintic_at_an_interior_plant_within_the_layer():
    """Figure 3.2: the tracker's gains (K2 = -tau S1/Km, not the servo's), and the run at Km = 1.6, tau = 0.6 stays
    in the layer with x1 within ||s/N||_1 max|slm| of the trajectory itself (the sliding motion is dx1 = 0)."""
    text = """\
name: pid-sm-tracking
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.4, 2.6], tau: [0.35, 0.65]}}
controller: {kind: pid_sliding_mode, form: tracking, poles: [-10, -12, -15], epsilon: 0.0005, perturbation_bound: 0.5}
simulation:
  duration: 2.0
  trajectory: {kind: quintic, amplitude: 1.0, duration: 1.0}
  perturbation: {value: 0.5, time: 1.2}
  plant_change: {time: 0.0, values: {Km: 1.6, tau: 0.6}}
"""
    result = run(parse_spec(text))
    g = result.design.gains
    assert float(g["K2"]) == pytest.approx(0.5 * 37 / 2.0) and float(g["K1"]) == pytest.approx(0.5 * 450 / 2.0)
    m = measure(result.design, result.simulation)
    assert m.reach == 0 and m.worst <= 0.0005
    ref = np.asarray(result.simulation.reference[:, 0, 0], float)
    assert np.max(np.abs(m.data["x1"] - ref)) <= m.deviation_bound * (1 + 1e-3) + 1e-12
