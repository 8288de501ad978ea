"""Default integration step and duration; refusal of incompatible user steps."""

from __future__ import annotations

import pytest

from designkit.errors import SpecError
from designkit.schema.spec import Spec
from designkit.simulation.run import simulate
from designkit.simulation.timing import rates_of, resolve
from tests.simulation.helpers import TRACKING, design_of, make_spec


def _timing(spec, rate=0.0, horizon=0.0):
    design = design_of(spec)
    rates = rates_of(design.poles, design.closed_loop.poles, [-1.0 / design.plant.tau], reference_rate=rate)
    return resolve(spec, rates, horizon)


def test_default_dt_from_the_fastest_pole_and_default_duration_from_the_slowest():
    t = _timing(make_spec())
    assert t.dt == pytest.approx(0.001)  # 0.02 / 20 1/s
    assert t.settings["duration"] == pytest.approx(2.5)  # 10 / 4 1/s
    assert t.steps_per_sample == 0 and t.delay_steps == 0


def test_default_duration_from_the_settling_time_requirement_and_perturbation():
    spec = Spec.model_validate({
        "name": "x", "plant": {"kind": "link", "Km": 2, "tau": 0.5},
        "controller": {"kind": "pid_servo", "poles": [-4, -5, -20]}, "requirements": {"settling_time": 1.2},
        "simulation": {"perturbation": {"value": 1.0, "time": 2.0}, "delay": 0.01},
    })
    assert _timing(spec).settings["duration"] == pytest.approx(2.0 + 3 * 1.2 + 0.01)


def test_tracking_duration_adds_the_trajectory():
    spec = make_spec(TRACKING, trajectory={"kind": "quintic", "duration": 2.0})
    assert _timing(spec, horizon=2.0).settings["duration"] == pytest.approx(2.0 + 10 / 10)


def test_default_dt_divides_sampling_period_and_delay():
    t = _timing(make_spec(sampling_period=0.005, delay=0.0035))
    assert t.steps_per_sample * t.dt == pytest.approx(0.005)
    assert t.delay_steps * t.dt == pytest.approx(0.0035)
    assert t.dt <= 0.001 + 1e-15


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"dt": 0.003, "sampling_period": 0.01}, "simulation.sampling_period"),
        ({"dt": 0.004, "delay": 0.01}, "simulation.delay"),
        ({"dt": 0.1}, "too coarse"),
        ({"dt": 0.04, "duration": 0.03}, "smaller than the duration"),
        ({"dt": 1e-6, "duration": 10.0}, "more than"),
    ],
)
def test_incompatible_user_dt_is_refused_naming_simulation_dt(options, message):
    spec = make_spec(**options)
    with pytest.raises(SpecError, match=message) as err:
        simulate(spec, design_of(spec))
    assert err.value.path == "simulation.dt"


def test_the_switching_step_of_a_law_whose_largest_step_is_too_small_to_count():
    """Events at 1 s and 0.5 s: their common divisor is 0.5 s, split into ceil(0.5 / 0.3) = 2 steps of 0.25 s; a
    largest step of 2.6e-310 s would need more steps than a float counts: the step is left as is (the step bound
    then refuses the run, naming simulation.duration)."""
    from designkit.simulation.timing import _switching_dt

    assert _switching_dt(0.3, [1.0, 0.5]) == pytest.approx(0.25, rel=1e-12)
    assert _switching_dt(2.6e-310, [1.0]) == 2.6e-310
    assert _switching_dt(0.3, []) == 0.3


def test_a_default_step_too_small_to_round_is_kept_for_the_step_bound():
    """0.0031 rounds down to 2.5e-3; 0, 1e-310 (subnormal) cannot be rounded to {1, 2, 2.5, 5} x 10^k and are kept (0 as
    the smallest float), so that the step bound refuses the run instead of the logarithm failing."""
    from designkit.simulation.timing import _nice_floor

    assert _nice_floor(0.0031) == pytest.approx(2.5e-3, rel=1e-12)
    assert _nice_floor(1e-310) == 1e-310
    assert _nice_floor(0.0) == 5e-324
