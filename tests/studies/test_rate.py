"""The rate study (src/designkit/studies/rate): offered to switching families only, its rows against the run's record
counted here, its settings refused with their key paths, its budget respected."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from designkit.families import FAMILIES, family
from designkit.studies import STUDIES
from designkit.studies.core.study import StudyContext
from designkit.studies.rate import RateSettings

SPECS = Path(__file__).resolve().parents[2] / "specs"
SHORT = "simulation:\n  duration: 2.0\n  perturbation: {value: 1.0, time: 1.0}\n"
"""The sliding-mode link's scenario, its run shortened from 3 s to 2 s (the load still at 1 s)."""


def _text(extra: str = "") -> str:
    text = (SPECS / "sliding-mode-link.yaml").read_text()
    head = text[: text.index("simulation:")]
    return head + SHORT + extra


@pytest.fixture(scope="module")
def link():
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    return run(parse_spec(_text()))


def _study(result, rates, budget=15.0):
    return STUDIES["rate"].run(StudyContext(result, family(result.design.kind), RateSettings(rates=rates), budget))


@pytest.fixture(scope="module")
def at_1khz(link):
    return _study(link, [1000.0])


def test_offered_by_the_trait_switching_only(link):
    rate = STUDIES["rate"]
    own = family(link.design.kind)
    assert "switching" in own.traits and rate.applies(link, own)
    planted = dataclasses.replace(own, traits=tuple(t for t in own.traits if t != "switching") + ("model_based",))
    assert not rate.applies(link, planted)  # the same run, a family that does not declare it: not offered
    switching = {k for k in FAMILIES if "switching" in family(k).traits}
    assert switching == {"sliding_mode", "pid_sliding_mode", "vsc", "sliding_mode_identification"}
    for kind in FAMILIES:
        assert rate.applies(link, family(kind)) == (kind in switching), kind


def _own_reversals(u: np.ndarray, t: np.ndarray, window: float) -> int:
    """Turning points of ``u`` with the hysteresis of docs/verification (a move against the current direction by
    more than h from the last extremum), h = max(0.5 RMS(s), 1e-3 range(u)), s = u minus its centred moving
    average over ``window`` computed here by a box filter over the uniform record."""
    dt = t[1] - t[0]
    half = int(round(window / 2 / dt))
    c = np.concatenate(([0.0], np.cumsum(u)))
    k = np.arange(u.size)
    lo, hi = np.maximum(k - half, 0), np.minimum(k + half, u.size - 1)
    avg = (c[hi + 1] - c[lo]) / (hi - lo + 1)
    s = u - avg
    h = max(0.5 * math.sqrt(float(np.mean(s**2))), 1e-3 * float(np.ptp(u)))
    count, direction, ext = 0, 0, u[0]
    lo_, hi_ = u[0], u[0]
    for v in u[1:]:
        if direction == 0:
            lo_, hi_ = min(lo_, v), max(hi_, v)
            if v - lo_ > h:
                direction, ext = 1, v
            elif hi_ - v > h:
                direction, ext = -1, v
        elif direction * (v - ext) > 0:
            ext = v
        elif direction * (ext - v) > h:
            direction, ext, count = -direction, v, count + 1
    return count


def test_the_1khz_row_against_the_record_counted_here(link, at_1khz):
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    (row,) = at_1khz.entries[0].rows
    assert row.value == 1000.0 and row.outcome == "verified"
    # the same spec sampled at 1 kHz, written here as text and run by the pipeline
    text = _text().replace("  duration: 2.0\n", "  duration: 2.0\n  sampling_period: 0.001\n")
    sim = run(parse_spec(text)).simulation
    t = np.asarray(sim.time, float)
    u = np.asarray(sim.u_command, float)[:, 0]
    # the command is held: it changes only at the samples, every millisecond
    changes = t[1:][np.abs(np.diff(u)) > 0]
    assert changes.size > 100 and np.allclose(np.round(changes / 1e-3) * 1e-3, changes, atol=1e-9)
    steps = 1e-3 / np.diff(t).mean()
    assert row.metrics["dt"] == pytest.approx(t[1] - t[0]) and abs(steps - round(steps)) < 1e-6
    assert row.metrics["sampling_period"] == 1e-3
    # reversals counted here (window 1/|p|max = 1/5 s for the sliding pole -5 1/s, above two periods)
    mine = _own_reversals(u, t, 0.2)
    assert row.metrics["reversal_rate"] * (t[-1] - t[0]) == pytest.approx(mine, rel=0.005)
    assert mine <= (t[-1] - t[0]) * 1000 + 1  # a held command reverses at most once a sample
    # precision: the largest |x - xD| over the last tenth of the run, and the final error within it
    e = np.asarray(sim.tracked_positions, float)[:, 0] - np.asarray(sim.desired, float)[:, 0]
    tail = np.abs(e[t >= t[-1] - 0.1 * (t[-1] - t[0])])
    assert row.metrics["steady_error"] == pytest.approx(tail.max(), rel=1e-9)
    assert row.metrics["steady_error"] >= abs(e[-1])
    # effort: RMS of u over the run; the switching part's peak within the command's range
    assert row.metrics["command_rms"] == pytest.approx(math.sqrt(np.mean(u**2)), rel=1e-9)
    assert row.metrics["chatter_peak"] <= np.ptp(u)


