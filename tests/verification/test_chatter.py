"""Chattering of commanded inputs (designkit.verification.chatter and the universal command_chatter check).

Independent routes: synthetic commands whose chattering is known by construction (a square wave at every step,
a random telegraph signal, a smooth sine, a reference step and a square-wave reference), and the runs where it is
expected to happen (the PUMA's Coulomb compensation at rest, the sliding-mode law).
"""

from __future__ import annotations

import numpy as np
import pytest

import designkit as dk
from designkit.verification.chatter import MIN_JUMPS, input_chatter

T = np.linspace(0.0, 2.0, 2001)


def test_a_command_switching_back_and_forth_chatters():
    rng = np.random.default_rng(0)
    telegraph = 26.0 * np.sign(np.cumsum(rng.normal(size=T.size)) % 7 - 3.5)  # dwell of a few samples
    m = input_chatter("u", T, telegraph + 0.1 * np.sin(T))
    assert m.chatters and m.jumps >= MIN_JUMPS and m.swing == pytest.approx(52.0, rel=0.01)
    every = 3.0 * (-1.0) ** np.arange(T.size)
    m = input_chatter("u", T, every, speed=np.zeros(T.size) + 1e-18)
    assert m.chatters and m.jumps == T.size - 1 and m.rate == pytest.approx(1000.0, rel=1e-2)
    assert m.slow_share == 1.0 and m.jump_share == pytest.approx(1.0)


@pytest.mark.parametrize("u", [np.sin(2 * np.pi * 3 * T), np.where(T > 0.5, 1.0, 0.0), np.cumsum(np.ones(T.size))])
def test_smooth_commands_and_single_jumps_do_not(u):
    assert not input_chatter("u", T, u).chatters


def test_jumps_that_the_reference_makes_are_not_chattering():
    square = np.sign(np.sin(2 * np.pi * 5 * T))  # 20 edges: the command follows the reference's jumps
    reference = np.column_stack([square, np.zeros(T.size), np.zeros(T.size)])
    assert input_chatter("u", T, 10 * square).chatters  # without the reference, alternating jumps
    assert not input_chatter("u", T, 10 * square, reference=reference).chatters


def _chatter_check(path):
    result = dk.run(dk.load_spec(path))
    return next(c for c in result.checks if c.name == "command_chatter")


@pytest.mark.slow
def test_the_pumas_coulomb_compensation_at_rest_is_seen_and_named():
    check = _chatter_check("specs/puma560-resolved-acceleration.yaml")
    assert check.passed is False and check.required is False
    row = check.certificate["inputs"][0]
    assert row["chatters"] and "Coulomb friction compensation" in row["source"]
    assert [r["chatters"] for r in check.certificate["inputs"][1:]] == [False] * 5
    assert check.warnings and "u1 chatters" in check.warnings[0]


def test_a_switching_law_is_not_offered_the_check_and_a_smooth_loop_passes():
    result = dk.run(dk.load_spec("specs/sliding-mode-link.yaml"))
    assert "command_chatter" not in [c.name for c in result.checks]  # its family measures its chattering band
    assert _chatter_check("specs/posspeed-link.yaml").passed is True


def test_a_command_that_stops_being_finite_is_measured_up_to_that_instant():
    """A diverged run's command (NaN from sample 1500 on) is measured as its finite part, without a warning."""
    import warnings

    rng = np.random.default_rng(1)
    u = 26.0 * np.sign(np.cumsum(rng.normal(size=T.size)) % 7 - 3.5)
    cut = u.copy()
    cut[1500:] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        m = input_chatter("u", T, cut, speed=np.ones(T.size), reference=np.zeros((T.size, 1, 3)))
    ref = input_chatter("u", T[:1500], u[:1500], speed=np.ones(1500), reference=np.zeros((1500, 1, 3)))
    assert m == ref and m.chatters
