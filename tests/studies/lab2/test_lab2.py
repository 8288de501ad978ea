"""Lab experiment 2 as a comparison study: its section, and its numbers against independent runs of hand-written
specs (the perturbation, an adaptation gain, each modification of the gradient rule, the larger change).

The modifications themselves are checked against the same equations integrated by scipy's ``solve_ivp`` in
tests/families/mrac/test_modification.py; here, the study's rows are the runs of the hand-written modified specs.
"""

from __future__ import annotations

import numpy as np
import pytest

from designkit.comparison.answers import comparison_sections
from designkit.comparison.metrics import baseline_simulation, compute_metrics, rise_times
from designkit.families import family
from designkit.pipeline import run
from designkit.schema.loader import load_spec, parse_spec
from designkit.studies import STUDIES
from designkit.studies.core.members import amount
from tests.comparison.test_comparison import EXAMPLE, STEP

# mrac-vs-selftune.yaml's MRAC alone, written by hand: the family's own run of each variant must be this spec's run
MRAC = """\
name: mrac
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: mrac, poles: [-4, -5], gamma: GAMMA, Q: [1, 0.1]MODIFICATION}
simulation:
  duration: 40
  trajectory: {kind: square, amplitude: 0.5, period: 4}
  plant_change: {time: 20, values: {Km: 1.0CHANGE}}
"""
SELFTUNE = """\
name: selftune
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: self_tuning, sampling_period: 0.01, estimator: speed, forgetting: LAMBDA, initial_covariance: 100,
             poles: [-4, -5], nominal: {Km: 1.0, tau: 1.0}}
simulation:
  duration: 40
  trajectory: {kind: square, amplitude: 0.5, period: 4}
  plant_change: {time: 20, values: {Km: 1.0CHANGE}}
"""
# swing of the square wave: 1 rad, so the dead zone a study tries is 0.01 rad; the box is 4x either side of (20, 9)
MODIFICATIONS = {"normalized": "{kind: normalized}", "dead_zone": "{kind: dead_zone, width: 0.01}",
                 "projection": "{kind: projection, low: [5, 2.25], high: [80, 36]}"}


def _mrac(gamma: str = "10000", modification: str = "", change: str = "") -> str:
    mod = f", modification: {modification}" if modification else ""
    return MRAC.replace("GAMMA", gamma).replace("MODIFICATION", mod).replace("CHANGE", change)


@pytest.fixture(scope="module")
def comparison():
    return run(load_spec(EXAMPLE))


@pytest.fixture(scope="module")
def lab(comparison):
    return next(st for st in comparison.studies if st.name == "lab2")


def _entry(lab, parameter):
    return next(e for e in lab.entries if e.parameter == parameter)


def _question(lab, words):
    return next(q for q in lab.section.questions if words in q.question.lower())


def test_the_section_carries_its_experiment_number_and_answers_every_question(comparison, lab):
    sections = comparison_sections(comparison)
    assert [s.anchor for s in sections] == ["comparison-answers", "lab-2-comparison"]
    assert lab.title.startswith("Lab experiment 2 (notes, appendix A): ") and lab.section.title == lab.title
    titles = " ".join(q.question for q in lab.section.questions).lower()
    for words in ("adapt", "comparative difference", "adaptation parameters", "control strategies", "ad hoc",
                  "perturbation", "response time", "control level", "robust"):
        assert words in titles, words
    assert lab.reduced == "" and lab.runs > 0


def test_it_applies_by_the_families_traits():
    step = run(parse_spec(STEP))  # two PID servos: no adaptive family
    assert not STUDIES["lab2"].applies(step, None)
    assert {"adaptive", "model_reference"} <= family("mrac").traits
    assert {"adaptive", "certainty_equivalence"} <= family("self_tuning").traits


def test_adaptation_gain_rows_are_the_runs_of_the_changed_spec(lab):
    rows = {r.factor: r for r in _entry(lab, "mrac: gamma").rows}
    for factor, gamma in ((0.1, "1000"), (10.0, "100000")):
        alone = run(parse_spec(_mrac(gamma)))
        metrics = compute_metrics(alone.loaded.spec, alone.simulation, baseline_simulation(alone.loaded.spec,
                                                                                           alone.plant))
        row = rows[factor]
        assert row.value == pytest.approx(float(gamma))
        assert row.outcome == ("verified" if alone.verified else "failed")
        for key in ("rms_deviation", "reconvergence", "peak_command"):
            assert row.metrics[key] == pytest.approx(metrics[key], rel=1e-9), key
        assert row.metrics["model_error_rms"] == pytest.approx(family("mrac").metrics[0].value(alone), rel=1e-9)
    forgetting = {r.factor: r for r in _entry(lab, "selftune: forgetting").rows}
    alone = run(parse_spec(SELFTUNE.replace("LAMBDA", "0.95").replace("CHANGE", "")))
    metrics = compute_metrics(alone.loaded.spec, alone.simulation, baseline_simulation(alone.loaded.spec, alone.plant))
    assert forgetting[5.0].value == pytest.approx(0.95)
    assert forgetting[5.0].metrics["reconvergence"] == pytest.approx(metrics["reconvergence"], rel=1e-9)


