"""The family's figures and report section reach the report, and their captions describe what is drawn."""

from __future__ import annotations

from designkit.display.numbers import fmt_number
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
    reach = next(c for c in elastic_result.checks if c.name == "vsc_reaching_time").achieved
    assert 0 < reach < 0.005  # from the initial error, sigma reaches the band within a few ms (tens of held steps)
    assert f"reaches the band after {fmt_number(reach, 4)} s" in sigma.caption  # the caption states the measured time
    assert "100 % of the samples" in figs[2].caption  # u_eq between the switched controls
    gains = figs[3]
    assert gains.svg.count("l₁") >= 1 and "2 uncertain parameters" in gains.caption


def test_report_section_answers_theorems_1_3_4(elastic_result, link_result):
    s = section(elastic_result)
    assert [q.question.split(":")[0] for q in s.questions] == ["Theorem 3", "Theorem 1", "Theorem 4"]
    assert "unmatched" in s.questions[2].sentences[0] and "0.01229 rad" in s.questions[2].sentences[0]
    assert len(s.questions[0].tables[0].rows) == 4
    assert "(matched)" in section(link_result).questions[2].sentences[0]


def test_sliding_poles_over_the_box(elastic_result, link_result):
    """The link's sliding motion x1' = -c1 x1 is the same at every corner; the elastic joint's depends on J2 (the
    link side): at J2 = 0.45 its poles are those of s^3 + (c1 + 1/tau2) s^2 + (k2 (1 + c4) + c1/tau2) s +
    k2 (c1 + c3), computed here with numpy.roots."""
    import numpy as np

    for v in link_result.design.data.vertex_poles:
        assert [p.real for p in v.poles] == [-5.0] or abs(v.poles[0].real + 5.0) < 1e-12
    c1, _, c3, c4 = elastic_result.design.data.c
    k2, t2 = 200.0 / 0.45, 2.0
    want = np.sort_complex(np.roots([1.0, c1 + 1 / t2, k2 * (1 + c4) + c1 / t2, k2 * (c1 + c3)]))
    got = next(v for v in elastic_result.design.data.vertex_poles if v.at["J2"] == 0.45)
    got = np.sort_complex(np.array(got.poles))
    assert np.allclose(got, want, rtol=1e-9)
    assert "invariant to matched uncertainty only" in section(elastic_result).questions[0].sentences[-1]
