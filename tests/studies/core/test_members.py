"""What a comparison study reads of its members: the words of a measured value, of a run's checks, of a run that
diverged or that its family refused; the budget's plan."""

from __future__ import annotations

import math

from designkit.comparison.verdicts import CheckLine
from designkit.studies.core.budget import Budget
from designkit.studies.core.members import Measured, Plan, amount, status_words
from designkit.studies.core.study import Row


def test_amounts_are_typeset():
    assert amount(10000.0) == "10000"  # an adaptation gain as the spec writes it
    assert amount(0.012345, "rad") == "0.0123 rad"
    assert amount(22937.5, "1/s") == "2.29 × 10⁴ 1/s" and amount(2.5e-7, "rad") == "2.5 × 10⁻⁷ rad"
    assert amount(math.inf, "s") == "never" and amount(math.inf, "rad") == "unbounded"
    assert amount(None) == "—" and amount(math.nan) == "—"
    assert amount(0.2, "N*m") == "0.2 N·m"


def test_status_words_say_what_the_checks_say():
    lines = (CheckLine("a", "Overshoot", "PASS"), CheckLine("b", "Settling time", "FAIL"),
             CheckLine("c", "Margins", "UNDECIDED", required=False))
    words = status_words(lines)
    assert words.startswith("not verified: of its 2 required checks, 1 passes and 1 fails: Settling time")
    assert "Margins" in words  # an informational check that did not pass is named too
    assert status_words((CheckLine("a", "Overshoot", "PASS"),)) == "verified: its only check passes"
    assert status_words(()) == "no checks were run"


def test_a_run_without_checks_says_why():
    diverged = Measured("mrac", "larger change", Row(1.0, 1.0, {}, "diverged", "the state leaves at t = 25 s"))
    refused = Measured("vsc", "no load", Row(1.0, 1.0, {}, "refused", "controller.relay_amplitude: give it"))
    assert diverged.status == "diverges: the state leaves at t = 25 s"
    assert refused.status == "is refused by its family: controller.relay_amplitude: give it"


def test_the_plan_says_what_the_budget_left_out():
    plan = Plan(Budget(1.0, 0.4))
    assert plan.fits("first", 2)
    plan.budget.record(0.1)
    plan.budget.record(0.1)
    assert not plan.fits("third", 1) and plan.left == ["third"]