@pytest.mark.parametrize("key", list(MODIFICATIONS))
def test_each_modification_row_is_the_run_of_the_modified_spec(lab, key):
    alone = run(parse_spec(_mrac(modification=MODIFICATIONS[key])))
    row = _entry(lab, f"mrac: {key}").rows[0]
    assert row.outcome == ("verified" if alone.verified else "failed")
    for metric in family("mrac").metrics:  # the error against the reference model, the parameters' drift, ...
        assert row.metrics[metric.key] == pytest.approx(metric.value(alone), rel=1e-9), metric.key
    question = _question(lab, "ad hoc")
    text = " ".join(question.sentences)
    drift = next(m for m in family("mrac").metrics if m.key == "parameter_drift")
    assert amount(drift.value(alone), "", 3) in text


def test_through_the_larger_change_the_projection_is_what_the_mrac_requires(lab):
    plain = _entry(lab, "mrac: larger change").rows[0]
    projected = _entry(lab, "mrac: projection through the larger change").rows[0]
    assert plain.outcome == "diverged" and projected.outcome == "verified"
    alone = run(parse_spec(_mrac(modification=MODIFICATIONS["projection"], change=", tau: 0.8")))
    assert alone.verified
    a = np.asarray(alone.simulation.controller_state[:, -2:], dtype=float)
    assert np.all(a >= [5.0 - 0.05, 2.25 - 0.05]) and np.all(a <= [80.05, 36.05])  # kept in the box
    diverging = run(parse_spec(_mrac(change=", tau: 0.8")))
    assert not np.all(np.isfinite(np.asarray(diverging.simulation.state, dtype=float)))
    text = " ".join(_question(lab, "ad hoc").sentences)
    assert "the projection on a box keeps every required check there: that is the modification it requires" in text


def test_the_larger_change_diverges_the_mrac_only(comparison, lab):
    text = EXAMPLE.read_text().replace("values: {Km: 1.0}", "values: {Km: 1.0, tau: 0.8}")
    larger = run(parse_spec(text))
    mrac = np.asarray(larger["mrac"].simulation.state, dtype=float)
    selftune = np.asarray(larger["selftune"].simulation.state, dtype=float)
    assert not np.all(np.isfinite(mrac)) or np.max(np.abs(mrac)) > 1e3
    assert np.all(np.isfinite(selftune)) and np.max(np.abs(selftune[:, 0])) < 1.0
    robust = _question(lab, "robust")
    rows = {r[0]: r for r in robust.tables[0].rows}
    assert rows["mrac"][-1] == "no" and rows["selftune"][-1] == "yes"
    assert rows["selftune"][1] == ("verified" if larger["selftune"].verified else "failed")


def test_perturbation_numbers_against_a_spec_with_the_perturbation(comparison, lab):
    text = EXAMPLE.read_text().replace("  plant_change:", "  perturbation: {value: 1.0, time: 31.0}\n  plant_change:")
    perturbed = run(parse_spec(text))
    rows = {r[0]: r for r in _question(lab, "perturbation").tables[0].rows}
    for label in comparison.labels:
        x = np.asarray(perturbed[label].simulation.state)[:, 0]
        x0 = np.asarray(comparison[label].simulation.state)[:, 0]
        t = np.asarray(perturbed[label].simulation.time)
        d = np.abs(x - x0)
        assert np.all(d[t < 31.0] < 1e-9)
        assert rows[label][1] == amount(float(np.sqrt(np.mean(d[t >= 31.0] ** 2))), "rad")
        assert rows[label][2] == amount(float(d[t >= 31.0].max()), "rad")
        assert rows[label][5] == ("verified" if perturbed[label].verified else "failed")


def test_rise_times_against_a_direct_search(comparison, lab):
    sim = comparison["selftune"].simulation
    t = np.asarray(sim.time)
    xd = np.asarray(sim.desired).ravel()
    x = np.asarray(sim.state)[:, 0]
    edge, rise = rise_times(sim)[5]
    i = int(np.searchsorted(t, edge))
    start, target = x[i - 1], xd[i]
    k = i + int(np.argmax((x[i:] - (start + 0.9 * (target - start))) * np.sign(target - start) >= 0))
    assert rise == pytest.approx(t[k] - t[i], abs=1e-12)


def test_every_member_sentence_says_what_its_checks_say(comparison, lab):
    from designkit.comparison.verdicts import check_lines, member_sentence

    text = " ".join(_question(lab, "adapt, and with what success").sentences)
    for label in comparison.labels:
        r = comparison[label]
        assert member_sentence(label, family(r.design.kind).display.label, check_lines(r.checks)) in text
