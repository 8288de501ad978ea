"""The metrics follow the scenario: jumps of the reference found from its arrays, a step's rise time and load
response, and metrics that would measure the reference rather than the controller left out."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from designkit.comparison.metrics import SETTLED_FRACTION, jumps, settled
from designkit.pipeline import run
from designkit.schema.loader import parse_spec


def _sim(t: np.ndarray, xd: np.ndarray, vd: np.ndarray, x0: float) -> SimpleNamespace:
    reference = np.stack([xd, vd, np.zeros_like(xd)], axis=1).reshape(len(t), 1, 3)
    x = np.full_like(t, x0)
    return SimpleNamespace(time=t, reference=reference, tracked_positions=x)


def test_jumps_of_a_square_wave_a_step_and_none_of_a_smooth_reference():
    t = np.linspace(0.0, 8.0, 3201)
    square = np.where(np.mod(t, 4.0) < 2.0, 0.5, -0.5)
    found = jumps(_sim(t, square, np.zeros_like(t), 0.0))
    assert t[found].tolist() == pytest.approx([0.0, 2.0, 4.0, 6.0, 8.0], abs=1e-9)  # 0: starts off the reference
    assert jumps(_sim(t, square, np.zeros_like(t), 0.5))[0] > 0  # starts on it: no jump at 0
    step = np.ones_like(t)
    assert jumps(_sim(t, step, np.zeros_like(t), 0.0)).tolist() == [0]
    assert jumps(_sim(t, step, np.zeros_like(t), 1.0)).tolist() == []
    w = 2 * math.pi / 4.0
    coarse = np.linspace(0.0, 8.0, 161)  # 50 ms steps: the sine moves by up to 4 % of its range between samples
    sine = _sim(coarse, np.sin(w * coarse), w * np.cos(w * coarse), 0.0)
    assert jumps(sine).tolist() == []


def test_settled_instants_are_the_last_quarter_of_each_level():
    t = np.linspace(0.0, 8.0, 801)
    ok = settled(t, (0.0, 2.0, 4.0, 6.0, 8.0), SETTLED_FRACTION * 2.0)
    assert np.all(ok == (np.mod(t, 2.0) >= 1.5 - 1e-9))
    assert not ok[-1]  # the jump at the last sample
    assert np.all(settled(t, (2.0, 4.0), 1.0)[t < 2.0])  # before the first jump: no transient yet


STEP_LOAD = """\
name: step-load
plant: {kind: link, Km: 2.0, tau: 0.5}
controllers:
  - {kind: pid_servo, poles: [-4, -5, -20], zero: -3, label: slow}
  - {kind: pid_servo, poles: [-8, -10, -40], zero: -6, label: fast}
simulation: {duration: 4.0, perturbation: {value: 0.5, time: 2.5}}
"""


@pytest.fixture(scope="module")
def step_load():
    return run(parse_spec(STEP_LOAD))


def test_a_step_with_a_load_against_numpy(step_load):
    table = step_load.table
    keys = [m.key for m in table.metrics]
    assert "max_error_before" not in keys  # the largest error of a step's run is the step itself
    assert "rms_settled_before" not in keys and "rms_error_after" not in keys
    for label in step_load.labels:
        sim = step_load[label].simulation
        t = np.asarray(sim.time)
        x = np.asarray(sim.state)[:, 0]
        xd = np.asarray(sim.desired).ravel()
        e = np.abs(xd - x)
        row = table.row(label).values
        assert row["max_error_load"] == pytest.approx(e[t >= 2.5].max(), rel=1e-12)
        k = int(np.argmax(x >= x[0] + 0.9 * (xd[0] - x[0])))
        assert row["rise_time_before"] == pytest.approx(t[k] - t[0], abs=1e-12)
        assert row["rms_error_before"] == pytest.approx(math.sqrt(np.mean(e ** 2)), rel=1e-12)
    words = {m.key: m for m in table.metrics}
    assert words["rise_time_before"].label == "90 % rise time of the step"
    assert words["max_error_load"].meaning == ("largest |xD − x| from the load step's onset (2.5 s) to the end of "
                                               "the run")
    assert all("{" not in m.meaning for m in table.metrics)


def test_equal_overshoots_tie_and_the_faster_loop_wins_the_rest(step_load):
    """Both loops place their poles and zero at the same ratios, so their step responses are one shape on two time
    scales: the same overshoot (a tie), and the fast one rises in half the time (a win)."""
    winners = {w.metric.key: w for w in step_load.table.winners()}
    over = winners["overshoot"]
    assert over.tie and set(over.tied) == {"slow", "fast"} and "tie" in over.sentence
    rise = winners["rise_time_before"]
    assert not rise.tie and rise.label == "fast" and rise.value == pytest.approx(rise.second / 2, rel=0.02)
