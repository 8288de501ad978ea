"""The rate study's ladder: the key its sampling period is set through, the integration step that goes with it, the
reference's last plateau, and a member's rate study run once and kept for its own studies."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from designkit.schema.loader import parse_spec
from designkit.studies.rate.ladder import SAMPLING_KEYS, rung_changes, sampling_key
from designkit.studies.rate.measure import plateau

SPECS = Path(__file__).resolve().parents[2] / "specs"


def _fake(text: str, settings: dict | None = None) -> SimpleNamespace:
    """A run's ``loaded`` spec and its simulation's settings (what the ladder reads), nothing run."""
    return SimpleNamespace(loaded=parse_spec(text), simulation=SimpleNamespace(settings=settings or {}))


def _link(extra: str = "") -> str:
    return (SPECS / "sliding-mode-link.yaml").read_text().replace("  duration: 3.0\n", "  duration: 3.0\n" + extra)


def test_the_key_is_the_one_the_spec_samples_through():
    assert sampling_key(_fake(_link())) == SAMPLING_KEYS[0] == "implementation.sampling_period"
    assert sampling_key(_fake(_link("  sampling_period: 0.001\n"),
                              {"sampling_period": 0.001, "sampling_period_source": "simulation.sampling_period"})
                        ) == "simulation.sampling_period"
    with_implementation = _link() + "implementation: {sampling_period: 0.001}\n"
    assert sampling_key(_fake(with_implementation)) == "implementation.sampling_period"
    smid = (SPECS / "smid-link.yaml").read_text()  # the law declares its period: controller.sampling_period
    assert sampling_key(_fake(smid, {"sampling_period": 0.002, "sampling_period_source": "controller.sampling_period"})
                        ) == "controller.sampling_period"


def _largest_dividing_step(period: float, not_above: float) -> float:
    """Brute force: the largest period/n (n = 1, 2, ...) not above ``not_above``."""
    return max(period / n for n in range(1, 100_000) if period / n <= not_above * (1 + 1e-12))


@pytest.mark.parametrize(("dt", "rate"), [(3.0e-5, 1000.0), (3.0e-5, 20_000.0), (7.0e-4, 2000.0), (1.0e-3, 500.0)])
def test_a_given_step_that_does_not_divide_the_period_is_replaced(dt, rate):
    rung = rung_changes(_fake(_link(f"  dt: {dt}\n")), "simulation.sampling_period", rate)
    changes = dict(rung.changes)
    assert changes["simulation.sampling_period"] == pytest.approx(1 / rate, rel=1e-15)
    n = (1 / rate) / dt
    if abs(n - round(n)) < 1e-9:
        assert "simulation.dt" not in changes and rung.dt_note == ""
    else:
        assert changes["simulation.dt"] == pytest.approx(_largest_dividing_step(1 / rate, dt), rel=1e-12)
        assert "does not divide" in rung.dt_note


def test_a_step_left_out_is_left_to_the_default():
    rung = rung_changes(_fake(_link()), "simulation.sampling_period", 1000.0)
    assert rung.changes == (("simulation.sampling_period", 0.001),) and rung.dt_note == ""


def test_the_row_is_run_with_the_replaced_step(tmp_path):
    from designkit.families import family
    from designkit.pipeline import run
    from designkit.studies import STUDIES
    from designkit.studies.core.study import StudyContext
    from designkit.studies.rate import RateSettings

    text = _link("  dt: 3.0e-5\n").replace("  duration: 3.0\n", "  duration: 1.2\n")
    result = run(parse_spec(text))
    done = STUDIES["rate"].run(StudyContext(result, family("sliding_mode"), RateSettings(rates=[1000.0]), 15.0))
    (row,) = done.entries[0].rows
    assert row.metrics["dt"] == pytest.approx(1e-3 / 34, rel=1e-12)  # 33.3 steps of 3e-5 s: 34 of 2.94e-5 s
    assert "replaced by 2.941 × 10⁻⁵ s (34 steps a period)" in done.section.questions[0].sentences[0]


def test_the_last_plateau_of_a_reference():
    t = np.linspace(0.0, 20.0, 2001)
    step = np.ones((t.size, 1))
    assert plateau(t, step) == (0, t.size)
    square = np.where(np.floor(t) % 2 == 0, 0.5, -0.5)[:, None]  # jumps every second, the last on the last sample
    first, end = plateau(t, square)
    assert (t[first], t[end - 1]) == (19.0, pytest.approx(19.99))
    sine = np.sin(t)[:, None]
    assert plateau(t, sine) == (0, t.size)


def test_a_members_rate_study_runs_once_and_is_kept_for_its_own_studies():
    from designkit.pipeline import run
    from designkit.studies import run_studies, study_of

    text = _link().replace("  duration: 3.0\n", "  duration: 1.2\n") + "studies: {budget: 0.3, rate: {rates: [1000]}}\n"
    result = run(parse_spec(text))
    first = study_of(result, "rate")
    assert first is not None and [r.value for r in first.entries[0].rows] == [1000.0]
    assert study_of(result, "rate") is first
    assert next(st for st in run_studies(result) if st.name == "rate") is first
    assert study_of(result, "lab3") is None  # a comparison study is no run's own


def test_a_law_that_declares_its_period_is_studied_about_its_own_rate():
    from designkit.studies.rate.ladder import DEFAULT_RATES, OWN_FACTORS, default_rates

    smid = _fake((SPECS / "smid-link.yaml").read_text(),
                 {"sampling_period": 0.002, "sampling_period_source": "controller.sampling_period"})
    rates, words = default_rates(smid, sampling_key(smid))
    assert rates == pytest.approx([2000.0, 1000.0, 500.0, 250.0, 125.0], rel=1e-12)  # 500 Hz times 4 .. 1/4
    assert len(OWN_FACTORS) == 5 and "controller.sampling_period" in words
    link = _fake(_link())
    assert default_rates(link, sampling_key(link)) == (DEFAULT_RATES, "")
