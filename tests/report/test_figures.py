"""Figures: valid deterministic SVG, figures left out without data, responses."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

from designkit.report import figures as fg
from designkit.spec.loader import parse_spec
from designkit.synthesis.registry import synthesize
from tests.problems import POSSPEED_YAML
from tests.report.conftest import assert_svg


def _design(text):
    return synthesize(parse_spec(text).spec)


def test_figures_are_valid_and_deterministic(servo_result):
    res = servo_result
    spec = res.loaded.spec
    first = fg.design_figures(res.design, requirements=spec.requirements, simulation_spec=spec.simulation,
                             simulation=res.simulation, checks=res.checks)
    second = fg.design_figures(res.design, requirements=spec.requirements, simulation_spec=spec.simulation,
                              simulation=res.simulation, checks=res.checks)
    assert [f.filename for f in first] == [
        "fig-pole-zero.svg", "fig-linear-response.svg", "fig-loop-bode.svg", "fig-simulation.svg",
        "fig-robustness-robust_stability.svg",
    ]
    for a, b in zip(first, second, strict=True):
        assert_svg(a.svg)
        assert a.svg == b.svg
        assert a.title and a.caption


def test_optional_figures_are_left_out_without_data():
    design = _design(POSSPEED_YAML)
    figs = fg.design_figures(design)
    assert [f.filename for f in figs] == ["fig-pole-zero.svg", "fig-linear-response.svg", "fig-loop-bode.svg"]
    assert fg.simulation_svg(None) is None


def test_rendering_leaves_matplotlib_global_state_alone():
    before = dict(matplotlib.rcParams)
    fg.pole_zero_svg(_design(POSSPEED_YAML))
    assert dict(matplotlib.rcParams) == before


def test_tracking_response_uses_the_simulation_reference(tracking_result):
    res = tracking_result
    svg = fg.step_response_svg(res.design, res.loaded.spec.requirements, res.loaded.spec.simulation,
                              res.simulation)
    assert_svg(svg)
    # and without a simulation: the spec's (default quintic) trajectory
    assert_svg(fg.step_response_svg(res.design, res.loaded.spec.requirements, res.loaded.spec.simulation))


def test_linear_response_settles_at_the_step():
    design = _design(POSSPEED_YAML)
    t = np.linspace(0, 5, 501)
    ref = np.zeros((t.size, 3))
    ref[:, 0] = 1.0
    x1, u = fg.linear_response(design, t, ref)
    assert x1[-1] == pytest.approx(1.0, abs=1e-4)
    assert u[-1] == pytest.approx(0.0, abs=1e-3)  # no steady control: the link has no spring
