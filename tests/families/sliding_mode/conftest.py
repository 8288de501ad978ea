"""Shared runs of the sliding-mode family's tests (each pipeline run once per session)."""

from __future__ import annotations

import pytest

from tests.families.sliding_mode.common import LINK_SPEC, WEAK_SPEC


@pytest.fixture(scope="session")
def link_result():
    from designkit.pipeline import run
    from designkit.schema.loader import load_spec

    return run(load_spec(LINK_SPEC))


@pytest.fixture(scope="session")
def weak_result():
    from designkit.pipeline import run
    from designkit.schema.loader import load_spec

    return run(load_spec(WEAK_SPEC))
