"""The confirming sweep of the tuned spec: its pass fraction is the sweep's own per-sample verdicts counted again,
its worst sample re-runs through the runner with the same margins, a spec the sweep kernel refuses is stated, not
raised, and ``--scheduler`` runs it on a Dask scheduler (a bad address refused in one line, nothing written)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import designkit as dk
from designkit.cli import main
from designkit.schema.loader import load_spec
from designkit.tuning.confirm import confirm
from tests.tuning.specs import LINK, write

WIDE = LINK.replace("name: link-tune", "name: link-tune-wide").replace(
    "tau: 0.5}", "tau: 0.5, uncertainty: {Km: [0.8, 3.0], tau: [0.3, 0.8]}}").replace(
    "overshoot: 5, settling_time: 1.5", "overshoot: 2, settling_time: 0.8")
"""The link PID over a wide Km, tau box, with requirements its own poles meet at some plants of it and not others."""

BOX = LINK.replace("tau: 0.5}", "tau: 0.5, uncertainty: {Km: [1.6, 2.4]}}")
"""The link PID over a +-20 % Km box."""


def _own_count(sw) -> int:
    """Samples whose every requirement margin the sweep recorded is defined and not negative, and whose run did not
    fail."""
    ok = np.all(np.isfinite(sw.margin) & (sw.margin >= 0.0), axis=1) & ~np.asarray(sw.failed_runs, dtype=bool)
    return int(np.count_nonzero(ok))


def test_the_pass_fraction_is_the_sweeps_per_sample_results_counted(tmp_path):
    loaded = load_spec(write(tmp_path, WIDE))
    found = confirm(loaded, samples=24, seed=2)
    sw = dk.sweep(loaded, 24, seed=2, engine="process", falsification=False, report=False)
    own = _own_count(sw)
    assert 0 < own < 24  # the box has plants on both sides of the requirements: the count is not trivial
    assert found.refused is None and found.samples == 24
    assert found.passed == own and found.pass_fraction == pytest.approx(own / 24)
    lo, hi = found.confidence
    assert lo < own / 24 < hi
    # the worst sample is the one whose worst margin over its limit is smallest, by our own reading of the table
    norm = np.min(sw.margin / np.array([sw.limits[k] for k in sw.requirements]), axis=1)
    assert found.worst["sample"] == int(sw.index[int(np.argmin(norm))])
    # and it re-runs through the runner (the nominal design, the sampled plant) with the same margins
    from designkit.runner.run import run_spec
    from designkit.spec.plant_builder import plant_from_spec

    plant = plant_from_spec(loaded.spec.plant, tmp_path)
    run = run_spec(loaded, actual=plant.with_params(**found.worst["parameters"]), box=False)
    checks = {c.name: c for c in run.checks}
    for req, margin in found.worst["margins"].items():
        assert checks[req].margin == pytest.approx(margin, rel=1e-3, abs=1e-3 * sw.limits[req]), req


def test_tune_states_the_sweep_of_its_tuned_spec(tmp_path):
    result = dk.tune(write(tmp_path, BOX), budget=1.0, write=False, sweep_samples=16, seed=1)
    c = result.confirmation
    assert c is not None and c.samples == 16 and c.seed == 1
    sw = dk.sweep(result.tuned, 16, seed=1, engine="process", falsification=False, report=False)
    assert c.passed == _own_count(sw)
    assert result.to_json()["sweep"]["pass_fraction"] == pytest.approx(_own_count(sw) / 16)
    # no uncertainty, no sweep; zero samples, none
    assert dk.tune(write(tmp_path, LINK, "plain.yaml"), budget=0.5, write=False).confirmation is None
    assert dk.tune(write(tmp_path, BOX, "none.yaml"), budget=0.5, write=False, sweep_samples=0).confirmation is None


def test_a_spec_the_sweep_refuses_is_stated_not_raised(tmp_path):
    text = BOX + "implementation:\n  sampling_period: 1.0e-3\n"
    loaded = load_spec(write(tmp_path, text))
    found = confirm(loaded, samples=8)
    assert found.refused is not None and found.refused.startswith("implementation")
    assert found.pass_fraction is None and "refuses" in found.sentence
    result = dk.tune(loaded, budget=0.5, write=False, sweep_samples=8)
    assert result.to_json()["sweep"]["refused"] == found.refused


@pytest.mark.parametrize(("address", "reason"), [
    ("inproc://x", "the inproc:// protocol is not supported"),
    ("not an address", "not a scheduler address"),
])
def test_a_bad_scheduler_exits_2_in_one_line_and_writes_nothing(tmp_path, capsys, address, reason):
    spec = write(tmp_path, BOX)
    out = tmp_path / "out"
    assert main(["tune", str(spec), "--out", str(out), "--budget", "0.5", "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert err.startswith("designkit: error: --scheduler: ") and reason in err and err.count("\n") == 1, err
    assert not out.exists()


def test_the_confirming_sweep_runs_on_the_scheduler_given(tmp_path, capsys):
    from distributed import LocalCluster

    spec = write(tmp_path, BOX)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://",
                      dashboard_address=None) as lc:
        code = main(["tune", str(spec), "--out", str(tmp_path / "out"), "--budget", "1", "--sweep-samples", "12",
                     "--scheduler", lc.scheduler_address, "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code in (0, 1) and data["sweep"]["engine"] == f"dask.distributed at {lc.scheduler_address}, 1 worker"
    tuned = load_spec(tmp_path / "out" / "link-tune-tuned.yaml")
    sw = dk.sweep(tuned, 12, seed=0, engine="process", falsification=False, report=False)
    assert data["sweep"]["samples"] == 12 and data["sweep"]["passed"] == _own_count(sw)


@pytest.mark.parametrize("value", ["-1", "10001", "many"])
def test_a_bad_sample_count_exits_2_in_one_line_and_writes_nothing(tmp_path, capsys, value):
    spec = write(tmp_path, BOX)
    out = tmp_path / "out"
    try:
        code = main(["tune", str(spec), "--out", str(out), "--sweep-samples", value])
    except SystemExit as exc:
        code = int(exc.code)
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("designkit: error: --sweep-samples: must be an integer from 0 to 10000")
    assert err.count("\n") == 1 and not out.exists()


def test_a_sweep_that_cannot_be_run_is_stated_not_raised(tmp_path, monkeypatch):
    import designkit.sweep.api as api

    def lost(*args, **kwargs):
        raise OSError("Timed out during handshake while connecting to tcp://127.0.0.1:1")

    monkeypatch.setattr(api, "sweep", lost)
    found = confirm(load_spec(write(tmp_path, BOX)), samples=8)
    assert found.refused == "not run: OSError: Timed out during handshake while connecting to tcp://127.0.0.1:1"
    assert found.sentence.startswith("no confirming sweep: it could not be run (OSError: Timed out")
    assert found.pass_fraction is None and found.samples == 0
