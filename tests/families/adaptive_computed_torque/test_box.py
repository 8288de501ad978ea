"""``plant.uncertainty`` on the adaptive computed torque: the law copes with the parameters it adapts, so a box
that moves only those is judged by its own run designed for each arm of the box (``box_runs``), and a box that
moves a parameter it takes as known is refused."""

from __future__ import annotations

import pytest

from designkit.errors import SpecError
from designkit.models.robots.planar2r import DEFAULTS
from designkit.pipeline import run
from designkit.schema.loader import parse_spec

SPEC = """\
name: act-box
plant: {kind: robot, robot: planar2r%s}
controller: {kind: adaptive_computed_torque, poles: [-10, -10], adapt: [%s], initial: {m1: 7.0, m2: 4.5, fv1: 2.5},
             gain: 5.0, bounds: {m1: [4.0, 10.0], m2: [2.5, 6.0]}, delta: 0.05}
simulation: {duration: 8, trajectory: {kind: sine, amplitude: [1.0, 1.2], frequency: 0.5}}
"""
ADAPT = "m1, m2, fv1"


def _box_runs(result):
    return next(c for c in result.checks if c.name == "box_runs")


def test_a_mass_box_moves_the_first_moment_and_inertia_it_takes_as_known():
    # own route: a uniform link of mass m2 and length d2 pivoting at its joint has mcx2 = -m2 d2 / 2 (the centre of
    # mass half-way back along x) and Izz2 = I2 + m2 (d2 / 2)^2 (parallel axes): both move with m2
    d2, I2 = DEFAULTS["d2"], DEFAULTS["I2"]
    assert -1e-3 * d2 / 2 != -1e4 * d2 / 2 and I2 + 1e-3 * (d2 / 2) ** 2 != I2 + 1e4 * (d2 / 2) ** 2
    with pytest.raises(SpecError) as info:
        run(parse_spec(SPEC % (", uncertainty: {m2: [1.0e-3, 1.0e4]}", ADAPT)))
    assert info.value.path == "plant.uncertainty.m2"
    assert "mcx2" in str(info.value) and "Izz2" in str(info.value)


def test_the_cli_refuses_the_mass_box(tmp_path, capsys):
    from designkit.cli import main

    path = tmp_path / "act.yaml"
    path.write_text(SPEC % (", uncertainty: {m2: [1.0e-3, 1.0e4]}", ADAPT))
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("designkit: error: plant.uncertainty.m2: ")


def test_a_narrow_friction_box_of_an_adapted_parameter_passes_with_its_count():
    result = run(parse_spec(SPEC % (", uncertainty: {f1: [1.8, 2.2]}", ADAPT)))
    check = _box_runs(result)
    assert check.passed is True and result.verified and check.certificate["runs"] == 2
    assert "verified at all 2 plants of the box (2 corners)" in check.detail


def test_a_wide_friction_box_fails_and_its_failing_corner_fails_on_its_own():
    result = run(parse_spec(SPEC % (", uncertainty: {f1: [0.01, 100]}", ADAPT)))
    check = _box_runs(result)
    assert check.passed is False and not result.verified
    row = next(r for r in check.certificate["plants"] if r["f1"] == 100.0)
    assert not row["verified"]
    # independent route: the arm with f1 = 100 written in the spec, run without a box by the ordinary pipeline
    alone = run(parse_spec(SPEC % (", parameters: {f1: 100}", ADAPT)))
    assert not alone.verified
    assert {c.name for c in alone.failed} == set(row["failed"])
