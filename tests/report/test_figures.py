"""Figures: valid deterministic SVG, figures left out without data, responses."""

from __future__ import annotations

import matplotlib

from designkit.report.figures import design_figures
from designkit.report.figures.pole_zero import pole_zero_figure
from designkit.report.figures.simulation import simulation_figure
from tests.report.conftest import SERVO_YAML, assert_svg, make_result


def test_figures_are_valid_and_deterministic(servo_result):
    first = design_figures(servo_result)
    second = design_figures(servo_result)
    assert [f.filename for f in first] == [
        "fig-pole-zero.svg", "fig-linear-response.svg", "fig-simulation.svg",
        "fig-robustness-robust_grid.svg", "fig-loop-bode.svg", "fig-loop-sensitivity.svg",
    ]
    for a, b in zip(first, second, strict=True):
        assert_svg(a.svg)
        assert a.svg == b.svg
        assert a.title and a.caption


def test_optional_figures_are_left_out_without_data():
    res = make_result(checks=(), simulate=False)
    figs = design_figures(res)
    assert [f.filename for f in figs] == ["fig-pole-zero.svg", "fig-linear-response.svg", "fig-loop-bode.svg",
                                          "fig-loop-sensitivity.svg"]
    assert simulation_figure(res) is None


def test_rendering_leaves_matplotlib_global_state_alone(servo_result):
    before = dict(matplotlib.rcParams)
    pole_zero_figure(servo_result)
    assert dict(matplotlib.rcParams) == before


def test_tracking_figures(tracking_result):
    figs = {f.filename: f for f in design_figures(tracking_result)}
    assert "trajectory" in figs["fig-linear-response.svg"].title
    assert_svg(figs["fig-simulation.svg"].svg)
    assert "tracking error" in figs["fig-simulation.svg"].caption


def test_captions_name_only_what_is_drawn(servo_result):
    figs = {f.filename: f for f in design_figures(servo_result)}
    sim = figs["fig-simulation.svg"].caption
    assert "settling band" in sim and "overshoot limit" in sim and "perturbation" in sim
    bare = make_result(yaml_text=SERVO_YAML.replace(
        "requirements: {overshoot: 10, settling_time: 2.0, rise_time: 0.8, steady_state_error: 0.01, "
        "max_control: 40}\n", ""), checks=())
    cap = {f.filename: f for f in design_figures(bare)}["fig-simulation.svg"].caption
    assert "settling band" not in cap and "control limit" not in cap
