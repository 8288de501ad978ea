"""The verdict logic of Check values: undecided is never a pass; informational checks do not count."""

from __future__ import annotations

from designkit.verification.check import Check, all_passed, not_passed


def test_undecided_required_check_is_not_a_pass():
    checks = [Check("a", True), Check("b", None)]
    assert not all_passed(checks)
    assert [c.name for c in not_passed(checks)] == ["b"]
    assert checks[1].status == "UNDECIDED"


def test_informational_check_does_not_change_the_verdict():
    checks = [Check("a", True), Check("common_lyapunov", None, required=False)]
    assert all_passed(checks)
    assert not_passed(checks) == ()
    assert checks[1].to_dict()["required"] is False


def test_failed_required_check_fails():
    checks = [Check("a", False, detail="x"), Check("b", True, required=False)]
    assert not all_passed(checks)
    assert Check("a", False).status == "FAIL"
