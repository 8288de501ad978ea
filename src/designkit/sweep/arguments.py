"""The arguments of :func:`designkit.sweep.api.sweep`, checked before anything runs or is written.

The error paths are the command line's option names (``--samples``, ``--chunk``, ...) where ``designkit sweep``
has the option, else the argument's name (``engine``, ``client``, ``progress``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from designkit import arguments
from designkit.errors import OutputError, SpecError

MAX_WORKERS = 1024
"""Most workers of the LocalCluster a sweep starts."""
MAX_CHUNK = 1_000_000
"""Most samples per chunk."""


@dataclass(frozen=True)
class Arguments:
    """The checked arguments (their documentation: :func:`designkit.sweep.api.sweep`)."""

    samples: int
    seed: int
    workers: int | None
    out: Path | None
    chunk: int | None
    engine: str
    progress: bool
    falsification: bool
    report: bool


def check(samples: Any, seed: Any, client: Any, scheduler: Any, workers: Any, out: Any, chunk: Any, engine: Any,
          progress: Any, falsification: Any, report: Any, *, max_samples: int) -> Arguments:
    """The arguments of a sweep, checked; :class:`~designkit.errors.SpecError` (or
    :class:`~designkit.errors.OutputError` for ``out``) naming the first one that is wrong."""
    samples = arguments.integer(samples, "--samples", low=1, high=max_samples)
    seed = arguments.integer(seed, "--seed", low=0, high=2**32 - 1)
    if chunk is not None:
        chunk = arguments.integer(chunk, "--chunk", low=1, high=MAX_CHUNK)
    if workers is not None:
        workers = arguments.integer(workers, "--workers", low=1, high=MAX_WORKERS)
    engine = arguments.choice(engine, "engine", ("dask", "process"))
    if scheduler is not None:
        scheduler = arguments.text(scheduler, "--scheduler", empty=False)
    if client is not None and not all(callable(getattr(client, m, None)) for m in ("submit", "scheduler_info")):
        raise SpecError("client", f"must be a dask.distributed.Client, got {type(client).__name__}")
    if out is not None:
        out = arguments.path(out, "--out", error=OutputError, what="a folder path")
    return Arguments(samples=samples, seed=seed, workers=workers, out=out, chunk=chunk, engine=engine,
                     progress=arguments.flag(progress, "progress"),
                     falsification=arguments.flag(falsification, "falsification"),
                     report=arguments.flag(report, "report"))
