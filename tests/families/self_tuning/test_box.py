"""``plant.uncertainty`` on the self-tuning regulator: judged by its own run at the box's corners (``box_runs``)."""

from __future__ import annotations

import numpy as np

from designkit.pipeline import run
from designkit.schema.loader import parse_spec

SPEC = """\
name: selftune-box
plant: {kind: link, %s}
controller: {kind: self_tuning, sampling_period: 0.01, estimator: position, forgetting: 0.99,
             initial_covariance: 100, poles: [-4, -5], nominal: {Km: 1.0, tau: 1.0}}
requirements: {overshoot: 20}
simulation: {duration: 12, trajectory: {kind: square, amplitude: 0.5, period: 4}}
"""


def _box_runs(result):
    return next(c for c in result.checks if c.name == "box_runs")


def _overshoot(sim) -> float:
    """Own count: the largest excursion of x1 past the first square-wave level, in % of the step from rest."""
    t = np.asarray(sim.time)
    x = np.asarray(sim.state)[:, 0]
    first = t < 2.0  # the first half period: a step from 0 to +0.5 rad
    return float(100.0 * max(0.0, x[first].max() / 0.5 - 1.0))


def test_a_wide_box_fails_and_its_failing_corner_fails_on_its_own():
    result = run(parse_spec(SPEC % "Km: 2.0, tau: 0.5, uncertainty: {Km: [0.01, 100], tau: [0.01, 100]}"))
    check = _box_runs(result)
    assert check.passed is False and not result.verified
    assert check.certificate["runs"] == 4 and "4 corners" in check.detail
    row = next(r for r in check.certificate["plants"] if (r["Km"], r["tau"]) == (100.0, 0.01))
    assert "overshoot" in row["failed"]
    # independent route: that link alone (the controller's nominal model is given, so the design is the same);
    # the overshoot measured here from the run's samples, not by the time-domain check
    alone = run(parse_spec(SPEC % "Km: 100, tau: 0.01"))
    assert alone.design.gains == result.design.gains
    assert _overshoot(alone.simulation) > 20.0


def test_a_narrow_box_passes_with_its_count():
    result = run(parse_spec(SPEC % "Km: 2.0, tau: 0.5, uncertainty: {Km: [1.5, 2.5], tau: [0.4, 0.6], samples: 1}"))
    check = _box_runs(result)
    assert check.passed is True and result.verified and check.certificate["runs"] == 5
    assert "verified at all 5 plants of the box (4 corners and 1 seeded samples" in check.detail
