"""The tuning space: coordinates of the family's spec knobs, their ranges, and the spec changes they give back."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families import family, synthesize
from designkit.schema.loader import parse_spec
from designkit.spec.plant_builder import plant_from_spec
from designkit.tuning.space import build_space
from tests.tuning.specs import LINK


def _space(text):
    loaded = parse_spec(text)
    design = synthesize(loaded.spec, plant_from_spec(loaded.spec.plant, None))
    return loaded, build_space(loaded, design, family(design.kind).knobs, loaded.spec.tune)


def test_real_poles_are_one_log_coordinate_each_within_a_decade():
    _, space = _space(LINK)
    assert [c.label for c in space.coordinates] == ["poles[0]", "poles[1]", "poles[2]"]
    bounds = np.array([(c.low, c.high) for c in space.coordinates], dtype=float)
    np.testing.assert_allclose(bounds, [(0.4, 40), (0.5, 50), (2, 200)], rtol=1e-12)
    assert space.x0 == pytest.approx(np.log([4, 5, 20]))
    assert space.changes(space.x0) == [("controller.poles", pytest.approx([-4.0, -5.0, -20.0]))]
    assert "zero: fixed by tune.fixed" in space.kept and any(k.startswith("K1:") for k in space.kept)


def test_a_derived_pair_keeps_its_structure_and_the_zero_is_written():
    text = LINK.replace("poles: [-4, -5, -20], zero: -3", "third_pole_factor: 5").replace(
        "tune: {fixed: [zero]}", "tune: {ranges: {zero: [1, 100]}}")
    loaded, space = _space(text)
    design = synthesize(loaded.spec, plant_from_spec(loaded.spec.plant, None))
    pair = max(design.poles, key=lambda p: p.imag)
    assert [c.label for c in space.coordinates] == ["Re poles[0]", "Im poles[0]", "poles[1]", "zero"]
    assert space.coordinates[0].initial == pytest.approx(-pair.real)
    assert space.coordinates[1].initial == pytest.approx(pair.imag)
    assert (space.coordinates[3].low, space.coordinates[3].high) == (1.0, 100.0)
    x = space.x0 + np.log([2.0, 0.5, 1.0, 1.0])
    poles = dict(space.changes(x))["controller.poles"]
    assert poles[0] == pytest.approx(complex(2 * pair.real, 0.5 * pair.imag))
    assert poles[1] == pytest.approx(poles[0].conjugate())
    # the zero the family put on the third pole starts a hair off it: a spec may not name a zero equal to a pole
    zero = dict(space.changes(space.x0))["controller.zero"]
    assert zero != poles[2].real and zero == pytest.approx(poles[2].real, rel=1e-5)


def test_one_zero_per_joint_is_tuned_per_joint_and_a_pole_set_per_joint_is_kept():
    text = """\
name: arm
plant: {kind: robot, robot: planar2r}
controller: {kind: decentralized_pid, poles: [[-4, -5, -20], [-3, -6, -12]], zero: [-3, -2]}
requirements: {overshoot: 5}
"""
    _, space = _space(text)
    assert [c.label for c in space.coordinates] == ["zero[0]", "zero[1]"]  # the family's poles knob: one set
    assert dict(space.changes(space.x0)) == {"controller.zero": pytest.approx([-3, -2])}
    _, shared = _space(text.replace("[[-4, -5, -20], [-3, -6, -12]]", "[-4, -5, -20]"))
    assert [c.label for c in shared.coordinates] == ["poles[0]", "poles[1]", "poles[2]", "zero[0]", "zero[1]"]
