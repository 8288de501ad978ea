"""``plant.uncertainty`` on the sliding-mode identification: judged by its own run at the box's corners
(``box_runs``)."""

from __future__ import annotations

from designkit.pipeline import run
from designkit.schema.loader import parse_spec

SPEC = """\
name: smid-box
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: %s}
controller: {kind: sliding_mode_identification, servo: {K1: 5.0, K2: 0.5}, initial_estimates: [1.0, 1.0],
             error_bounds: {a: 3.0, b: 5.0}, window: 0.25, adaptation_gains: [1.0, 1.0], sampling_period: 0.002}
simulation: {duration: 10, trajectory: {kind: square, amplitude: 0.5, period: 2}}
"""


def _box_runs(result):
    return next(c for c in result.checks if c.name == "box_runs")


def test_a_wide_box_fails_where_the_stated_error_bounds_do_not_cover_the_link():
    result = run(parse_spec(SPEC % "{Km: [0.01, 100], tau: [0.01, 100]}"))
    check = _box_runs(result)
    assert check.passed is False and not result.verified and check.certificate["runs"] == 4
    for row in check.certificate["plants"]:
        # own route: the link x2' = -a x2 + b u has a = 1/tau, b = Km/tau; the observer's premise is that the initial
        # estimates (1, 1) are within the stated error bounds (3, 5) of them
        a, b = 1.0 / row["tau"], row["Km"] / row["tau"]
        covered = abs(a - 1.0) <= 3.0 and abs(b - 1.0) <= 5.0
        if not covered:
            assert "switching_condition" in row["failed"], row


def test_a_narrow_box_passes_with_its_count():
    result = run(parse_spec(SPEC % "{Km: [1.9, 2.1], tau: [0.48, 0.52]}"))
    check = _box_runs(result)
    assert check.passed is True and result.verified and check.certificate["runs"] == 4
    assert "verified at all 4 plants of the box (4 corners)" in check.detail
