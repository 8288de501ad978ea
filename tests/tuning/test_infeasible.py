"""The minimum-time bound against a numerical integration of the full command, and the conflict of a search's
candidates."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.tuning.evaluate import Evaluation
from designkit.tuning.infeasible import conflict, reach_time, rest_to_rest_time


def _link(Km, tau, u):
    return lambda t, x: [x[1], -x[1] / tau + Km / tau * u(t, x)]


@pytest.mark.parametrize(("Km", "tau", "U", "A"), [(2.0, 0.5, 5.0, 1.0), (1.0, 3.0, 0.5, 0.2), (10.0, 0.05, 2.0, 2.0)])
def test_reach_time_is_when_the_full_command_reaches_the_level(Km, tau, U, A):
    hit = lambda t, x: x[0] - A  # noqa: E731
    hit.terminal = True
    sol = solve_ivp(_link(Km, tau, lambda t, x: U), (0, 100), [0, 0], events=hit, rtol=1e-10, atol=1e-12)
    assert reach_time(A, Km, tau, U) == pytest.approx(sol.t_events[0][0], rel=1e-6)


@pytest.mark.parametrize(("Km", "tau", "U", "A"), [(2.0, 0.5, 5.0, 1.0), (1.0, 3.0, 0.5, 0.2)])
def test_rest_to_rest_time_stops_at_the_target(Km, tau, U, A):
    # bisect on the switching instant: the bang-bang move that stops exactly at A takes the closed form's time
    def stop(t1):
        u = lambda t, x: U if t < t1 else -U  # noqa: E731
        halt = lambda t, x: x[1] if t > t1 else 1.0  # noqa: E731
        halt.terminal, halt.direction = True, -1
        sol = solve_ivp(_link(Km, tau, u), (0, 100), [0, 0], events=halt, rtol=1e-11, atol=1e-12, max_step=1e-3)
        return sol.y_events[0][0][0], sol.t_events[0][0]

    lo, hi = 0.0, 50.0
    for _ in range(50):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if stop(mid)[0] < A else (lo, mid)
    assert rest_to_rest_time(A, Km, tau, U) == pytest.approx(stop(hi)[1], rel=1e-4)


def _ev(margins, certified=True):
    return Evaluation(np.zeros(1), {}, min(margins.values()), margins, certified=certified)


def test_the_pair_is_what_the_active_requirement_trades_against():
    cands = (_ev({"overshoot": 0.5, "settling_time": -0.6, "max_control": 0.9}),
             _ev({"overshoot": 0.4, "settling_time": -0.1, "max_control": -0.8}),  # settling pushed: torque pays
             _ev({"overshoot": 0.3, "settling_time": -0.3, "max_control": -0.2}),
             _ev({"overshoot": 0.9, "settling_time": 0.5, "max_control": 0.9}, certified=False))  # not certified
    found = conflict(cands, cands[2])
    assert (found.active, found.against) == ("settling_time", "max_control")
    assert found.alone == {"overshoot": 0.5, "settling_time": -0.1, "max_control": 0.9}
    assert found.compromise == cands[2].margins
