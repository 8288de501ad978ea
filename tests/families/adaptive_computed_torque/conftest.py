"""Shared runs of the adaptive computed-torque tests (one pipeline run per example spec for the whole directory)."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.pipeline import run
from designkit.schema.loader import load_spec

SPECS = Path(__file__).resolve().parents[3] / "specs"


@pytest.fixture(scope="session")
def simnog_result():
    """``specs/adaptive-ct-simnog.yaml``: m1, m2 adapted on an exciting sine (converging)."""
    return run(load_spec(SPECS / "adaptive-ct-simnog.yaml"))


@pytest.fixture(scope="session")
def poor_result():
    """``specs/adaptive-ct-simnog-poor.yaml``: one move to the upright pose, then rest (poor excitation)."""
    return run(load_spec(SPECS / "adaptive-ct-simnog-poor.yaml"))


@pytest.fixture(scope="session")
def not_spr_result():
    """``specs/adaptive-ct-not-spr.yaml``: psi K2 = 0.4 (not SPR)."""
    return run(load_spec(SPECS / "adaptive-ct-not-spr.yaml"))
