"""The self-tuning lab section and figures: present, and numbers that can be recomputed independently."""

from __future__ import annotations

import numpy as np

from designkit.families.self_tuning.figures import FIGURES
from designkit.families.self_tuning.study import section
from tests.families.self_tuning.oracles import theta_scipy


def test_lab_section_answers_the_five_questions_with_tables(speed_result):
    sec = section(speed_result)
    assert sec is not None and len(sec.questions) == 5
    assert all(q.tables for q in sec.questions)
    words = " ".join(s for q in sec.questions for s in q.sentences)
    assert "_" not in words  # words, not identifiers


def test_estimator_off_row_keeps_the_initial_estimates(speed_result):
    """With the estimator off the estimates stay at the nominal link's: the row's error is theirs against the final
    true link (both discretized by scipy)."""
    sec = section(speed_result)
    row = next(r for r in sec.questions[0].tables[0].rows if r[0].startswith("estimator off"))
    initial = theta_scipy(1.0, 1.0, 0.01, "speed")
    final = theta_scipy(1.0, 0.8, 0.01, "speed")
    expected = float(np.max(np.abs(initial / final - 1)))
    assert abs(float(row[6]) - expected) <= 5e-3 * expected  # three significant digits in the table
    assert row[7] == "never"


def test_the_covariance_bound_row_ends_at_the_bound(speed_result):
    sec = section(speed_result)
    rows = sec.questions[3].tables[1].rows
    bounded = next(r for r in rows if r[0].startswith("quiet reference with noise, with"))
    free = next(r for r in rows if r[0].startswith("quiet reference with noise, without"))
    assert float(bounded[1]) == speed_result.design.data.settings.max_trace and int(bounded[2]) > 0
    assert float(free[1]) > 10 * float(bounded[1]) and int(free[2]) == 0


def test_figures_are_drawn(speed_result):
    figs = [f(speed_result) for f in FIGURES]
    assert all(f is not None and f.svg.startswith("<") for f in figs)
    assert {f.filename for f in figs} == {"fig-selftune-estimates.svg", "fig-selftune-loop.svg",
                                          "fig-selftune-conditioning.svg"}


def test_reports_have_no_raw_python_representation(speed_result, failing_result, tmp_path, monkeypatch):
    """The written reports (HTML and PDF) pass the shared report suite's raw-notation patterns."""
    from designkit.report.provenance import STABLE_ENV
    from designkit.report.writer import write_report
    from tests.report.test_pipeline_reports import _html_text, _pdf_text, _raw

    monkeypatch.setenv(STABLE_ENV, "stable")  # the command line is pytest's here: not part of what is scanned

    for result in (speed_result, failing_result):
        files = write_report(result, tmp_path, studies=False)
        html = _html_text(files.html.read_text(encoding="utf-8"))
        assert _raw(html) == [] and "N*m" not in html
        assert "Lab questions (notes, experiment 2: self-tuning)" in html
        pdf = _pdf_text(files.pdf)
        assert _raw(pdf) == [] and "N*m" not in pdf
