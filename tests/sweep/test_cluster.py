"""A real multi-process Dask cluster on localhost: ``dask scheduler`` and two ``dask worker`` processes, one of
them killed mid-sweep; the result equals the in-process sweep of the same samples."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from designkit.sweep.api import sweep
from tests.sweep.specs import link, write

pytestmark = pytest.mark.slow

DASK = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
WORKER = [sys.executable, "-m", "distributed.cli.dask_worker"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_workers(address: str, n: int, timeout: float = 60.0) -> None:
    from dask.distributed import Client

    with Client(address, timeout="10s", set_as_default=False) as c:
        c.wait_for_workers(n, timeout=timeout)


@pytest.fixture
def cluster(tmp_path):
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    log = open(tmp_path / "cluster.log", "w")  # noqa: SIM115 - closed below
    procs = [subprocess.Popen([*DASK, "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], stdout=log,
                              stderr=subprocess.STDOUT, env=env, start_new_session=True)]
    try:
        time.sleep(1.0)
        for _ in range(2):
            procs.append(subprocess.Popen([*WORKER, address, "--nworkers", "1", "--nthreads", "1", "--no-dashboard",
                                           "--no-nanny"], stdout=log, stderr=subprocess.STDOUT, env=env,
                                          start_new_session=True))
        _wait_for_workers(address, 2)
        yield address, procs
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
            p.wait(timeout=10)
        log.close()


def test_a_cluster_with_a_worker_killed_mid_sweep_gives_the_in_process_result(cluster, tmp_path):
    address, procs = cluster
    spec = write(tmp_path, link(km=(0.1, 1.0), tau=(0.5, 4.0), duration=30.0))
    out = tmp_path / "out"
    import threading

    box: dict = {}

    def run():
        box["result"] = sweep(spec, 400, seed=5, scheduler=address, chunk=10, out=out, falsification=False,
                              report=False)

    thread = threading.Thread(target=run)
    thread.start()
    chunks = out / "chunks"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(list(chunks.glob("chunk-*.npz"))) < 6:
        time.sleep(0.05)
    written_at_kill = len(list(chunks.glob("chunk-*.npz")))
    os.killpg(procs[1].pid, signal.SIGKILL)  # one worker lost mid-sweep
    thread.join(timeout=120)
    assert not thread.is_alive()
    assert 6 <= written_at_kill < 40, written_at_kill
    got = box["result"]
    ref = sweep(spec, 400, seed=5, engine="process", chunk=400, falsification=False)
    for f in ("index", "values", "achieved", "margin", "passed", "failed_runs"):
        assert np.array_equal(getattr(got, f), getattr(ref, f), equal_nan=True), f
    assert len(list(Path(chunks).glob("chunk-*.npz"))) == 40