def test_what_the_physics_guarantees_at_every_rate(link):
    done = _study(link, [20_000.0, 5_000.0, 500.0])
    rows = done.entries[0].rows
    assert [r.value for r in rows] == [500.0, 5_000.0, 20_000.0]  # increasing rate
    for r in rows:
        m = r.metrics
        assert m["sampling_period"] == pytest.approx(1 / r.value, rel=1e-12)
        n = m["sampling_period"] / m["dt"]
        assert abs(n - round(n)) < 1e-6  # the default step divides the period
        assert m["reversal_rate"] <= r.value * (1 + 1e-9)  # at most one reversal a sample
        assert m["chatter_rms"] <= m["chatter_peak"] * (1 + 1e-12)
    hold = done.entries[0].recommended
    expected = None
    for r in sorted(rows, key=lambda r: -r.value):  # the lowest rate with every rate above it passing
        if r.outcome != "verified":
            break
        expected = r.value
    assert (hold.value if hold else None) == expected
    text = " ".join(done.section.questions[0].sentences)
    if expected is not None:
        assert f"{expected:g} Hz" in text or f"{expected / 1000:g} kHz" in text
    assert done.figures and done.figures[0].filename == "fig-rate-study.svg"


def test_a_tiny_budget_leaves_rates_out_and_says_so(link):
    from designkit.runner.variants import changed_spec
    from designkit.studies.rate import rung_cost

    rates = [20_000.0, 5_000.0, 1_000.0, 500.0]
    cost = {r: rung_cost(changed_spec(link.loaded, [("simulation.sampling_period", 1 / r)]).spec, None, 1 / r)
            for r in rates}
    assert cost[20_000.0] > cost[500.0] >= 0.25  # a shorter period, more steps; never below the variant's floor
    budget = cost[20_000.0] + cost[500.0] + 0.5 * min(cost.values())  # the two ends and not a third
    done = _study(link, rates, budget=budget)
    rows = done.entries[0].rows
    assert sorted(r.value for r in rows) == [500.0, 20_000.0]  # the ends first
    assert done.runs == 2
    assert "5 kHz, 1 kHz not run" in done.reduced and "raise studies.budget" in done.reduced
    assert "Reduced: " in done.section.intro


@pytest.mark.parametrize(("rate", "path"), [
    ("{rates: [0]}", "studies.rate.rates[0]"),
    ("{rates: [1000, -5]}", "studies.rate.rates[1]"),
    ("{rates: [1000, 0.2]}", "studies.rate.rates[1]: 0.2 Hz samples every 5 s, not shorter than the run"),
    ("{rates: [1000, 1000]}", "studies.rate.rates[1]: 1000 Hz is listed twice"),
    ("{rates: [2.0e6]}", "studies.rate.rates[0]"),
    ("{rates: []}", "studies.rate.rates"),
    ("{rate: 5}", "studies.rate.rate"),
])
def test_settings_refused_with_the_key_path(rate, path, tmp_path, capsys):
    from tests.cli_input import assert_bad_input

    assert_bad_input(tmp_path, capsys, (SPECS / "sliding-mode-link.yaml").read_text() + f"studies: {{rate: {rate}}}\n",
                     path)


def test_a_period_longer_than_a_default_duration_is_refused(tmp_path, capsys):
    from tests.cli_input import assert_bad_input

    text = (SPECS / "sliding-mode-link.yaml").read_text().replace("  duration: 3.0\n", "")
    assert_bad_input(tmp_path, capsys, text + "studies: {rate: {rates: [1.0e-3]}}\n",
                     "studies.rate.rates[0]: 0.001 Hz samples every 1000 s, not shorter than the run (the run's "
                     "default duration")
