"""The requirement margins' gradients through the simulated loop (CasADi forward sensitivities) against central finite
differences of the same margins, each side a simulation of its own; and which loops the gradient search takes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import designkit as dk
from designkit.errors import SpecError
from designkit.tuning.api import prepare
from tests.tuning.specs import SIMNOG

SPECS = Path(__file__).resolve().parents[2] / "specs"


def _margins(problem, space, x, point):
    """Every requirement's normalised margin at ``x`` on the plant at ``point``: the spec with the values at ``x``,
    the family's design for the nominal plant, the runner's simulation of it on that plant, the family's checks."""
    from designkit.families import synthesize
    from designkit.runner.variants import changed_spec
    from designkit.simulation.run import build
    from designkit.tuning.evaluate import margins_on

    loaded = changed_spec(problem.loaded, space.changes(x))
    design = synthesize(loaded.spec, problem.plant)
    plant = problem.plant.with_params(**point) if point else problem.plant
    return margins_on(problem, loaded.spec, design, plant, build(loaded.spec, design, plant=plant).run())


@pytest.fixture(scope="module")
def simnog():
    return prepare(dk.parse_spec(SIMNOG))


def test_the_gradient_is_the_central_difference_of_the_margins(simnog):
    """SIMNOG's decentralized PID (four log coordinates: the poles and the zero), overshoot and settling time at the
    nominal plant and at both ends of m2 in [2, 4] kg at the spec's derived poles, and at one end at a point away:
    each derivative within 3 % (or 0.02) of the central difference with a step of 1e-3 in the log coordinates."""
    from designkit.tuning.sensitivity import gradients

    problem, space = simnog
    assert len(problem.points) == 2
    h = 1e-3
    for x, where in ((space.x0, (0, 1, 2)), (space.x0 + np.array([0.2, -0.15, 0.1, 0.3]), (1,))):
        g = gradients(problem, space, x)
        assert not g.failed and g.runs == 3
        for p in where:
            point = ({}, *problem.points)[p]
            for j in range(x.size):
                e = np.zeros(x.size)
                e[j] = h
                up, down = _margins(problem, space, x + e, point), _margins(problem, space, x - e, point)
                for r in problem.requirements:
                    fd = (up[r] - down[r]) / (2 * h)
                    assert g.gradients[p][r][j] == pytest.approx(fd, rel=0.03, abs=0.02), (x, point, j, r)
            here = _margins(problem, space, x, point)
            for r in problem.requirements:  # the margins of the sensitivity run (RK4, a coarser grid) are the run's
                assert g.margins[p][r] == pytest.approx(here[r], abs=2e-3), (point, r)


@pytest.mark.parametrize(("name", "why"), [
    ("tune-simnog-decentralized-pid.yaml", ""),
    ("tune-vsc-link.yaml", "discontinuous"),
    ("tune-ilc-simnog.yaml", "learns over trials"),
    ("tune-simnog-computed-torque.yaml", "sampled"),
])
def test_the_gradient_search_takes_smooth_loops_only(name, why):
    from designkit.families import synthesize
    from designkit.tuning.sensitivity import smooth_loop

    loaded = dk.load_spec(SPECS / name)
    problem, _ = prepare(loaded)
    said = smooth_loop(problem, synthesize(loaded.spec, problem.plant))
    assert (why in said and said) if why else said == ""


def test_the_gradient_search_is_refused_on_a_switching_loop(tmp_path):
    with pytest.raises(SpecError) as err:
        dk.tune(SPECS / "tune-vsc-link.yaml", out=tmp_path, method="gradient", write=False)
    assert err.value.path == "method" and "discontinuous" in str(err.value)
    with pytest.raises(SpecError) as err:
        dk.tune(SPECS / "tune-vsc-link.yaml", out=tmp_path, method="newton", write=False)
    assert err.value.path == "method"
    assert not any(tmp_path.iterdir())


def test_values_the_family_refuses_give_every_point_a_refused_margin(tmp_path):
    """A pole on the fixed zero (-3 1/s): the family refuses the design, the gradients say so and still give one
    margin per requirement and point (the evaluation's refused score, a zero gradient), as the epigraph needs."""
    from designkit.tuning.evaluate import REFUSED
    from designkit.tuning.sensitivity import gradients
    from tests.tuning.specs import LINK

    problem, space = prepare(dk.parse_spec(LINK.replace("tau: 0.5}", "tau: 0.5, uncertainty: {Km: [1.6, 2.4]}}")))
    x = space.x0.copy()
    x[0] = np.log(3.0)
    g = gradients(problem, space, x)
    assert g.failed.startswith("refused") and g.runs == 0
    assert len(g.margins) == len(g.gradients) == 1 + len(problem.points) == 3
    for m, gr in zip(g.margins, g.gradients, strict=True):
        assert set(m) == set(problem.requirements) and all(v == REFUSED for v in m.values())
        assert all(np.array_equal(v, np.zeros(x.size)) for v in gr.values())
