"""SVG rendering helpers: min/max decimation of long signals."""

from __future__ import annotations

import numpy as np

from designkit.report import svg


def test_minmax_decimate_keeps_extremes_and_bounds_the_length():
    t = np.linspace(0, 1, 100_001)
    y = np.sign(np.sin(2 * np.pi * 500 * t))  # chattering signal
    y[12345] = 7.0
    td, yd = svg.minmax_decimate(t, y, max_points=1000)
    assert td.size <= 1000 and np.all(np.diff(td) > 0)
    assert yd.max() == 7.0 and yd.min() == -1.0
    short = np.arange(5.0)
    assert svg.minmax_decimate(short, short)[0] is not None and svg.minmax_decimate(short, short)[0].size == 5
