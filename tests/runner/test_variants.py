"""Variants of a comparison's member: with nothing changed, the member's own run bit for bit (its canonical text writes
every default out, and a default written out is not the same spec: ``numerics.integrator`` given chooses the
integrator); a scenario variant keeps the member's own design."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from designkit.pipeline import run
from designkit.runner.run import run_spec
from designkit.runner.variants import changed_spec, vary_scenario
from designkit.schema.loader import load_spec

ROBEL = Path(__file__).resolve().parents[2] / "specs" / "robel.yaml"


@pytest.fixture(scope="module")
def comparison():
    return run(load_spec(ROBEL))


def test_a_member_unchanged_is_its_own_run(comparison):
    for label in ("pid", "sliding-regulator"):  # a smooth loop (the poles choose dopri5) and a switching one (RK4)
        member = comparison[label]
        again = run_spec(changed_spec(member.loaded, []), plant=member.plant)
        assert "integrator" not in again.loaded.spec.numerics.model_fields_set
        assert again.simulation.settings["integrator"] == member.simulation.settings["integrator"]
        np.testing.assert_array_equal(again.simulation.state, member.simulation.state)


def test_a_scenario_variant_keeps_the_members_design(comparison):
    member = comparison["sliding-regulator"]  # its relay is sized from the load
    moved = vary_scenario(member, (("simulation.perturbation.time", 1e9),))
    assert moved.design is member.design
    t, t0 = np.asarray(moved.simulation.time), np.asarray(member.simulation.time)
    before = t < 2.5  # before the load, the same loop (its held step differs by 1e-5 relative: the member's grid
    x3 = np.interp(t[before], t0, np.asarray(member.simulation.state)[:, 2])  # lands on the load's onset)
    assert np.max(np.abs(np.asarray(moved.simulation.state)[before, 2] - x3)) < 1e-4
    assert np.all(np.asarray(moved.simulation.perturbation, dtype=float) == 0.0)  # never felt within the run
