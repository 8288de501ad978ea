"""``dk.sweep``: the Python API returns a frozen result with the per-sample table as a pandas DataFrame."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

import designkit as dk
from tests.sweep.specs import link, write


def test_dk_sweep_returns_a_frozen_result_with_a_dataframe(tmp_path):
    res = dk.sweep(write(tmp_path, link(duration=10.0)), samples=20, seed=2, engine="process",
                   falsification=False)
    table = res.table
    assert isinstance(table, pd.DataFrame) and len(table) == 20
    assert list(table.columns) == ["sample", "Km", "tau", "steady_state_error", "margin_steady_state_error",
                                   "passed", "integrator_failed"]
    assert np.array_equal(table["passed"].to_numpy(), res.passed)
    assert table["margin_steady_state_error"].to_numpy() == pytest.approx(0.5 - table["steady_state_error"])
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.seed = 3
    with pytest.raises(ValueError):
        res.margin[0, 0] = 1.0


def test_dk_sweep_is_callable_after_the_package_was_imported():
    import designkit.sweep.api  # noqa: F401 - imports the package first

    assert callable(dk.sweep)
    with pytest.raises(dk.SpecError, match="--samples"):
        dk.sweep("specs/simnog-decentralized-pid.yaml", samples=0)
