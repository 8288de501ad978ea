"""numerics.compile: auto compiles a loop that will run more than once, and the pair of a smooth loop always."""

from __future__ import annotations

import pytest

from designkit.models.codegen import find_compiler
from designkit.schema.spec import Spec
from designkit.simulation.run import COMPILE_BREAK_EVEN, build
from tests.simulation.helpers import design_of, make_spec

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="no C compiler on PATH")


def _spec(**numerics: object) -> Spec:
    base = make_spec(duration=20.0, dt=0.001, nonlinearity={"kind": "saturation", "limit": 20.0})
    return Spec.model_validate({**base.model_dump(exclude={"numerics"}), "numerics": numerics})


def test_a_loop_run_more_than_once_compiles_and_one_run_once_does_not(tmp_path, monkeypatch):
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    spec = _spec(integrator="rk4")
    design = design_of(spec)
    once = build(spec, design)
    assert once.compiled["interpreted_estimate_s"] < COMPILE_BREAK_EVEN and once.compiled["compiled"] is False
    twice = build(spec, design, expected_runs=2)
    assert twice.compiled["compiled"] is True and twice.compiled["why"] == "compiled now"
    assert build(spec, design).compiled["why"] == "cached library"  # and a later single run finds it


def test_the_pair_of_a_smooth_loop_compiles_by_default_and_not_under_never(tmp_path, monkeypatch):
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    design = design_of(_spec())
    default = build(_spec(), design)
    assert default.dopri5.library is not None and default.compiled["why"] == "compiled now"
    assert build(_spec(), design).compiled["why"] == "cached library"
    never = build(_spec(compile="never"), design)
    assert never.dopri5.library is None and never.compiled["compiled"] is False
