"""The engine of a sweep: Dask distributed, a LocalCluster by default or any cluster by address.

Every chunk is one task (:func:`designkit.sweep.chunk.run_chunk`) with a key of its own, submitted with
retries, so a worker lost mid-sweep has its chunks run again elsewhere; a chunk's samples come from their
own seeded streams and its file is written atomically, so the result does not depend on which worker ran
which chunk, on how many workers there are, or on whether a chunk ran twice.  With an output folder the
chunks already written are read back instead of submitted (a resumed sweep).

``dask.distributed`` is imported here only, inside the functions.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from typing import Any

from designkit.errors import SpecError
from designkit.sweep.chunk import ChunkResult, Job, read_chunk, run_chunk
from designkit.sweep.scheduler import CONNECT_TIMEOUT, endpoint, probe

__all__ = ["CONNECT_TIMEOUT", "RETRIES", "connect", "execute", "in_process"]

RETRIES = 3
"""Times a chunk is re-run after its worker was lost or it raised."""


def connect(scheduler: str | None = None, workers: int | None = None, *, probed: bool = False) -> tuple[Any, Any]:
    """``(client, cluster)``: a client of the scheduler at ``scheduler``, or of a new LocalCluster of ``workers``
    single-threaded processes (default one per core); ``cluster`` is None for an address (not ours to close).
    ``probed``: the scheduler has just answered :func:`~designkit.sweep.scheduler.probe` (not asked again).

    Raises
    ------
    SpecError
        ``--scheduler``: not an address of a supported protocol, or no Dask scheduler answering there within
        :data:`~designkit.sweep.scheduler.CONNECT_TIMEOUT` s (:mod:`designkit.sweep.scheduler`); ``--workers`` not
        positive.
    """
    from dask.distributed import Client, LocalCluster

    if scheduler is not None:
        ep = endpoint(scheduler)
        if not probed:
            probe(ep, CONNECT_TIMEOUT)  # the handshake within the deadline: Dask's own has none
        try:
            return Client(ep.address, security=ep.security, timeout=f"{CONNECT_TIMEOUT}s", set_as_default=False), None
        except Exception as exc:  # noqa: BLE001 - it answered the handshake, then failed: still this address
            raise SpecError("--scheduler", f"{scheduler}: the Dask scheduler answered but the client could not "
                            f"register within {CONNECT_TIMEOUT:g} s ({type(exc).__name__})") from None
    n = workers if workers is not None else (os.cpu_count() or 1)
    if n < 1:
        raise SpecError("--workers", f"must be at least 1, got {n}")
    import dask

    # the workers' statistical profiler samples every thread's stack every 10 ms: 15 % more CPU a sample in the
    # SIMNOG sweep, for a profile nobody reads here (a cluster given by address keeps its own settings)
    with dask.config.set({"distributed.worker.profile.enabled": False}):
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=50)
    return Client(cluster, set_as_default=False), cluster


def _progress(total: int, enabled: bool) -> Callable[[int], None]:
    """A progress line on stderr (samples done, rate, time left), or nothing."""
    if not enabled:
        return lambda done: None
    start = time.monotonic()

    def show(done: int) -> None:
        elapsed = time.monotonic() - start
        rate = done / elapsed if elapsed > 0 else 0.0
        left = (total - done) / rate if rate > 0 else float("nan")
        bar = "#" * int(30 * done / total) if total else ""
        sys.stderr.write(f"\rsweep [{bar:<30}] {done:,}/{total:,} samples, {rate:,.0f}/s, "
                         f"{left:,.0f} s left   " if left == left else f"\rsweep {done:,}/{total:,}   ")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def in_process(job: Job, *, progress: bool = False) -> list[ChunkResult]:
    """Every chunk of ``job`` in this process, one after the other (no Dask: the reference of the engine's
    overhead, and the falsification's evaluator)."""
    show = _progress(job.samples, progress)
    out, done = [], 0
    for k in range(job.n_chunks):
        out.append(run_chunk(job, k))
        done += out[-1].index.size
        show(done)
    return out


def execute(job: Job, *, client: Any = None, scheduler: str | None = None, workers: int | None = None,
            progress: bool = False) -> list[ChunkResult]:
    """Run every chunk of ``job`` on Dask (module docstring) and return them in chunk order.

    Parameters
    ----------
    job : Job
    client : dask.distributed.Client, optional
        A client to use as it is (not closed).
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``).
    workers : int, optional
        Workers of the LocalCluster started when neither ``client`` nor ``scheduler`` is given.
    progress : bool
        Draw a progress bar on stderr.
    """
    results: dict[int, ChunkResult] = {}
    for k in range(job.n_chunks):
        done = read_chunk(job, k)
        if done is not None:
            results[k] = done
    todo = [k for k in range(job.n_chunks) if k not in results]
    show = _progress(job.samples, progress)
    count = sum(r.index.size for r in results.values())
    show(count)
    if not todo:
        return [results[k] for k in range(job.n_chunks)]
    own = client is None
    cluster = None
    if own:
        client, cluster = connect(scheduler, workers)
    from dask.distributed import as_completed

    futures = []
    current = client.as_current()
    current.__enter__()
    try:
        futures = [client.submit(run_chunk, job, k, key=f"designkit-sweep-{job.key[:16]}-{job.samples}-{k}",
                                 pure=False, retries=RETRIES) for k in todo]
        for fut in as_completed(futures):
            res = fut.result()
            results[res.chunk] = res
            count += res.index.size
            show(count)
    finally:
        for f in futures:
            if not f.done():
                f.cancel()
        current.__exit__(None, None, None)
        if own:
            client.close()
            if cluster is not None:
                cluster.close()
    return [results[k] for k in range(job.n_chunks)]
