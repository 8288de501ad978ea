"""``designkit.tune``: a short end-to-end tuning, its files and its JSON; the API's argument errors."""

from __future__ import annotations

import json

import pytest

import designkit as dk
from tests.tuning.specs import LINK, write


def test_a_short_tuning_writes_a_verified_spec_and_a_report(tmp_path):
    result = dk.tune(write(tmp_path, LINK), out=tmp_path, budget=2.0)
    # the spec's own values already meet the requirements; the search keeps the best, never worse than them
    assert result.initial.feasible and result.verified
    assert result.best.score >= result.initial.score
    assert result.best.margins[result.best.active] == pytest.approx(result.best.score)
    assert result.search.simulations >= len(result.search.evaluations) >= 1
    tuned = dk.load_spec(result.files["spec"])
    assert tuned.spec.name == "link-tune-tuned" and tuned.spec.controller.zero == -3.0
    assert [complex(p).real for p in tuned.spec.controller.poles] == pytest.approx(result.best.values["poles"])
    payload = json.loads(json.dumps(result.to_json()))
    assert payload["verified"] is True and payload["tuned"]["active"] == result.best.active
    assert [c["label"] for c in payload["coordinates"]] == ["poles[0]", "poles[1]", "poles[2]"]
    assert all(c["low"] <= c["tuned"] <= c["high"] for c in payload["coordinates"])
    # a smooth loop: the gradient search, its sensitivity runs counted among the simulations
    assert payload["method"].startswith("gradient: SLSQP") and payload["method_choice"].startswith("gradient")
    s = result.search
    assert payload["sensitivity_runs"] == s.sensitivity_runs >= 1
    assert payload["simulations"] == sum(e.runs for e in s.evaluations) + s.sensitivity_runs
    assert set(result.files) == {"spec", "html", "pdf"} and result.files["pdf"].read_bytes().startswith(b"%PDF")


@pytest.mark.parametrize(("kwargs", "where"), [({"budget": 0}, "budget"), ({"budget": float("nan")}, "budget"),
                                               ({"budget": True}, "budget"), ({"seed": -1}, "seed"),
                                               ({"method": "newton"}, "method")])
def test_bad_arguments_name_the_argument(tmp_path, kwargs, where):
    with pytest.raises(dk.SpecError) as info:
        dk.tune(write(tmp_path, LINK), out=tmp_path / "out", **kwargs)
    assert info.value.path == where
    assert not (tmp_path / "out").exists()


def test_a_spec_that_is_not_a_path_is_refused():
    with pytest.raises(dk.SpecError) as info:
        dk.tune(42)
    assert info.value.path == "spec"
