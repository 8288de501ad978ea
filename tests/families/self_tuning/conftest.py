"""Shared runs of the self-tuning tests (one pipeline run per example spec for the whole directory)."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.pipeline import run
from designkit.schema.loader import load_spec

SPECS = Path(__file__).resolve().parents[3] / "specs"


@pytest.fixture(scope="session")
def speed_result():
    """``specs/selftune-speed.yaml``: speed measured, the link changing at t = 12 s, lambda = 0.99."""
    return run(load_spec(SPECS / "selftune-speed.yaml"))


@pytest.fixture(scope="session")
def position_result():
    """``specs/selftune-position.yaml``: the same without a speed measurement."""
    return run(load_spec(SPECS / "selftune-position.yaml"))


@pytest.fixture(scope="session")
def failing_result():
    """``specs/selftune-no-forgetting.yaml``: lambda = 1 through the change."""
    return run(load_spec(SPECS / "selftune-no-forgetting.yaml"))
