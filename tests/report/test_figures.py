"""Figures: valid deterministic SVG, the loop transfer against its hand derivation, helpers."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import control
import matplotlib
import numpy as np
import pytest

from designkit.report import figures as fg
from designkit.spec.loader import parse_spec
from designkit.synthesis.registry import synthesize
from tests.problems import COMPLEX_YAML, POSSPEED_YAML, TRACKING_YAML


def _design(text):
    return synthesize(parse_spec(text).spec)


def _assert_svg(svg: str) -> ET.Element:
    root = ET.fromstring(svg.encode("utf-8"))
    assert root.tag.endswith("svg")
    assert "<dc:date>" not in svg  # no creation date: reproducible
    return root


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
        _assert_svg(a.svg)
        assert a.svg == b.svg
        assert a.title and a.caption


def test_optional_figures_are_left_out_without_data():
    design = _design(POSSPEED_YAML)
    figs = fg.design_figures(design)
    assert [f.filename for f in figs] == ["fig-pole-zero.svg", "fig-linear-response.svg", "fig-loop-bode.svg"]
    assert fg.simulation_svg(None) is None
    assert fg.robustness_svg("x", {"P": [[1.0]]}) is None


def test_rendering_leaves_matplotlib_global_state_alone():
    before = dict(matplotlib.rcParams)
    fg.pole_zero_svg(_design(POSSPEED_YAML))
    assert dict(matplotlib.rcParams) == before


@pytest.mark.parametrize("text", [POSSPEED_YAML, COMPLEX_YAML])
def test_servo_loop_transfer_matches_hand_derivation(text):
    """L(s) = C(s) P(s), C = K1 + K2 s + K3/s on x1, P = Km / (s (tau s + 1))."""
    design = _design(text)
    g, Km, tau = design.gains, design.plant.Km, design.plant.tau
    w = np.logspace(-1, 3, 25)
    s = 1j * w
    hand = Km * (g["K2"] * s**2 + g["K1"] * s + g["K3"]) / (s**2 * (tau * s + 1))
    np.testing.assert_allclose(fg.loop_frequency_response(design, w), hand, rtol=1e-10)


def test_tracking_loop_transfer_matches_hand_derivation():
    design = _design(TRACKING_YAML)
    g, Km, tau = design.gains, design.plant.Km, design.plant.tau
    w = np.logspace(-1, 3, 25)
    s = 1j * w
    hand = ((Km * g["K2"] - 1) * s**2 + Km * g["K1"] * s + Km * g["K3"]) / (s**2 * (tau * s + 1))
    np.testing.assert_allclose(fg.loop_frequency_response(design, w), hand, rtol=1e-10)


@pytest.mark.parametrize("text", [POSSPEED_YAML, COMPLEX_YAML, TRACKING_YAML])
def test_loop_equals_minus_one_at_the_closed_loop_poles(text):
    """1 + L(p) = 0 at every closed-loop pole: the loop really closes into the design's poles."""
    design = _design(text)
    A, b, c = fg.loop_matrices(design)
    for p in design.poles:
        L = (c @ np.linalg.solve(p * np.eye(3) - A, b))[0, 0]
        assert abs(1 + L) < 1e-9 * (1 + abs(L))


def test_margins_agree_with_python_control_on_the_hand_transfer():
    design = _design(POSSPEED_YAML)
    g, Km, tau = design.gains, design.plant.Km, design.plant.tau
    L = control.tf([Km * g["K2"], Km * g["K1"], Km * g["K3"]], [tau, 1, 0, 0])
    gm, pm, _, _, wgc, _ = control.stability_margins(L)
    m = fg.loop_margins(design)
    assert m.phase_margin == pytest.approx(pm, rel=1e-6)
    assert m.w_gain_crossover == pytest.approx(wgc, rel=1e-6)
    assert np.isinf(m.gain_margin) and np.isinf(gm)
    assert 0 < m.modulus_margin <= 1.0 + 1e-6


def test_achieved_zero_is_the_requested_zero():
    design = _design(POSSPEED_YAML)
    np.testing.assert_allclose(fg.achieved_zeros(design), [-3.0], atol=1e-9)
    assert fg.achieved_zeros(_design(TRACKING_YAML)).size == 0


def test_siso_zeros_of_a_known_transfer():
    sys = control.ss(control.tf([1, 3, 2], [1, 6, 11, 6]))  # zeros -1, -2
    z = fg.siso_zeros(np.asarray(sys.A), np.asarray(sys.B)[:, 0], np.asarray(sys.C)[0], float(sys.D[0, 0]))
    np.testing.assert_allclose(np.sort(z.real), [-2.0, -1.0], atol=1e-9)


def test_minmax_decimate_keeps_extremes_and_bounds_the_length():
    t = np.linspace(0, 1, 100_001)
    y = np.sign(np.sin(2 * np.pi * 500 * t))  # chattering signal
    y[12345] = 7.0
    td, yd = fg.minmax_decimate(t, y, max_points=1000)
    assert td.size <= 1000 and np.all(np.diff(td) > 0)
    assert yd.max() == 7.0 and yd.min() == -1.0
    short = np.arange(5.0)
    assert fg.minmax_decimate(short, short)[0] is not None and fg.minmax_decimate(short, short)[0].size == 5


def test_robustness_grid_formats():
    km, tau = [1.0, 2.0, 3.0], [0.1, 0.2]
    vals = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]  # (tau, Km)
    got = fg.robustness_grid({"grid": {"Km": km, "tau": tau, "margin": vals}})
    assert got is not None and got[2].shape == (2, 3) and got[3] == "margin"
    transposed = fg.robustness_grid({"grid": {"Km": km, "tau": tau, "values": np.array(vals).T.tolist()}})
    np.testing.assert_array_equal(transposed[2], np.array(vals))
    assert fg.robustness_grid({"grid": {"Km": km, "tau": tau, "values": [[1.0]]}}) is None
    assert fg.robustness_grid({"grid": {"Km": km}}) is None
    assert fg.robustness_grid({"grid": "coarse"}) is None
    svg = fg.robustness_svg("robust", {"grid": {"Km": km, "tau": tau, "values": vals, "label": "margin (1/s)"}})
    _assert_svg(svg)


def test_tracking_response_uses_the_simulation_reference(tracking_result):
    res = tracking_result
    svg = fg.step_response_svg(res.design, res.loaded.spec.requirements, res.loaded.spec.simulation,
                              res.simulation)
    _assert_svg(svg)
    # and without a simulation: the spec's (default quintic) trajectory
    _assert_svg(fg.step_response_svg(res.design, res.loaded.spec.requirements, res.loaded.spec.simulation))


def test_linear_response_settles_at_the_step():
    design = _design(POSSPEED_YAML)
    t = np.linspace(0, 5, 501)
    ref = np.zeros((t.size, 3))
    ref[:, 0] = 1.0
    x1, u = fg.linear_response(design, t, ref)
    assert x1[-1] == pytest.approx(1.0, abs=1e-4)
    assert u[-1] == pytest.approx(0.0, abs=1e-3)  # no steady control: the link has no spring
