"""A model-based law tuned: computed torque's error poles (specs/tune-simnog-computed-torque.yaml) for a tracking
error over a payload box under a 10 ms sampled implementation, confirmed by an independent sweep of the box."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import designkit as dk
from tests.tuning.specs import write
from tests.tuning.test_space import _space

SPEC = Path(__file__).resolve().parents[2] / "specs" / "tune-simnog-computed-torque.yaml"

TASK = """\
name: ra-tune
plant: {kind: robot, robot: planar2r}
controller: {kind: resolved_acceleration, poles: [-10, -12]}
requirements: {tracking_error: 0.01}
simulation:
  duration: 1.0
  trajectory: {kind: line, displacement: [0.1, 0.1, 0.0], duration: 1.0}
  initial_position: [0.3, 1.2]
"""


def test_computed_torque_and_resolved_acceleration_tune_their_error_poles():
    for text in (SPEC.read_text(encoding="utf-8"), TASK):
        _, space = _space(text)
        assert [c.label for c in space.coordinates] == ["poles[0]", "poles[1]"]
        x = space.x0 + np.log([2.0, 3.0])
        assert space.changes(x) == [("controller.poles", pytest.approx([-2 * space.coordinates[0].initial,
                                                                           -3 * space.coordinates[1].initial]))]


def test_a_spec_giving_damping_and_natural_frequency_has_nothing_to_tune(tmp_path):
    text = SPEC.read_text(encoding="utf-8").replace("poles: [-20, -20]", "damping: 1.0, natural_frequency: 20")
    with pytest.raises(dk.errors.SpecError, match="tune: .*poles: not given in the spec"):
        dk.tune(write(tmp_path, text), out=tmp_path, budget=1.0)


@pytest.mark.slow  # about 40 s: a search of 25 s and two sweeps
def test_the_error_poles_are_tuned_and_the_box_sweep_passes(tmp_path):
    result = dk.tune(SPEC, out=tmp_path, budget=25.0)
    assert result.initial.margins["tracking_error"] < 0  # -20, -20 leave 0.03 rad at m2 = 4 kg
    assert result.verified and result.met
    poles = np.asarray(result.best.values["poles"], dtype=complex)
    assert np.all(poles.real < -20) and np.all(np.abs(poles) * 0.01 < 2)  # faster, yet well inside the sampling
    # the sweep's own sampling of the box: the spec as given fails somewhere, the tuned spec nowhere, and its
    # worst tracking error is within the requirement
    before = dk.sweep(SPEC, samples=8, seed=5, engine="process", falsification=False, report=False)
    after = dk.sweep(result.files["spec"], samples=8, seed=5, engine="process", falsification=False, report=False)
    assert before.n_passed < before.samples
    assert after.n_passed == after.samples == 8
    k = after.requirements.index("tracking_error")
    assert after.margin[:, k].min() > 0
