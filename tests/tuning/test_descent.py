"""The gradient search: SLSQP on the epigraph of the worst margin reaches the max-min of two margins known in closed
form, and on the one-link PID it reaches Nelder--Mead's optimum (and the independent one of python-control) in fewer
simulations, every candidate run as the tuner runs it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

import designkit as dk
from designkit.tuning.descent import slsqp
from tests.tuning.specs import LINK, write


@dataclass(frozen=True)
class _Candidate:
    x: np.ndarray
    score: float
    runs: int = 1


@dataclass(frozen=True)
class _Gradient:
    margins: tuple
    gradients: tuple
    runs: int = 1
    failed: str = ""
    x: np.ndarray = field(default_factory=lambda: np.zeros(2))


def _margins(x):
    """Two margins pulling apart: ``2 - (x0 - 1)^2 - x1^2`` and ``2 - (x0 + 1)^2 - x1^2``; their minimum is largest,
    1, at the origin, where both are equal."""
    return {"a": 2 - (x[0] - 1) ** 2 - x[1] ** 2, "b": 2 - (x[0] + 1) ** 2 - x[1] ** 2}


def test_the_epigraph_reaches_the_max_min_of_two_margins():
    runs = []

    def evaluate(x, above):
        runs.append(x)
        return _Candidate(np.asarray(x), min(_margins(x).values()))

    def gradient(x):
        g = {"a": np.array([-2 * (x[0] - 1), -2 * x[1]]), "b": np.array([-2 * (x[0] + 1), -2 * x[1]])}
        return _Gradient((_margins(x),), (g,), x=x)

    bounds = (np.array([-3.0, -3.0]), np.array([3.0, 3.0]))
    s = slsqp(evaluate, gradient, np.array([2.0, 1.5]), bounds, budget=30.0)
    assert s.best.score == pytest.approx(1.0, abs=1e-4)
    assert np.allclose(s.best.x, 0.0, atol=1e-2)
    assert s.evaluations[0].x.tolist() == [2.0, 1.5]  # the start is a candidate, and every candidate is evaluated
    assert len(s.evaluations) == len(runs) and s.simulations == len(runs) + s.sensitivity_runs
    assert s.sensitivity_runs >= 1 and s.method.startswith("gradient")


@pytest.mark.slow  # about 20 s: the link tuned by both searches
def test_the_link_reaches_nelder_meads_optimum_in_fewer_simulations(tmp_path):
    from designkit.tuning.api import choose, prepare
    from tests.tuning.test_link_optimum import _score

    loaded = dk.load_spec(write(tmp_path, LINK))
    problem, space = prepare(loaded)
    gradient, why = choose(problem, space, "auto", 0, 30.0)
    assert why.startswith("gradient")
    nm, _ = choose(problem, space, "nelder-mead", 0, 30.0)
    assert gradient.best.feasible and nm.best.feasible
    assert gradient.best.score >= nm.best.score - 0.01
    assert gradient.simulations < nm.simulations / 5
    # the gradient search's answer scored by the independent route (python-control's step responses)
    independent, _ = _score(np.asarray(gradient.best.values["poles"], dtype=complex))
    assert independent == pytest.approx(gradient.best.score, abs=0.01)
    assert independent > 0.6
