"""Robustness heat map: the certificate grid formats it accepts, and its SVG."""

from __future__ import annotations

import numpy as np

from designkit.report import heatmap
from tests.report.conftest import assert_svg


def test_robustness_grid_formats():
    km, tau = [1.0, 2.0, 3.0], [0.1, 0.2]
    vals = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]  # (tau, Km)
    got = heatmap.robustness_grid({"grid": {"Km": km, "tau": tau, "margin": vals}})
    assert got is not None and got[2].shape == (2, 3) and got[3] == "margin"
    transposed = heatmap.robustness_grid({"grid": {"Km": km, "tau": tau, "values": np.array(vals).T.tolist()}})
    np.testing.assert_array_equal(transposed[2], np.array(vals))
    assert heatmap.robustness_grid({"grid": {"Km": km, "tau": tau, "values": [[1.0]]}}) is None
    assert heatmap.robustness_grid({"grid": {"Km": km}}) is None
    assert heatmap.robustness_grid({"grid": "coarse"}) is None
    svg = heatmap.robustness_svg("robust", {"grid": {"Km": km, "tau": tau, "values": vals, "label": "margin (1/s)"}})
    assert_svg(svg)


def test_no_heat_map_without_grid_data():
    assert heatmap.robustness_svg("x", {"P": [[1.0]]}) is None
