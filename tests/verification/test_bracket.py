"""The rule every bracketed certificate is judged by: a proof of falsity is a FAIL whatever a secondary route
says; a margin within the boundary tolerance is undecided."""

from __future__ import annotations

import pytest

from designkit.verification.bracket import bracket_verdict
from designkit.verification.tolerances import BOUNDARY_REL


@pytest.mark.parametrize(("lower", "upper", "agree", "passed", "reason"), [
    (0.6, 0.7, True, True, "proved"),
    (0.6, 0.7, False, None, "routes"),               # a pass the routes do not confirm
    (1.0317, 1.2, False, False, "proved_false"),     # proved above 1: routes disagreeing do not matter
    (1.0317, 1.2, True, False, "proved_false"),
    (1 - 4.6e-13, 1 - 4.5e-13, True, None, "boundary"),  # below 1, but by less than 1e-9
    (1 + 1e-12, 1 + 2e-12, True, None, "boundary"),
    (0.5, 1.5, True, None, "bracket"),
])
def test_verdict_of_a_bracket(lower, upper, agree, passed, reason):
    v = bracket_verdict(1.0 - upper, lower - 1.0, routes_agree=agree)
    assert v.passed is passed and v.reason == reason
    assert v.tolerance == BOUNDARY_REL
    assert (v.explanation == "") is (passed is not None)


def test_the_tolerance_scales_with_the_bound():
    assert bracket_verdict(5e-9, -1.0, bound=10.0).reason == "boundary"  # 5e-9 < 1e-9 * 10
    assert bracket_verdict(5e-9, -1.0, bound=1.0).passed is True
