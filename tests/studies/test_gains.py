"""The gain study runs each variant through the family's own run (designkit.studies.gains).

Independent routes: the static error that computed torque leaves under a model error, solved here with scipy for
each scale of K1 (the rows' final errors); the learning law's error after its trials, predicted from the lifted
model for each scaled learning gain (the rows of the ILC study, which learn over every trial); a destabilised
decentralized PID against the Routh condition on its joint loop.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.optimize

from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from designkit.studies.core.study import StudyContext
from designkit.studies.gains import STUDY

CT_MISMATCH = """\
name: gains-ct-mismatch
plant: {kind: robot, robot: planar2r}
controller: {kind: computed_torque, poles: [-20, -20], model: {parameters: {m2: 2.5}}}
simulation: {duration: 3.0, trajectory: {kind: quintic, amplitude: [1.0, -0.5], duration: 1.0}}
"""
# joint 2's loop on slow poles has K2 = -0.52 < 0: doubled, K2 < -1/Km2 and the Routh condition fails
PID_FRAGILE = """\
name: gains-pid-fragile
plant: {kind: robot, robot: planar2r}
controller: {kind: decentralized_pid, poles: [[-4, -5, -20], [-0.5, -1, -1.5]]}
simulation: {duration: 3.0, step: [0.2, 0.1], dt: 0.002}
"""


def _study(result, budget=60.0, settings=None):
    from designkit.families import family

    return STUDY.run(StudyContext(result, family(result.design.kind), settings, budget))


@pytest.fixture(scope="module")
def mismatch():
    result = run(parse_spec(CT_MISMATCH))
    return result, _study(result)


def test_the_unit_row_is_the_spec_s_own_run(mismatch):
    result, study = mismatch
    err = np.abs(np.asarray(result.simulation.tracking_errors))
    for entry in study.entries:
        nominal = next(r for r in entry.rows if r.factor == 1.0)
        assert [r.factor for r in entry.rows] == [0.5, 1.0, 2.0]
        assert nominal.metrics["error_peak"] == float(np.max(err))
        assert nominal.metrics["error_final"] == float(np.max(err[-1]))
        assert nominal.outcome == ("verified" if result.verified else nominal.outcome)


def test_scaled_K1_runs_end_at_the_static_error_of_the_scaled_gain(mismatch):
    """At rest computed torque gives ``M^(q) K1 (qD - q) + g^(q) = g(q)``: solved here for each scale of K1."""
    result, study = mismatch
    plant, model = result.plant, result.design.plant
    qD = np.asarray(result.simulation.desired)[-1]
    K1 = np.asarray(result.design.gains["K1"], dtype=float)
    entry = next(e for e in study.entries if e.parameter == "K1")
    finals = {}
    for r in entry.rows:
        assert r.outcome in ("verified", "failed")  # the run itself stays finite and is judged by its checks

        def residual(q, k1=r.factor * K1):
            M = model.robot.mass_matrix(q, p=model.model_parameters())
            gm = model.robot.gravity_torque(q, p=model.model_parameters())
            g = plant.robot.gravity_torque(q, p=plant.model_parameters())
            return M @ (k1 * (qD - q)) + gm - g

        q = scipy.optimize.fsolve(residual, qD, xtol=1e-13)
        expected = float(np.max(np.abs(qD - q)))
        assert r.metrics["error_final"] == pytest.approx(expected, rel=1e-4, abs=1e-9), (r.factor, expected)
        finals[r.factor] = r.metrics["error_final"]
    assert finals[0.5] > 1.5 * finals[1.0] > 2.25 * finals[2.0]  # the static error scales as 1/K1
    text = " ".join(s for q in study.section.questions for s in q.sentences)
    assert "Halving K1" in text and "Doubling K1" in text


def test_a_destabilizing_gain_is_a_row_that_fails_and_says_why():
    result = run(parse_spec(PID_FRAGILE))
    study = _study(result)
    k2 = next(e for e in study.entries if e.parameter == "K2")
    doubled = next(r for r in k2.rows if r.factor == 2.0)
    # the independent condition: K2_2 doubled is below -1/Km2, so joint 2's loop has a root in the right half plane
    loop = result.design.loops[1]
    km = result.design.data.links[1].Km
    assert 2 * float(loop.gains["K2"]) < -1.0 / km
    assert doubled.outcome in ("failed", "diverged") and doubled.detail
    assert any(r.factor == 0.5 and r.outcome == "verified" for r in k2.rows) or not result.verified
    sentence = next(s for q in study.section.questions for s in q.sentences if s.startswith("Doubling K2"))
    assert "fails" in sentence or "diverges" in sentence


def test_a_budget_too_small_for_every_variant_reduces_the_study_and_says_so(mismatch):
    result, _ = mismatch
    study = _study(result, budget=1e-3)
    assert study.runs == 1 and study.reduced
    assert "raise studies.budget" in study.reduced
    assert "Reduced:" in study.section.intro


def test_learning_gain_rows_learn_over_the_trials():
    """Each scaled learning gain's row is the error after all its trials (not one trial with no learning): the
    lifted model predicts e_N = (I - Q H)^N e_0 per joint, from the first trial's measured error."""
    from designkit.families.ilc.learning import lifted_errors, lifted_of
    from designkit.studies.gains import GainsSettings

    spec = parse_spec(ILC_EXACT)
    result = run(spec)
    # away from alpha = 2 / sigma_max^2, where the slowest direction of I - Q H stops contracting
    study = _study(result, settings=GainsSettings(knobs=["alpha"], factors=[0.5, 1.5]))
    entry = next(e for e in study.entries if e.parameter == "alpha")
    e0 = lifted_errors(result.trials.results[0])  # (n, L): what the learning sees of the first trial
    lifted = lifted_of(result.design, result.simulation.time)
    trials = result.trials.results.__len__()
    alpha0 = float(result.design.gains["alpha"])
    lasts = {}
    for r in entry.rows:
        e = e0.copy()
        for _ in range(trials - 1):
            e = e - r.factor * alpha0 * lifted.apply(lifted.apply_transpose(e))
        predicted = float(np.max(np.abs(e)))
        lasts[r.factor] = r.metrics["last_trial_error"]
        assert r.metrics["last_trial_error"] == pytest.approx(predicted, rel=0.05, abs=1e-6), (r.factor, predicted)
    assert len({round(v, 12) for v in lasts.values()}) == 3  # three different learnings, three different errors
    assert not math.isclose(lasts[0.5], lasts[1.5])


# The SIMNOG arm with an exact model and a constant load the model does not know: d = M^-1 f is the same every
# trial, so the lifted model describes the trials exactly up to the integration.
ILC_EXACT = """\
name: gains-ilc-exact
plant: {kind: robot, robot: planar2r}
controller: {kind: ilc, poles: [-20, -20], trials: 8, learning: {kind: adjoint}}
requirements: {tracking_error: 0.01}
simulation:
  duration: 2.0
  dt: 0.002
  trajectory: {kind: quintic, amplitude: [1.0, -0.5], duration: 1.0}
  perturbation: {value: [2.0, 1.0], time: 0.0}
"""
