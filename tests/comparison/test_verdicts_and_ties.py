"""The comparison's sentences say what the checks' statuses say, and a difference within the tie tolerance is a tie.

Built from constructed check lists and tables (no run), so that each sentence is compared with the statuses it
must be written from, and a sentence that overstates them (``all 10 of its checks pass`` with one undecided)
fails.
"""

from __future__ import annotations

import re

import pytest

from designkit.comparison.table import TIE_TOLERANCE, ComparisonTable, ControllerRow, Metric, tally, tie
from designkit.comparison.verdicts import CheckLine, check_lines, member_sentence, member_verified
from designkit.verification.check import Check, all_passed


def _checks(required: dict[str, int], informational: dict[str, int] | None = None) -> list[CheckLine]:
    out = []
    for required_, counts in ((True, required), (False, informational or {})):
        for status, n in counts.items():
            out += [CheckLine(f"{status.lower()}_{required_}_{k}", f"{status.capitalize()} check {'ABCDEFGHIJ'[k]} "
                              f"{'required' if required_ else 'informational'}", status, required_) for k in range(n)]
    return out


def _counts(clause: str) -> dict[str, int]:
    """The counts a clause states: ``5 pass, 1 fails and 2 are undecided`` -> {PASS: 5, FAIL: 1, UNDECIDED: 2}."""
    found = {"PASS": r"(\d+) pass(?:es)?\b", "FAIL": r"(\d+) fails?\b", "UNDECIDED": r"(\d+) (?:is|are) undecided"}
    return {status: int(m.group(1)) for status, pattern in found.items() if (m := re.search(pattern, clause))}


def test_an_undecided_informational_check_is_named_and_never_counted_as_a_pass():
    """The PID of robel: 7 required checks pass, of 3 informational 2 pass and 1 is undecided."""
    checks = _checks({"PASS": 7}, {"PASS": 2, "UNDECIDED": 1})
    sentence = member_sentence("pid", "PID position servo", checks)
    assert sentence.startswith("pid (PID position servo) is verified: ")
    assert "all 10" not in sentence and "all 7 of its required checks pass" in sentence
    assert "Of its 3 informational checks (not part of the verdict), 2 pass and 1 is undecided: " in sentence
    assert "Undecided check A informational" in sentence
    assert "Pass check" not in sentence  # only the checks that did not pass are named


def test_an_informational_failure_is_named_and_the_controller_stays_verified():
    """The sliding regulator of robel: 7 required pass, of 6 informational 5 pass and 1 fails."""
    checks = _checks({"PASS": 7}, {"PASS": 5, "FAIL": 1})
    sentence = member_sentence("sliding-regulator", "Variable structure state regulator (theorem 3)", checks)
    assert " is verified: all 7 of its required checks pass." in sentence
    assert "all 13" not in sentence
    assert "Of its 6 informational checks (not part of the verdict), 5 pass and 1 fails: Fail check A " \
           "informational." in sentence


@pytest.mark.parametrize(("required", "informational"), [
    ({"PASS": 5, "FAIL": 1, "UNDECIDED": 2}, {"PASS": 1}),
    ({"PASS": 4, "UNDECIDED": 1}, {"FAIL": 2, "UNDECIDED": 1}),
    ({"FAIL": 3}, {}),
    ({"PASS": 9}, {"PASS": 3}),
    ({"UNDECIDED": 1}, {"PASS": 2}),
])
def test_counts_and_names_follow_the_statuses(required, informational):
    checks = _checks(required, informational)
    sentence = member_sentence("c", "a family", checks)
    verified = all(c.status == "PASS" for c in checks if c.required)
    assert member_verified(checks) is verified
    assert (" is verified:" in sentence) is verified and (" is not verified:" in sentence) is (not verified)
    for c in checks:  # every check that did not pass is named, none that passed
        assert (c.label in sentence) is (c.status != "PASS"), c.label
    if all(c.status == "PASS" for c in checks):
        n_req, n_info = sum(required.values()), sum(informational.values())
        assert f"all {n_req + n_info} of its checks pass ({n_req} required, {n_info} informational)" in sentence
        return
    required_clause, informational_clause = (re.split(r"\. (?=[A-Z])", sentence, maxsplit=1) + [""])[:2]
    for clause, counts in ((required_clause, required), (informational_clause, informational)):
        n = sum(counts.values())
        if n == 0:
            continue
        if n == 1 or all(k == "PASS" for k in counts):  # "its only ... check fails", "all 4 of its ... pass"
            assert ("its only" in clause.lower()) is (n == 1), clause
            continue
        assert f"{n} {'required' if clause is required_clause else 'informational'} checks" in clause
        stated = re.split(r"[:;]", re.split(r" checks(?: \(not part of the verdict\))?, ", clause, maxsplit=1)[1])[0]
        assert _counts(stated) == {k: v for k, v in counts.items() if v}, clause


