"""The studies' budget: planned on the estimate, stopped by processor time (not by the wall clock)."""

from __future__ import annotations

import time

from designkit.studies.core.budget import SAFETY, Budget, cpu_seconds


def test_waiting_costs_no_processor_time_and_working_does():
    before = cpu_seconds()
    time.sleep(0.3)  # what a loaded machine does to a study: the wall clock runs, this process does not
    waited = cpu_seconds() - before
    before = cpu_seconds()
    end = time.process_time() + 0.2
    while time.process_time() < end:
        pass
    worked = cpu_seconds() - before
    assert waited < 0.1 and worked >= 0.15  # os.times counts in clock ticks (10 ms)


def test_the_safety_net_trips_beyond_its_factor_and_says_so():
    budget = Budget(seconds=1.0, estimate=0.25)
    assert budget.capacity() == 4 and budget.affords(4) and not budget.affords(5)
    budget.record(SAFETY * 1.0 - 0.01)
    assert not budget.overrun
    budget.record(0.02)
    assert budget.overrun and not budget.affords(1)
    assert "processor time" in budget.overrun_words() and "2 variants" in budget.overrun_words()
