"""Robustness figure: the certificate grid form it accepts (axes from the certificate), and its SVG."""

from __future__ import annotations

import numpy as np

from designkit.display import heatmap
from tests.report.conftest import assert_svg


def _grid(values, axes=(("Km", [1.0, 2.0, 3.0]), ("tau", [0.1, 0.2]))):
    return {"grid": {"axes": [{"name": n, "unit": "", "values": v} for n, v in axes], "values": values,
                     "label": "margin (1/s)"}}


def test_robustness_grid_form():
    vals = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]  # (axis 2, axis 1)
    got = heatmap.robustness_grid(_grid(vals))
    assert got is not None and got.values.shape == (2, 3) and got.label == "margin (1/s)"
    assert [a[0] for a in got.axes] == ["Km", "tau"]
    assert heatmap.robustness_grid(_grid(np.array(vals).T.tolist())) is None  # wrong orientation is refused
    assert heatmap.robustness_grid(_grid([[1.0]])) is None
    assert heatmap.robustness_grid({"grid": {"axes": []}}) is None
    assert heatmap.robustness_grid({"grid": "coarse"}) is None
    assert_svg(heatmap.robustness_svg("robust", _grid(vals)))


def test_one_axis_is_a_line():
    got = heatmap.robustness_grid(_grid([0.5, 0.2, -0.1], axes=(("m2", [1.0, 2.0, 3.0]),)))
    assert got is not None and len(got.axes) == 1
    root = assert_svg(heatmap.robustness_svg("robust_grid", _grid([0.5, 0.2, -0.1], axes=(("m2", [1.0, 2.0, 3.0]),))))
    assert root is not None


def test_no_heat_map_without_grid_data():
    assert heatmap.robustness_svg("x", {"P": [[1.0]]}) is None


def test_zero_contour_is_drawn_and_tagged_only_when_the_margin_changes_sign():
    from designkit.display.svg import svg_keys

    mixed = svg_keys(heatmap.robustness_svg("r", _grid([[1.0, -2.0, 3.0], [4.0, 5.0, -6.0]])))
    positive = svg_keys(heatmap.robustness_svg("r", _grid([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])))
    assert "zero-contour" in mixed and "margin-map" in mixed
    assert "zero-contour" not in positive and "margin-map" in positive
    assert set(svg_keys(heatmap.robustness_svg("r", _grid([0.5, -0.1], axes=(("m2", [1.0, 2.0]),))))) == {
        "margin-line", "zero-line"}