def test_the_sentence_agrees_with_the_pipelines_verdict_on_real_checks():
    checks = [Check("lyapunov", True), Check("common_lyapunov", None, required=False, label="Common Lyapunov function"),
              Check("overshoot", False, label="Overshoot"), Check("loop_margins", True, required=False)]
    lines = check_lines(checks)
    assert [c.status for c in lines] == ["PASS", "UNDECIDED", "FAIL", "PASS"]
    assert [c.required for c in lines] == [True, False, True, False]
    assert member_verified(lines) is all_passed(checks) is False
    sentence = member_sentence("x", "PID position servo", lines)
    assert "is not verified: of its 2 required checks, 1 passes and 1 fails: Overshoot." in sentence
    assert "Of its 2 informational checks (not part of the verdict), 1 passes and 1 is undecided: Common " \
           "Lyapunov function." in sentence
    assert lines[3].label == "Loop margins"  # a check without a label is named from its name


def _table(values: dict[str, float], key: str = "m", unit: str = "s") -> ComparisonTable:
    metric = Metric(key, "metric in words", unit, "how")
    rows = tuple(ControllerRow(label, "kind", "family", True, {key: v}, ()) for label, v in values.items())
    return ComparisonTable((metric,), rows, "rad", "V")


def test_tie_tolerance_is_relative_to_the_larger_value():
    assert TIE_TOLERANCE == 0.01
    assert tie(1.0, 1.0099) and tie(1.0099, 1.0) and tie(0.0, 0.0)
    assert not tie(1.0, 1.0102) and not tie(0.0, 1e-12)
    assert not tie(1.0, float("inf")) and tie(float("inf"), float("inf"))
    assert tie(-2.0, -2.015) and not tie(-2.0, -2.03)


def test_a_difference_within_the_tolerance_is_a_tie_not_a_win():
    """mrac-vs-selftune's RMS error: 0.3607 against 0.3616 rad (0.245 %) is a tie."""
    w, = _table({"mrac": 0.3607, "selftune": 0.3616}, unit="error").winners()
    assert w.tie and w.tied == ("mrac", "selftune")
    assert "tie" in w.sentence and "wins" not in w.sentence
    assert "0.3607 rad and 0.3616 rad differ by 0.25 % at most, within the 1 % tie tolerance" in w.sentence
    assert tally(("mrac", "selftune"), (w,)) == ("Of the 1 metric compared, mrac wins none and selftune wins none. "
                                                 "1 is a tie (values within 1 % of each other): metric in words.")


def test_a_difference_beyond_the_tolerance_is_a_win():
    w, = _table({"a": 2.0, "b": 2.05}).winners()
    assert not w.tie and w.tied == () and w.label == "a" and w.runner_up == "b"
    assert w.sentence == "On the metric in words, a wins with 2 s against 2.05 s for b (2.44 % lower)."
    assert tally(("a", "b"), (w,)) == "Of the 1 metric compared, a wins 1 and b wins none."


def test_three_way_tie_and_the_one_left_out():
    table = _table({"a": 1.004, "b": 1.0, "c": 1.5, "d": 1.009})
    w, = table.winners()
    assert w.tie and w.tied == ("b", "a", "d") and " c" not in w.sentence and "1.5 s" not in w.sentence
    json_, = table.winners_json()
    assert json_ == {"metric": "m", "label": "b", "value": 1.0, "runner_up": "a", "runner_up_value": 1.004,
                     "tie": True, "tied": ["b", "a", "d"]}


def test_json_winner_without_a_tie():
    json_, = _table({"a": 1.0, "b": 3.0}).winners_json()
    assert json_["tie"] is False and json_["tied"] == [] and json_["label"] == "a"
