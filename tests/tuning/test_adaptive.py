"""An adaptive law tuned: the MRAC's adaptation gain of specs/tune-mrac-link.yaml, every candidate run through the
family's own adaptive run, compared with an independent scan of the gain."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import designkit as dk
from tests.tuning.specs import write

SPEC = Path(__file__).resolve().parents[2] / "specs" / "tune-mrac-link.yaml"


def _rise(t: np.ndarray, x: np.ndarray, final: float) -> float:
    """Time between the first crossings of 10 % and 90 % of ``final`` (s), interpolated here on the trace."""
    def crossing(level: float) -> float:
        k = int(np.argmax(x >= level))
        return float(np.interp(level, x[k - 1:k + 1], t[k - 1:k + 1]))
    return crossing(0.9 * final) - crossing(0.1 * final)


def _score(folder: Path, gamma: float) -> float:
    """Worst normalised margin of rise time (0.82 s) and overshoot (2 %) of the spec run with ``gamma``, each
    measured here from the simulated position (the step is 0.5 rad)."""
    data = yaml.safe_load(SPEC.read_text(encoding="utf-8"))
    data.pop("tune")
    data["controller"]["gamma"] = float(gamma)
    run = dk.run(dk.load_spec(write(folder, yaml.safe_dump(data), f"g{gamma:.6g}.yaml")))
    t, x = run.simulation.time, run.simulation.state[:, 0]
    overshoot = 100.0 * max(0.0, float(np.max(x)) - 0.5) / 0.5
    return min((0.82 - _rise(t, x, 0.5)) / 0.82, (2.0 - overshoot) / 2.0)


def test_the_adaptation_gain_is_tuned_and_the_tuned_spec_re_runs(tmp_path):
    result = dk.tune(SPEC, out=tmp_path, budget=20.0)
    assert result.initial.margins["rise_time"] < 0  # gamma = 100 misses the rise time
    assert result.verified and result.met
    # the tuned spec, read back, re-runs as it is (synth exit 0), and adapts
    run = dk.run(dk.load_spec(result.files["spec"]))
    assert run.verified
    sim = run.simulation
    a = sim.controller_state[:, [sim.controller_state_names.index("a1"), sim.controller_state_names.index("a2")]]
    assert np.max(np.abs(a[-1] - a[0]) / np.abs(a[0])) > 0.05  # adapted: a parameter moved by more than 5 %
    assert _score(tmp_path, float(result.best.values["gamma"])) > 0


@pytest.mark.slow  # about 6 s: 17 adaptive runs besides the search
def test_the_adaptation_gain_is_tuned_where_a_scan_of_it_is_best(tmp_path):
    result = dk.tune(SPEC, out=tmp_path, budget=20.0)
    gamma = float(result.best.values["gamma"])
    # an independent scan: 17 gains, a decade in four steps, over the tuned range, judged on the trace
    grid = np.logspace(0.0, 4.0, 17)
    scores = np.array([_score(tmp_path, g) for g in grid])
    best = grid[int(np.argmax(scores))]
    assert abs(np.log10(gamma) - np.log10(best)) <= 0.5  # within two grid steps
    assert _score(tmp_path, gamma) >= scores.max() - 0.01  # the tuned gain is no worse than the scan's best
    assert scores[0] < 0 < scores.max()
