"""The engine: the same samples and margins for 1 and 2 workers, for any chunk size, in this process or on
Dask, and after an interrupted sweep resumes from its chunk files."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.sweep import chunk as chunk_module
from designkit.sweep.api import sweep
from tests.sweep.specs import link, write

FIELDS = ("index", "values", "noise_seed", "achieved", "margin", "passed", "failed_runs")
TEXT = link(km=(0.1, 1.0), tau=(0.5, 4.0), duration=20.0)


def _same(a, b):
    for f in FIELDS:
        x, y = getattr(a, f), getattr(b, f)
        assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), f


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    spec = write(tmp_path_factory.mktemp("ref"), TEXT)
    return spec, sweep(spec, 90, seed=3, engine="process", chunk=90, falsification=False)


@pytest.mark.parametrize("chunk", [1, 7, 40])
def test_the_chunk_size_does_not_change_the_result(reference, chunk):
    spec, ref = reference
    _same(ref, sweep(spec, 90, seed=3, engine="process", chunk=chunk, falsification=False))


def test_one_and_two_local_workers_give_the_same_result(reference):
    spec, ref = reference
    one = sweep(spec, 90, seed=3, workers=1, chunk=10, falsification=False)
    two = sweep(spec, 90, seed=3, workers=2, chunk=10, falsification=False)
    _same(ref, one)
    _same(ref, two)
    assert one.engine["engine"] == "dask.distributed" and one.engine["chunks"] == 9


def test_an_interrupted_sweep_resumes_from_its_chunks(reference, tmp_path, monkeypatch):
    spec, ref = reference
    real = chunk_module.run_chunk
    calls = []

    def interrupted(job, k):
        if len(calls) == 4:
            raise KeyboardInterrupt
        calls.append(k)
        return real(job, k)

    monkeypatch.setattr("designkit.sweep.engine.run_chunk", interrupted)
    with pytest.raises(KeyboardInterrupt):
        sweep(spec, 90, seed=3, engine="process", chunk=10, out=tmp_path, falsification=False)
    written = sorted(p.name for p in (tmp_path / "chunks").glob("chunk-*.npz"))
    assert written == [f"chunk-{k:06d}.npz" for k in range(4)]
    monkeypatch.setattr("designkit.sweep.engine.run_chunk", real)
    computed = []
    monkeypatch.setattr(chunk_module, "prepared", _counting(chunk_module.prepared, computed))
    resumed = sweep(spec, 90, seed=3, engine="process", chunk=10, out=tmp_path, falsification=False, report=False)
    assert resumed.engine["resumed_chunks"] == 4
    _same(ref, resumed)


def test_a_chunk_file_of_another_sweep_is_not_reused(reference, tmp_path):
    spec, ref = reference
    sweep(spec, 20, seed=4, engine="process", chunk=10, out=tmp_path, falsification=False, report=False)
    again = sweep(spec, 20, seed=3, engine="process", chunk=10, out=tmp_path, falsification=False, report=False)
    assert again.engine["resumed_chunks"] == 0
    assert np.array_equal(again.values, ref.values[:20])


def _counting(func, log):
    def wrapped(*args):
        log.append(args)
        return func(*args)

    return wrapped


@pytest.mark.slow
def test_ctrl_c_stops_the_cli_and_the_same_command_resumes(tmp_path):
    """A real SIGINT to ``designkit sweep`` (a LocalCluster of two workers): exit 130 with the chunks written so
    far; the same command then reads them back and runs only the rest, giving the uninterrupted result."""
    import json
    import signal
    import subprocess
    import sys
    import time

    spec = write(tmp_path, link(km=(0.1, 1.0), tau=(0.5, 4.0), duration=20.0))
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "designkit.cli", "sweep", str(spec), "--samples", "300", "--chunk", "10",
           "--workers", "2", "--seed", "3", "--out", str(out), "--json"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    chunks = out / "link-sweep" / "chunks"
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline and len(list(chunks.glob("chunk-*.npz"))) < 3:
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130 and "run the same command again to resume" in err
    written = len(list(chunks.glob("chunk-*.npz")))
    assert 3 <= written < 30
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    payload = json.loads(again.stdout)
    assert payload["engine"]["resumed_chunks"] == written
    ref = sweep(spec, 300, seed=3, engine="process", chunk=300, falsification=False)
    assert payload["passed"] == ref.n_passed and payload["samples"] == 300
    table = (out / "link-sweep" / "samples.csv").read_text().splitlines()
    assert len(table) == 301
