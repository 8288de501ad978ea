"""Shared runs of the vsc family's tests (each pipeline run once per session)."""

from __future__ import annotations

import pytest

from tests.families.vsc.common import ELASTIC_SPEC, LINK_SPEC, NARROW_SPEC


def _run(path):
    from designkit.pipeline import run
    from designkit.schema.loader import load_spec

    return run(load_spec(path))


@pytest.fixture(scope="session")
def elastic_result():
    return _run(ELASTIC_SPEC)


@pytest.fixture(scope="session")
def link_result():
    return _run(LINK_SPEC)


@pytest.fixture(scope="session")
def narrow_result():
    return _run(NARROW_SPEC)
