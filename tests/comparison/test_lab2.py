"""Lab experiment 2's comparison section: its numbers against independent runs of hand-written specs."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.comparison.answers import comparison_sections
from designkit.comparison.lab2 import section
from designkit.comparison.studies import perturbation_run, rise_times
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from tests.comparison.test_comparison import EXAMPLE


@pytest.fixture(scope="module")
def comparison():
    from designkit.schema.loader import load_spec

    return run(load_spec(EXAMPLE))


def test_the_section_answers_every_question(comparison):
    sections = comparison_sections(comparison)
    assert [s.anchor for s in sections] == ["comparison-answers", "lab-2-comparison"]
    lab = section(comparison)
    titles = " ".join(q.question for q in lab.questions).lower()
    for words in ("adapt", "comparative difference", "adaptation parameters", "control strategies", "ad hoc",
                  "perturbation", "response time", "control level", "robust"):
        assert words in titles, words


def test_perturbation_study_against_a_spec_with_the_perturbation(comparison):
    text = EXAMPLE.read_text().replace("  plant_change:", "  perturbation: {value: 1.0, time: 31.0}\n  plant_change:")
    perturbed = run(parse_spec(text))
    for label in comparison.labels:
        p = perturbation_run(label, comparison[label], 1.0, 31.0)
        x = np.asarray(perturbed[label].simulation.state)[:, 0]
        x0 = np.asarray(comparison[label].simulation.state)[:, 0]
        t = np.asarray(perturbed[label].simulation.time)
        d = np.abs(x - x0)
        assert np.all(d[t < 31.0] < 1e-9)
        assert p.peak == pytest.approx(d[t >= 31.0].max(), rel=1e-9)
        assert p.rms == pytest.approx(np.sqrt(np.mean(d[t >= 31.0] ** 2)), rel=1e-9)


def test_the_larger_change_diverges_the_mrac_only(comparison):
    text = EXAMPLE.read_text().replace("values: {Km: 1.0}", "values: {Km: 1.0, tau: 0.8}")
    larger = run(parse_spec(text))
    mrac = np.asarray(larger["mrac"].simulation.state, dtype=float)
    selftune = np.asarray(larger["selftune"].simulation.state, dtype=float)
    assert not np.all(np.isfinite(mrac)) or np.max(np.abs(mrac)) > 1e3
    assert np.all(np.isfinite(selftune)) and np.max(np.abs(selftune[:, 0])) < 1.0
    robust = next(q for q in section(comparison).questions if "robust" in q.question.lower())
    rows = {r[0]: r for r in robust.tables[0].rows}
    assert rows["mrac"][-1] == "no" and rows["selftune"][-1] == "yes"


def test_rise_times_against_a_direct_search(comparison):
    sim = comparison["selftune"].simulation
    t = np.asarray(sim.time)
    xd = np.asarray(sim.desired).ravel()
    x = np.asarray(sim.state)[:, 0]
    edge, rise = rise_times(sim)[5]
    i = int(np.searchsorted(t, edge))
    start, target = x[i - 1], xd[i]
    k = i + int(np.argmax((x[i:] - (start + 0.9 * (target - start))) * np.sign(target - start) >= 0))
    assert rise == pytest.approx(t[k] - t[i], abs=1e-12)
