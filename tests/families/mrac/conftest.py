"""Shared runs of the MRAC tests (one pipeline run per example spec for the whole directory)."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.pipeline import run
from designkit.schema.loader import load_spec

SPECS = Path(__file__).resolve().parents[3] / "specs"


@pytest.fixture(scope="session")
def link_result():
    """``specs/mrac-link.yaml`` through the pipeline: Km 2 -> 1 at t = 20 s under a square wave, gamma = 1e4."""
    return run(load_spec(SPECS / "mrac-link.yaml"))


@pytest.fixture(scope="session")
def unstable_result():
    """``specs/mrac-gamma-unstable.yaml``: the same with gamma = 6e4 (the gradient rule diverges)."""
    return run(load_spec(SPECS / "mrac-gamma-unstable.yaml"))
