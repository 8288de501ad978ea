"""Nonlinear elements: CasADi against the NumPy reference, and their defining properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.errors import SpecError
from designkit.simulation.nonlinear import dead_zone, element_for, identity, quantizer, relay, saturation

finite = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False)
positive = st.floats(min_value=1e-3, max_value=1e2, allow_nan=False)


def _casadi(element, u, m):
    v, m_next = element.function(u, m)
    return float(v), np.asarray(m_next, float).ravel()


@settings(max_examples=60, deadline=None)
@given(u=finite, limit=positive, width=positive, step=positive)
def test_memoryless_elements_match_numpy(u, limit, width, step):
    for element in (identity(), saturation(limit), dead_zone(width), quantizer(step)):
        v, _ = _casadi(element, u, np.zeros(0))
        ref, _ = element.reference(np.array([u]), np.zeros(0))
        assert v == pytest.approx(float(ref[0]), rel=1e-12, abs=1e-12), element.kind


@settings(max_examples=60, deadline=None)
@given(u=finite, memory=st.sampled_from([-3.0, 0.0, 3.0]), hysteresis=st.floats(0.0, 10.0))
def test_relay_matches_numpy(u, memory, hysteresis):
    element = relay(3.0, hysteresis)
    v, m_next = _casadi(element, u, np.array([memory]))
    ref_v, ref_m = element.reference(np.array([u]), np.array([memory]))
    assert v == float(ref_v[0]) and m_next[0] == float(ref_m[0]) == v


def test_relay_hysteresis_keeps_its_last_output_inside_the_band():
    element = relay(amplitude=2.0, hysteresis=0.5)
    inputs = [0.0, 0.4, 0.6, 0.4, 0.0, -0.4, -0.6, -0.4, 0.0, 0.49, 0.51]
    expected = [0.0, 0.0, 2.0, 2.0, 2.0, 2.0, -2.0, -2.0, -2.0, -2.0, 2.0]
    m = np.array(element.initial_memory)
    outputs = []
    for u in inputs:
        v, m = _casadi(element, u, m)
        outputs.append(v)
    assert outputs == expected


def test_quantizer_levels_and_ties():
    q = quantizer(0.25)
    u = np.array([0.0, 0.12, 0.125, 0.13, -0.125, -0.13, 1.0, -0.37, 0.374])
    v, _ = q.reference(u, np.zeros(0))
    np.testing.assert_array_equal(v, [0.0, 0.0, 0.25, 0.25, 0.0, -0.25, 1.0, -0.25, 0.25])
    for ui, vi in zip(u, v, strict=True):
        assert _casadi(q, ui, np.zeros(0))[0] == vi


def test_dead_zone_and_saturation_shapes():
    dz, sat = dead_zone(1.0), saturation(2.0)
    u = np.array([-3.0, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 3.0])
    np.testing.assert_array_equal(dz.reference(u, np.zeros(0))[0], [-2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 2.0])
    np.testing.assert_array_equal(sat.reference(u, np.zeros(0))[0], [-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0])


def test_continuity_flags_and_unknown_kind():
    assert saturation(1.0).continuous and dead_zone(1.0).continuous and identity().continuous
    assert not quantizer(1.0).continuous and not relay(1.0, 0.0).continuous

    class Fake:
        kind = "backlash"

    with pytest.raises(SpecError, match="simulation.nonlinearity.kind"):
        element_for(Fake())
