"""A failing requirement's figure shows its band where a reviewer can see it (the relay and payload runs)."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

import designkit as dk
from designkit.display import svg
from designkit.report.figures.simulation import _draw_simulation


def _draw(name):
    result = dk.run(dk.load_spec(f"specs/{name}.yaml"))
    with matplotlib.rc_context(svg.RC_PARAMS):
        fig, info = _draw_simulation(result.design, result.simulation, result.loaded.spec.requirements)
    return result, fig, info


def test_the_relay_cases_steady_state_band_is_on_a_zoomed_error_axis():
    result, fig, info = _draw("posspeed-relay")
    check = next(c for c in result.checks if c.name == "steady_state_error")
    assert check.passed is False
    error_axis = fig.axes[1]
    low, high = error_axis.get_ylim()
    band = result.loaded.spec.requirements.steady_state_error
    assert high - low <= 30 * band  # the ±2 mrad band is a visible share of the axis (not 0-1 rad)
    assert high > abs(check.achieved) and high > band  # the error it fails by is inside the axis too
    assert info["steady_band"] == band and "zoomed" in info


@pytest.mark.slow
def test_the_payload_runs_error_panel_has_its_tracking_band_and_a_short_legend():
    result, fig, info = _draw("puma560-computed-torque-payload")
    error_axis = fig.axes[1]
    band = result.loaded.spec.requirements.tracking_error
    assert info["tracking_band"] == band and error_axis.get_ylim()[1] >= band
    top_legend = fig.axes[0].get_legend()
    assert len(top_legend.get_texts()) <= 7  # one entry for all references, one per joint
    labels = [t.get_text() for t in fig.axes[-1].get_legend().get_texts()]
    assert "u1" in labels and len(labels) <= 7
    assert np.all(np.isfinite(error_axis.get_ylim()))


def test_a_prismatic_joint_is_drawn_in_metres_and_newtons():
    result = dk.run(dk.load_spec("specs/scara-decentralized-pid.yaml"), simulate=True)
    with matplotlib.rc_context(svg.RC_PARAMS):
        fig, _ = _draw_simulation(result.design, result.simulation, result.loaded.spec.requirements)
    labels = [a.get_ylabel() for a in fig.axes]
    assert labels[0] == "position (rad, m)" and labels[-1] == "control (N·m, N)"


def test_the_sensitivity_caption_does_not_contradict_itself():
    from designkit.verification.figures.loop_margins import _sensitivity_caption

    calm = _sensitivity_caption([], [{"input": "u", "Ms": 1.0, "w_Ms": float("inf"), "Mt": 1.0, "w_Mt": 1.0}])
    assert "|S| < 1 at every frequency" in calm and "above 0 dB amplifies" not in calm
    peaked = _sensitivity_caption([], [{"input": "u", "Ms": 4.7, "w_Ms": 3.0, "Mt": 4.2, "w_Mt": 3.0}])
    assert "above 0 dB amplifies" in peaked
