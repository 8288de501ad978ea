"""Shared runs of the sliding-mode identification tests (one pipeline run per example spec for the directory)."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.pipeline import run
from designkit.schema.loader import load_spec

SPECS = Path(__file__).resolve().parents[3] / "specs"


@pytest.fixture(scope="session")
def link_result():
    """``specs/smid-link.yaml``: Km = 2, tau = 0.5 s under a square wave of period 2 s."""
    return run(load_spec(SPECS / "smid-link.yaml"))


@pytest.fixture(scope="session")
def step_result():
    """``specs/smid-link-parameter-step.yaml``: Km 2 -> 1, tau 0.5 -> 1 s at t = 10 s."""
    return run(load_spec(SPECS / "smid-link-parameter-step.yaml"))


@pytest.fixture(scope="session")
def single_step_result():
    """``specs/smid-link-single-step.yaml``: one step and nothing after it (not exciting)."""
    return run(load_spec(SPECS / "smid-link-single-step.yaml"))


@pytest.fixture(scope="session")
def simnog_result():
    """``specs/smid-simnog.yaml``: the SIMNOG arm's ten base parameters, m2 3 -> 4 kg at t = 40 s."""
    return run(load_spec(SPECS / "smid-simnog.yaml"))


@pytest.fixture(scope="session")
def simnog_single_step_result():
    """``specs/smid-simnog-single-step.yaml``: one step, then the arm at rest (not exciting)."""
    return run(load_spec(SPECS / "smid-simnog-single-step.yaml"))
