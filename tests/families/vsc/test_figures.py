"""The family's figures and report section reach the report, and their captions describe what is drawn."""

from __future__ import annotations

from designkit.families.vsc.figures import FIGURES
from designkit.families.vsc.report import section


def test_every_figure_is_drawn_with_its_caption(elastic_result):
    figs = [draw(elastic_result) for draw in FIGURES]
    assert all(f is not None for f in figs)
    names = {f.filename for f in figs}
    assert names == {"fig-vsc-sigma.svg", "fig-vsc-states.svg", "fig-vsc-control.svg", "fig-vsc-gains.svg"}
    for f in figs:
        assert "<svg" in f.svg and "Drawn:" in f.caption
    sigma = figs[0]
    assert "reaches the band after 0.00205 s" in sigma.caption
    assert "100 % of the samples" in figs[2].caption  # u_eq between the switched controls
    gains = figs[3]
    assert gains.svg.count("l₁") >= 1 and "2 uncertain parameters" in gains.caption


def test_report_section_answers_theorems_1_3_4(elastic_result, link_result):
    s = section(elastic_result)
    assert [q.question.split(":")[0] for q in s.questions] == ["Theorem 3", "Theorem 1", "Theorem 4"]
    assert "unmatched" in s.questions[2].sentences[0] and "0.01229 rad" in s.questions[2].sentences[0]
    assert len(s.questions[0].tables[0].rows) == 4
    assert "(matched)" in section(link_result).questions[2].sentences[0]
