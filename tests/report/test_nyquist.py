"""The describing-function figure: the Nyquist curve against -1/N(a) for the relay and saturation loops.

Independent routes: the saturation's describing function against the first Fourier harmonic of sat(a sin θ)
computed numerically; the saturation crossing against the loop-margins check's gain margin (the crossing of the
negative real axis is at -1/GM); the relay crossing against the diagnosis' own limit-cycle prediction.
"""

from __future__ import annotations

import numpy as np
import pytest

import designkit as dk
from designkit.report.figures.nyquist import nyquist_figure, saturation_describing_function


@pytest.mark.parametrize("a", [0.5, 1.0, 1.5, 3.0, 20.0])
def test_saturation_describing_function_is_the_first_harmonic(a):
    theta = np.linspace(0, 2 * np.pi, 200_001)[:-1]
    y = np.clip(a * np.sin(theta), -1.0, 1.0)
    b1 = 2 * np.mean(y * np.sin(theta))  # first sine coefficient of the output
    assert saturation_describing_function(np.array([a]), 1.0)[0] == pytest.approx(b1 / a, rel=1e-6)


def test_the_saturated_conditionally_stable_loop_crosses_at_minus_one_over_its_gain_margin():
    result = dk.run(dk.load_spec("specs/infeasible-requirements.yaml"))
    fig = nyquist_figure(result)
    assert fig is not None and "-9.63 on the real axis" in fig.caption
    gm = next(c for c in result.checks if c.name == "loop_margins").certificate["loops"][0]["gain_margin"]
    assert -1.0 / gm == pytest.approx(-9.63, rel=1e-3)


def test_the_relay_crossing_is_the_predicted_limit_cycle():
    result = dk.run(dk.load_spec("specs/posspeed-relay.yaml"))
    fig = nyquist_figure(result)
    from designkit.analysis.diagnosis import diagnose

    cycle = diagnose(result).limit_cycle
    assert cycle is not None and cycle.predicted_frequency is not None
    assert f"ω = {cycle.predicted_frequency:.3g} rad/s" in fig.caption


def test_no_figure_without_a_relay_or_saturation():
    assert nyquist_figure(dk.run(dk.load_spec("specs/posspeed-link.yaml"))) is None
