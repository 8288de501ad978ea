"""``--scheduler``: the protocols a sweep connects over, and endpoints that are not Dask schedulers (garbage bytes,
a silent listener, nothing listening), each refused in one line naming ``--scheduler`` within the deadline."""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from designkit.errors import SpecError
from designkit.sweep.scheduler import CONNECT_TIMEOUT, endpoint, probe
from tests.sweep.specs import SIMNOG, write

ROOT = Path(__file__).resolve().parents[2]
SSH_BANNER = b"SSH-2.0-OpenSSH_9.2p1 Debian-2\r\n"
"""What an SSH server sends first: read as Dask's 8-byte frame length, 2.8e18 bytes."""


@contextlib.contextmanager
def _listener(answer: bytes | None) -> Iterator[str]:
    """A TCP listener on localhost that accepts every connection and writes ``answer`` (None: stays silent, the
    connection held open); yields its ``tcp://`` address."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    server.settimeout(0.2)
    held: list[socket.socket] = []
    stop = threading.Event()

    def serve() -> None:
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except (TimeoutError, OSError):
                continue
            held.append(conn)
            if answer is not None:
                with contextlib.suppress(OSError):
                    conn.sendall(answer)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        stop.set()
        thread.join(5)
        for conn in held:
            conn.close()
        server.close()


def _cli(tmp_path: Path, scheduler: str) -> tuple[subprocess.CompletedProcess, float]:
    spec = write(tmp_path, SIMNOG)
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    for key in [k for k in env if k.startswith("DASK_DISTRIBUTED__COMM__TLS")]:
        del env[key]
    start = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "designkit.cli", "sweep", str(spec), "--samples", "10", "--out",
                           str(tmp_path / "out"), "--scheduler", scheduler], capture_output=True, text=True, env=env,
                          timeout=30)
    return done, time.monotonic() - start


def _one_line_refusal(done: subprocess.CompletedProcess, tmp_path: Path, reason: str) -> None:
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    assert done.stderr.startswith("designkit: error: --scheduler: ") and done.stderr.count("\n") == 1, done.stderr
    assert reason in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


def test_an_endpoint_answering_other_bytes_is_refused_at_once(tmp_path):
    with _listener(SSH_BANNER) as address:
        done, elapsed = _cli(tmp_path, address)
    _one_line_refusal(done, tmp_path, "not with Dask's handshake")
    assert "MemoryError" in done.stderr and "internal error" not in done.stderr
    assert elapsed < 10


def test_a_silent_listener_is_refused_within_the_deadline(tmp_path):
    with _listener(None) as address:
        done, elapsed = _cli(tmp_path, address)
    _one_line_refusal(done, tmp_path, f"did not answer as a Dask scheduler within {CONNECT_TIMEOUT:g} s")
    assert elapsed < 12  # the 5-s deadline plus the process's start (imports), not Dask's unbounded read


@pytest.mark.parametrize("answer", [None, SSH_BANNER, b"\x08" + b"\x00" * 7 + b"\xff" * 8, b"HTTP/1.1 400 Bad\r\n\r\n"])
def test_the_probe_keeps_its_deadline_whatever_the_bytes(answer):
    with _listener(answer) as address:
        start = time.monotonic()
        with pytest.raises(SpecError) as exc:
            probe(endpoint(address), timeout=2.0)
        elapsed = time.monotonic() - start
    assert exc.value.path == "--scheduler"
    assert elapsed < 2.0 + 1.5


def test_nothing_listening_is_refused_naming_the_scheduler(tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    done, elapsed = _cli(tmp_path, f"tcp://127.0.0.1:{port}")
    _one_line_refusal(done, tmp_path, "nothing answered at this address")
    assert elapsed < 12


@pytest.mark.parametrize(("address", "reason"), [
    ("ucx://127.0.0.1:8786", "the ucx:// protocol is not supported"),
    ("inproc://scheduler", "the inproc:// protocol is not supported"),
    ("ws://127.0.0.1:8786", "the ws:// protocol is not supported"),
    ("tls://127.0.0.1:8786", "tls:// needs the Dask TLS configuration"),
    ("tcp://127.0.0.1:0", "a port from 1 to 65535"),
    ("tcp://127.0.0.1", "missing port"),
    ("not an address", "not a scheduler address"),
])
def test_addresses_a_sweep_cannot_use_are_refused_in_one_line(tmp_path, address, reason):
    done, elapsed = _cli(tmp_path, address)
    _one_line_refusal(done, tmp_path, reason)
    assert elapsed < 10


def test_tls_with_the_dask_tls_configuration_connects(tmp_path):
    """A TLS scheduler (self-signed certificates) is reached with the certificates in the Dask configuration, and
    refused without them."""
    pytest.importorskip("cryptography")
    import dask
    from distributed import LocalCluster, Security

    from designkit.sweep.engine import connect

    sec = Security.temporary()
    with LocalCluster(n_workers=0, processes=False, protocol="tls://", security=sec, dashboard_address=None) as lc:
        address = lc.scheduler_address
        assert address.startswith("tls://")
        with pytest.raises(SpecError, match="tls:// needs the Dask TLS configuration"):
            connect(address)
        config = {"distributed.comm.tls.ca-file": sec.tls_ca_file, "distributed.comm.tls.client.cert":
                  sec.tls_client_cert, "distributed.comm.tls.client.key": sec.tls_client_key}
        with dask.config.set(config):
            info = probe(endpoint(address))
            client, cluster = connect(address)
            try:
                assert cluster is None
                assert client.scheduler_info()["address"] == address
            finally:
                client.close()
        assert "python" in info
