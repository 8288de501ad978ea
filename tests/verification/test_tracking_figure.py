"""The tracking-bounds check draws its evidence: the error over the box with the requirement inside the axis range."""

from __future__ import annotations

import numpy as np
import pytest

import designkit as dk
from designkit.verification.figures.tracking_bounds import _draw


@pytest.mark.slow
def test_the_payload_run_draws_the_error_over_the_box_against_its_band():
    result = dk.run(dk.load_spec("specs/puma560-computed-torque-payload.yaml"))
    check = next(c for c in result.checks if c.name == "tracking_bounds")
    names = [result.design.plant.states[i].name for i in result.design.plant.positions]
    fig = _draw(check.data, names, 0.001, "m6 (kg)")
    top, bottom = fig.axes[0], fig.axes[1]
    assert top.get_ylim()[1] >= 0.001 and bottom.get_ylim()[1] >= 0.001  # the band is visible on both
    peaks = np.asarray(check.data["peaks"])
    assert peaks.max() == pytest.approx(check.achieved)  # the figure's runs are the check's
    assert bottom.get_xlabel() == "m6 (kg)"
    from designkit.report.model import build_report_model

    titles = [f.title for f in build_report_model(result, studies=False).figures]
    assert "Tracking error over the uncertainty box" in titles
