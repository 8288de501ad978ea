"""The family's figures, report section and diagnoses, each called alone on a pipeline result."""

from __future__ import annotations

import pytest

from designkit.display.figure import Figure
from designkit.display.section import ReportSection
from designkit.display.svg import svg_keys
from designkit.families import family
from designkit.families.mrac.figures import gamma_figure, outputs_figure, parameters_figure
from designkit.families.mrac.regressor_figures import regressor_figure
from designkit.families.mrac.report import section

FAMILY = family("mrac")


def test_the_family_declares_its_figures_section_and_json():
    assert FAMILY.figures == (outputs_figure, parameters_figure, gamma_figure, regressor_figure)
    assert FAMILY.sections == (section,)
    assert FAMILY.references == ("step", "square", "prbs")


def test_the_coefficient_forms_figures_leave_the_other_structure_alone(link_result):
    assert regressor_figure(link_result) is None


def test_outputs_figure(link_result):
    fig = outputs_figure(link_result)
    assert isinstance(fig, Figure) and fig.svg.lstrip().startswith("<?xml") and fig.filename == "fig-mrac-outputs.svg"
    keys = set(svg_keys(fig.svg))
    assert {"reference", "model", "adaptive", "fixed", "adaptive-error", "fixed-error", "plant-change"} <= keys
    assert "t = 20 s" in fig.caption and "frozen at their initial values" in fig.caption
    assert fig.evidence == ("adaptation_error", "adaptive_stability")


def test_parameters_figure(link_result, unstable_result):
    fig = parameters_figure(link_result)
    keys = set(svg_keys(fig.svg))
    assert {"adapted", "initial", "final", "matching", "plant-change"} <= keys and "final-offscale" not in keys
    assert "20 and 9" in fig.caption and "39.99 and 16" in fig.caption  # initial and final values drawn
    bad = parameters_figure(unstable_result)
    assert "final-offscale" in svg_keys(bad.svg) and "stopped being finite" in bad.caption


def test_diagnosis_of_the_unstable_example_recommends_no_gain_from_boundedness_alone(unstable_result):
    """A bounded run at one γ is not a recommendation (the outcome is not monotone in γ): the fix points to the
    boundary study, which judges every required check, and names no γ of its own."""
    check = next(c for c in unstable_result.checks if c.name == "adaptive_stability")
    rule = next(r for r in FAMILY.checks if not isinstance(r, str) and r.name == "adaptive_stability")
    cause, fix = rule.diagnose(unstable_result, check)
    lo = check.certificate["gamma_bounded_at"][0]
    assert "unstable" in cause and "boundary study" in fix and "1/amplitude²" in fix
    assert f"{lo:.4g}" not in fix and "or less" not in fix
    assert f"{lo:.4g}" in check.detail  # the check's own line states the bounded run it measured


@pytest.mark.slow
def test_section_and_gamma_figure(link_result):
    sec = section(link_result)
    assert isinstance(sec, ReportSection) and sec.anchor == "lab-mrac" and len(sec.questions) == 7
    first = sec.questions[0]
    assert "0.0113 rad RMS with adaptation against 0.0625 rad without" in " ".join(first.sentences)
    boundary = sec.questions[4]
    assert "Floquet" in " ".join(boundary.sentences) and "Åström and Wittenmark" in " ".join(boundary.sentences)
    text = " ".join(s for q in sec.questions for s in q.sentences)
    assert "nan" not in text and "None" not in text and "Comparison(" not in text
    fig = gamma_figure(link_result)
    assert {"bounded", "diverged", "bracket", "floquet", "frozen", "spec-gamma"} <= set(svg_keys(fig.svg))
    assert "γ1 = 1e+04" in fig.caption
    assert section(link_result) is not None  # cached: the second call reuses the study
