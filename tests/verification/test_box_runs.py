"""The ``box_runs`` check: the family's own run at the corners and samples of the box, aggregated (planted runs),
and the runner's re-run at a point of the box (a real family)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from designkit.errors import SpecError
from designkit.models.link import LinkPlant
from designkit.schema.loader import parse_spec
from designkit.verification.check import Check
from designkit.verification.checks.box_runs import MAX_CORNERS, MAX_SAMPLES, RULE, box_points
from designkit.verification.robustness import Box
from designkit.verification.suite import Context

SPEC = """\
name: box
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: %s}
controller: {kind: self_tuning, sampling_period: 0.01, poles: [-4, -5], nominal: {Km: 1.0, tau: 1.0}}
simulation: {duration: 4, trajectory: {kind: square, amplitude: 0.5, period: 1}}
"""


class _Design:
    plant = LinkPlant(2.0, 0.5)


def _ctx(box: str, rerun) -> Context:
    spec = parse_spec(SPEC % box).spec
    return Context(spec, simulation=object(), rerun=rerun)


def _check(name: str, passed) -> Check:
    return Check(name=name, passed=passed, target="", achieved=None, margin=None, unit="", detail="")


def test_the_points_are_the_corners_then_the_seeded_samples():
    box = Box(names=("a", "b"), lo=(1.0, 10.0), hi=(2.0, 20.0), samples=3, seed=5)
    points, run, total, samples = box_points(box)
    assert (run, total, samples) == (4, 4, 3)
    corners = {tuple(p) for p in itertools.product((1.0, 2.0), (10.0, 20.0))}  # own count of the corners
    assert {tuple(p) for p in points[:4]} == corners
    rng = np.random.default_rng(5)
    np.testing.assert_array_equal(points[4:], np.array([1.0, 10.0]) + np.array([1.0, 10.0]) * rng.random((3, 2)))


def test_corners_and_samples_are_capped():
    k = 6
    box = Box(names=tuple(f"p{i}" for i in range(k)), lo=(0.0,) * k, hi=(1.0,) * k, samples=100, seed=1)
    points, run, total, samples = box_points(box)
    assert (run, total, samples) == (MAX_CORNERS, 2**k, MAX_SAMPLES)
    corners = points[:run]
    assert np.all((corners == 0.0) | (corners == 1.0)) and len({tuple(c) for c in corners}) == MAX_CORNERS
    np.testing.assert_array_equal(box_points(box)[0], points)  # seeded: the same choice every time


def test_every_plant_verified_passes_and_counts_the_runs():
    seen = []

    def rerun(values):
        seen.append(values)
        return (_check("a", True), _check("b", True))

    (c,) = RULE.run(_Design(), _ctx("{Km: [1.5, 2.5], tau: [0.4, 0.6], samples: 2}", rerun))
    assert c.passed is True and len(seen) == 6 and c.certificate["runs"] == 6
    assert "verified at all 6 plants of the box (4 corners and 2 seeded samples" in c.detail
    assert {(v["Km"], v["tau"]) for v in seen[:4]} == set(itertools.product((1.5, 2.5), (0.4, 0.6)))


def test_one_failing_plant_fails_the_box_and_is_named():
    def rerun(values):
        bad = values["Km"] == 2.5 and values["tau"] == 0.6
        return (_check("overshoot", not bad), _check("informational", False).__class__(
            name="informational", passed=False, target="", achieved=None, margin=None, unit="", detail="",
            required=False))

    (c,) = RULE.run(_Design(), _ctx("{Km: [1.5, 2.5], tau: [0.4, 0.6]}", rerun))
    assert c.passed is False
    assert "1 of 4 plants of the box fail" in c.detail and "(Km=2.5, tau=0.6) overshoot" in c.detail
    rows = c.certificate["plants"]
    assert [r["verified"] for r in rows].count(False) == 1  # the informational failure does not count


def test_an_undecided_plant_leaves_the_box_undecided():
    def rerun(values):
        return (_check("lyapunov", None if values["Km"] == 1.5 else True),)

    (c,) = RULE.run(_Design(), _ctx("{Km: [1.5, 2.5]}", rerun))
    assert c.passed is None and "undecided: lyapunov" in c.detail


def test_a_run_that_raises_fails_its_plant_but_bad_input_propagates():
    def rerun(values):
        if values["Km"] == 1.5:
            raise np.linalg.LinAlgError("SVD did not converge")
        return (_check("a", True),)

    (c,) = RULE.run(_Design(), _ctx("{Km: [1.5, 2.5]}", rerun))
    assert c.passed is False and "run raised LinAlgError: SVD did not converge" in c.detail

    def refused(values):
        raise SpecError("plant.uncertainty.Km", "refused")

    with pytest.raises(SpecError):
        RULE.run(_Design(), _ctx("{Km: [1.5, 2.5]}", refused))


def test_not_offered_without_a_box_or_a_rerun():
    assert not RULE.applies(_Design(), Context(parse_spec(SPEC.replace(", uncertainty: %s", "")).spec,
                                                simulation=object(), rerun=lambda v: ()))
    assert not RULE.applies(_Design(), _ctx("{Km: [1.5, 2.5]}", None))


def test_the_runner_reruns_the_nominal_design_on_each_plant_of_the_box():
    """A self-tuning run over a box: the re-run at a corner is the nominal design on the corner's link (the
    controller is not told), judged by the family's own checks."""
    from designkit import pipeline

    loaded = parse_spec(SPEC % "{Km: [1.8, 2.2], tau: [0.45, 0.55]}")
    result = pipeline.run(loaded)
    (c,) = [c for c in result.checks if c.name == "box_runs"]
    assert c.certificate["runs"] == 4 and c.certificate["corners"] == 4
    assert c.passed is all(r["verified"] for r in c.certificate["plants"])
    # the same corner run by hand: the nominal design on the corner's plant, its checks
    from designkit.runner.run import run_spec

    plant = pipeline.plant(loaded)
    design = pipeline.design(loaded, plant)
    corner = run_spec(loaded, plant=plant, design=design, actual=plant.with_params(Km=2.2, tau=0.55), box=False)
    assert corner.plant.parameter("Km").value == 2.2 and corner.design is design  # the controller is not told
    row = next(r for r in c.certificate["plants"] if (r["Km"], r["tau"]) == (2.2, 0.55))
    assert row["verified"] == corner.verified
