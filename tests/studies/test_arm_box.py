"""Lab answers over what the spec varies: the step response re-simulated at the corners of the parameter box."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import designkit as dk
from designkit.studies.arm.mass import box_response_sentence

SPEC = Path(__file__).resolve().parents[2] / "specs" / "simnog-decentralized-pid.yaml"


def _overshoot(sim) -> float:
    """Largest overshoot (%) over the moving joints, from the positions and references directly."""
    pos = sim.state[:, list(sim.positions)]
    ref = np.asarray(sim.reference)[:, :, 0]
    out = []
    for j in range(pos.shape[1]):
        step = ref[-1, j] - pos[0, j]
        if abs(step) > 1e-9:
            out.append(100 * max(0.0, np.max((pos[:, j] - pos[0, j]) / step) - 1.0))
    return max(out)


def test_overshoot_over_the_box_is_what_runs_at_the_corners_give():
    result = dk.run(dk.load_spec(SPEC))
    text = box_response_sentence(result, result.plant)
    m = re.search(r"overshoot ([0-9.e+-]+) to ([0-9.e+-]+) % \(largest at m2 = 4\)", text)
    assert m is not None, text
    # each corner simulated through the public API on the true plant with that m2, the overshoot computed here
    spec = result.loaded.spec
    corners = [_overshoot(dk.simulate(spec, result.design, plant=result.plant.with_params(m2=v))) for v in (2.0, 4.0)]
    assert float(m.group(1)) == pytest.approx(min(corners), rel=5e-3, abs=1e-9)  # printed to 3 digits
    assert float(m.group(2)) == pytest.approx(max(corners), rel=5e-3)
    assert "settling time to the 2 % band" in text and "steady-state error" in text


def test_no_box_no_sentence():
    result = dk.run(dk.load_spec(SPEC.parent / "posspeed-link.yaml"))
    assert box_response_sentence(result, result.plant) == ""
