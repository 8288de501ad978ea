"""The step-bound refusal names the field that drives it: the controller value that sets the control law's largest
step (a boundary layer, a band, a relay amplitude, a filter bandwidth) with the value the run needs, and
``simulation.duration`` only when the duration is the driver."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from designkit.cli import main
from designkit.errors import SpecError
from designkit.pipeline import design, plant
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from designkit.simulation.timing import MAX_STEPS

ROOT = Path(__file__).resolve().parents[2]


def _text(spec: str, changes: dict[str, object]) -> str:
    doc = yaml.safe_load((ROOT / "specs" / f"{spec}.yaml").read_text())
    for key, value in changes.items():
        *parents, last = key.split(".")
        node = doc
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = value
    return yaml.safe_dump(doc, sort_keys=False)


def _build(spec: str, changes: dict[str, object]):
    loaded = parse_spec(_text(spec, changes))
    true_plant = plant(loaded)
    return build(loaded.spec, design(loaded, true_plant), plant=true_plant)


CASES = [
    ("sliding-mode-link", "boundary_layer", 1e-12, {}),
    ("sliding-mode-link", "chattering_band", 1e-12, {}),
    ("sliding-mode-link", "M", 1e6, {}),
    ("pid-sm-link", "epsilon", 1e-12, {}),
    ("pid-sm-link", "switching_band", 1e-12, {}),
    ("hierarchy-simnog", "epsilon", 1e-12, {}),
    ("vsc-link", "boundary_layer", 1e-12, {}),
    ("vsc-link", "chattering_band", 1e-12, {}),
    ("vsc-link", "relay_amplitude", 1e6, {}),
    ("adaptive-ct-simnog", "bandwidth", 1e6, {"controller.acceleration": "filtered"}),
]


@pytest.mark.parametrize(("spec", "field", "value", "extra"), [
    pytest.param(*c, id=f"{c[0]}-{c[1]}", marks=[pytest.mark.slow] if c[0] == "hierarchy-simnog" else [])
    for c in CASES])
def test_the_controller_value_that_sets_the_step_is_named_with_the_value_that_fits(spec, field, value, extra):
    with pytest.raises(SpecError) as exc:
        _build(spec, {f"controller.{field}": value, **extra})
    err = exc.value
    assert err.path == f"controller.{field}"
    assert "shorten simulation.duration" not in err.message
    m = re.search(rf"needs controller\.{field} (at least|at most) ([0-9.e+-]+)$", err.message)
    assert m, err.message
    bound, fit = m.group(1), float(m.group(2))
    # the bound is necessary: a value 10 % on the wrong side of it is still refused, at the same key
    short = fit * (0.9 if bound == "at least" else 1.1)
    with pytest.raises(SpecError) as again:
        _build(spec, {f"controller.{field}": short, **extra})
    assert again.value.path == f"controller.{field}"
    # and the field is the driver: ten times beyond the bound, the run fits the step bound
    sim = _build(spec, {f"controller.{field}": fit * (10 if bound == "at least" else 0.1), **extra})
    assert sim.settings["n_steps"] <= MAX_STEPS


def test_the_duration_is_named_when_it_drives_the_step_count():
    with pytest.raises(SpecError) as exc:
        _build("posspeed-link", {"simulation.duration": 5000.0})
    assert exc.value.path == "simulation.duration"
    assert "shorten simulation.duration" in exc.value.message


def test_a_law_step_from_the_design_s_defaults_names_the_controller_and_its_step_fields():
    with pytest.raises(SpecError) as exc:
        _build("sliding-mode-link", {"simulation.duration": 3000.0})
    assert exc.value.path == "controller"
    assert "controller.boundary_layer, controller.chattering_band, controller.M" in exc.value.message


def test_verify_prints_the_controller_key(tmp_path, capsys):
    path = tmp_path / "spec.yaml"
    path.write_text(_text("sliding-mode-link", {"controller.boundary_layer": 1e-12}))
    assert main(["verify", str(path), "--jobs", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("designkit: error: controller.boundary_layer: 1e-12 sets the integration step")
    assert err.count("\n") == 1
