"""``finite_run``: offered only for a run that diverged, a FAIL naming the first instant a record stops being
finite (or leaves 1e150 in magnitude); ``SimulationResult.diverged_at`` finds that instant."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from designkit.verification.checks.finite_run import RULE
from designkit.verification.suite import Context
from tests.verification.helpers import step_result

T = np.linspace(0.0, 1.0, 11)


def _run(x1, u, controller=None):
    """A run with the state ``(x1, 5 e^(-5t))`` and the controller state ``controller`` (zeros by default)."""
    sim = step_result(T, x1, u)
    state = np.column_stack([x1, 5 * np.exp(-5 * T)])
    xc = np.zeros(T.size) if controller is None else np.asarray(controller, float)
    return replace(sim, state=state, measured=state.copy(), controller_state=xc.reshape(-1, 1))


def test_finite_run_is_not_offered():
    sim = _run(1 - np.exp(-5 * T), np.exp(-5 * T))
    assert sim.diverged_at is None
    assert not RULE.applies(None, Context(None, sim))


@pytest.mark.parametrize("where, k", [("state", 4), ("command", 7), ("controller", 2), ("huge", 9)])
def test_first_instant_not_finite_is_named(where, k):
    x1, u, xc = 1 - np.exp(-5 * T), np.exp(-5 * T), np.zeros(T.size)
    if where == "state":
        x1[k:] = np.nan
    elif where == "command":
        u[k:] = np.inf
    elif where == "controller":
        xc[k] = -np.inf
    else:
        u[k] = 1e151  # beyond 1e150: a diverged loop, though a finite double
    sim = _run(x1, u, xc)
    assert sim.diverged_at == T[k]
    ctx = Context(None, sim)
    assert RULE.applies(None, ctx)
    (check,) = RULE.run(None, ctx)
    assert check.name == "finite_run" and check.passed is False
    assert f"the run diverged at t = {T[k]:.6g} s" in check.detail
    assert check.certificate["diverged_at_s"] == T[k]


def test_diagnosis_names_the_instant_and_the_other_failed_checks():
    from types import SimpleNamespace

    x1, u = 1 - np.exp(-5 * T), np.exp(-5 * T)
    u[6:] = np.nan
    (check,) = RULE.run(None, Context(None, _run(x1, u)))
    other = SimpleNamespace(name="settling_time", passed=False)
    cause, fix = RULE.diagnose(SimpleNamespace(checks=(check, other)), check)
    assert f"t = {T[6]:.6g} s" in cause
    assert "settling_time" in fix and "finite_run" not in fix
