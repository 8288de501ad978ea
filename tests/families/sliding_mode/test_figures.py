"""The family's figures render standalone (a Figure with SVG), and their captions name what is drawn."""

from __future__ import annotations

import dataclasses

import pytest

from designkit.display.figure import Figure
from designkit.display.svg import svg_keys
from designkit.families import family
from designkit.families.sliding_mode.figures import FIGURES, control_figure, phase_portrait, sliding_function_figure

EXPECTED = {
    phase_portrait: ("fig-sliding_mode-phase.svg", {"trajectory", "start", "reach", "sliding-line", "switching-line",
                                                    "alpha-region"}),
    sliding_function_figure: ("fig-sliding_mode-sliding-function.svg", {"band", "s", "reaching",
                                                                        "perturbation-onset"}),
    control_figure: ("fig-sliding_mode-control.svg", {"u", "u-mean", "perturbation"}),
}


@pytest.fixture(scope="module")
def figures(link_result):
    return {draw: draw(link_result) for draw in FIGURES}


def test_the_family_declares_its_figures():
    from designkit.families.sliding_mode.linear_figures import LINEAR_FIGURES

    assert family("sliding_mode").figures == (*FIGURES, *LINEAR_FIGURES) and set(FIGURES) == set(EXPECTED)


@pytest.mark.parametrize("draw", FIGURES, ids=[f.__name__ for f in FIGURES])
def test_each_figure_is_standalone_svg_with_the_drawn_keys(draw, figures, link_result):
    fig = figures[draw]
    filename, keys = EXPECTED[draw]
    assert isinstance(fig, Figure) and fig.filename == filename
    assert fig.svg.lstrip().startswith("<?xml") and "<svg" in fig.svg and "</svg>" in fig.svg
    assert "<text" in fig.svg  # text kept as text
    assert set(svg_keys(fig.svg)) == keys
    names = {c.name for c in link_result.checks}
    assert set(fig.evidence) <= names and fig.evidence
    assert fig.caption and "Drawn:" in fig.caption


def test_captions_follow_what_is_drawn(figures, link_result):
    assert "perturbation's onset" in figures[sliding_function_figure].caption
    assert "sliding line s = 0" in figures[phase_portrait].caption
    # without a perturbation nothing of it is drawn, and the caption does not name it
    sim = link_result.simulation
    quiet = dataclasses.replace(link_result, simulation=dataclasses.replace(sim, perturbation=0 * sim.perturbation))
    s_fig, u_fig = sliding_function_figure(quiet), control_figure(quiet)
    assert "perturbation-onset" not in svg_keys(s_fig.svg) and "perturbation" not in s_fig.caption
    assert "perturbation" not in svg_keys(u_fig.svg) and "−ξ" not in u_fig.caption


def test_no_run_no_figure(link_result):
    bare = dataclasses.replace(link_result, simulation=None)
    assert all(draw(bare) is None for draw in FIGURES)
