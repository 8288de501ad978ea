"""Every example spec simulates (the docstring examples run with ``--doctest-modules``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from designkit.families import synthesize
from designkit.schema.loader import load_spec
from designkit.simulation.run import simulate
from tests.marks import slow_cases

SPECS = sorted(p for p in (Path(__file__).resolve().parents[2] / "specs").glob("*.yaml")
               if "\ncontrollers:" not in p.read_text())  # a comparison is its controllers' runs (tests/comparison)


SLOW = {"hierarchy-puma560", "hierarchy-puma560-payload"}
"""The PUMA 560 hierarchies (18-24 s each); the SIMNOG hierarchy runs in the default run."""


@pytest.mark.parametrize("path", slow_cases(SPECS, SLOW, lambda p: p.stem))
def test_example_spec_simulates(path):
    spec = load_spec(path).spec
    res = simulate(spec, synthesize(spec))
    if not np.all(np.isfinite(res.state)):  # only an example meant to fail may diverge (and its checks say so)
        from tests.test_cli import EXPECTED_EXIT

        assert EXPECTED_EXIT[path.stem] == 1
    discrete = getattr(spec.plant, "dt", None) is not None  # a discrete plant's trial: its own samples (Moore: 51)
    assert res.time.size > (50 if discrete else 100)
    json.dumps(res.settings)
    if spec.simulation.duration is not None:
        assert res.time[-1] == pytest.approx(spec.simulation.duration)
