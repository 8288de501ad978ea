"""Every example spec simulates (the docstring examples run with ``--doctest-modules``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from designkit.families import synthesize
from designkit.simulation.run import simulate
from designkit.spec.loader import load_spec

SPECS = sorted((Path(__file__).resolve().parents[2] / "specs").glob("*.yaml"))


@pytest.mark.parametrize("path", SPECS, ids=lambda p: p.stem)
def test_example_spec_simulates(path):
    spec = load_spec(path).spec
    res = simulate(spec, synthesize(spec))
    assert np.all(np.isfinite(res.state)) and res.time.size > 100
    json.dumps(res.settings)
    if spec.simulation.duration is not None:
        assert res.time[-1] == pytest.approx(spec.simulation.duration)
