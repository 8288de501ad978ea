"""A servo reference that does not move (``simulation.step: 0``, a square wave or PRBS of amplitude 0) is refused
alike by the switching servos whose band and step are sized on the reference's displacement: exit 2 naming the
key path, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from designkit.spec.sections import Simulation
from tests.cli_input import assert_bad_input

SPECS = Path(__file__).resolve().parents[2] / "specs"
FAMILIES = ("vsc-link", "pid-sm-link", "sliding-mode-link")
STILL = {
    "step 0": ("  step: 0\n", "simulation.step: the reference does not move"),
    "square 0": ("  trajectory: {kind: square, amplitude: 0, period: 1}\n",
                 "simulation.trajectory.amplitude: the reference does not move"),
    "prbs 0": ("  trajectory: {kind: prbs, amplitude: 0, bit: 0.1, order: 5}\n",
               "simulation.trajectory.amplitude: the reference does not move"),
}


def _with(name: str, line: str) -> str:
    text = (SPECS / f"{name}.yaml").read_text()
    assert "\nsimulation:\n" in text
    return text.replace("\nsimulation:\n", "\nsimulation:\n" + line, 1)


@pytest.mark.parametrize("name", FAMILIES)
@pytest.mark.parametrize("case", sorted(STILL))
def test_still_reference_is_refused_with_its_key_path(name, case, tmp_path, capsys):
    line, message = STILL[case]
    assert_bad_input(tmp_path, capsys, _with(name, line), message)


@pytest.mark.parametrize("line, key", [
    ("  step: 0\n", "simulation.step"),
    ("  step: [0, 0]\n", "simulation.step"),
    ("  step: [0, 0.1]\n", None),
    ("  trajectory: {kind: square, amplitude: [0, 0], period: 1}\n", "simulation.trajectory.amplitude"),
    ("  trajectory: {kind: square, amplitude: 0.5, period: 1}\n", None),
    ("  trajectory: {kind: sine, amplitude: 0, frequency: 1}\n", "simulation.trajectory.amplitude"),
    ("  trajectory: {kind: line, displacement: [0.1, 0.0, 0.0], duration: 1}\n", None),
])
def test_still_reference_names_the_key(line, key):
    """``Simulation.still_reference``: the key of a reference that is 0 on every joint, None otherwise (and for
    a path, which has no amplitude)."""
    section = Simulation.model_validate(yaml.safe_load("simulation:\n" + line)["simulation"])
    assert section.still_reference() == key
