"""``dk.sweep``: Monte Carlo of the nonlinear closed loop over what a spec leaves uncertain.

The controller is designed once, on the spec's nominal plant; each sample is a run of the true plant
(the sampled parameters and payload from the start of the run, the controller not told), from the
sampled initial position, with its own noise seed; every time-domain requirement is scored per sample.
The work is cut into chunks run on Dask (:mod:`designkit.sweep.engine`), or in this process
(``engine="process"``).
"""

from __future__ import annotations

import hashlib
import time
from pathlib import Path
from typing import Any

import numpy as np

from designkit.errors import OutputError, SpecError
from designkit.sweep.arguments import check
from designkit.sweep.chunk import Job, base, prepared
from designkit.sweep.result import SweepResult, Worst

__all__ = ["DEFAULT_CHUNK", "MAX_SAMPLES", "WORST", "sweep"]

MAX_SAMPLES = 10_000_000
"""Most samples in one sweep (the per-sample table of 10^7 samples is about a gigabyte)."""
DEFAULT_CHUNK = 1000
"""Largest default number of samples per chunk (one task, one file); see :func:`default_chunk`."""
WORST = 5
"""How many of the worst samples are written as specs."""
RECORD_BUDGET = 32e6
"""Bytes of kept records per batch: the batch size is chosen so a batch's trajectories fit in it."""


def _sweep_of(spec: Any) -> Any:
    from designkit.schema.loader import LoadedSpec
    from designkit.sweep.section import LoadedSweep, load_sweep, parse_sweep

    if isinstance(spec, LoadedSweep):
        return spec
    if isinstance(spec, LoadedSpec):
        return parse_sweep(spec.text, path=spec.path)
    if isinstance(spec, str | Path):
        return load_sweep(spec)
    raise SpecError("spec", f"expected a spec path, a LoadedSpec or a LoadedSweep, got {type(spec).__name__}")


def default_chunk(samples: int) -> int:
    """Samples per chunk when not given: ``ceil(N / 64)`` between 10 and :data:`DEFAULT_CHUNK` -- at least 64 tasks
    to spread over the workers (a function of ``N`` alone, so the same command resumes whatever the workers)."""
    return int(min(DEFAULT_CHUNK, max(10, -(-samples // 64)), samples))


def _batch_size(steps: int, n: int, nu: int, chunk: int) -> int:
    per_run = steps * (n + 2 * nu) * 8
    return int(max(1, min(64, chunk, RECORD_BUDGET // max(per_run, 1))))


def sweep(spec: Any, samples: int, *, seed: int = 0, client: Any = None, scheduler: str | None = None,
          workers: int | None = None, out: str | Path | None = None, chunk: int | None = None,
          engine: str = "dask", progress: bool = False, falsification: bool = True, report: bool = True,
          ) -> SweepResult:
    """Sample, simulate and score a spec's closed loop ``samples`` times (module docstring).

    Parameters
    ----------
    spec : path, LoadedSpec or LoadedSweep
        The spec, with an optional ``sweep:`` section (:mod:`designkit.sweep.section`).
    samples : int
        Number of samples, 1 to :data:`MAX_SAMPLES`.
    seed : int
        Seed of the samples (0 to 2^32 - 1): sample ``i`` draws from ``default_rng([seed, i])``.
    client : dask.distributed.Client, optional
        Run on this client (left open).
    scheduler : str, optional
        Address of a Dask scheduler to connect to: ``tcp://host:8786`` (or ``host:8786``), or ``tls://host:8786``
        with the Dask TLS configuration (:mod:`designkit.sweep.scheduler`).
    workers : int, optional
        Workers of the LocalCluster started otherwise (default one per core).
    out : path-like, optional
        Folder for the chunk files (``chunks/``, resumable), the per-sample table, the worst cases' specs and the
        report; None keeps everything in memory.
    chunk : int, optional
        Samples per chunk (default :func:`default_chunk`); the results do not depend on it.
    engine : {"dask", "process"}
        ``process`` runs the chunks in this process, one after the other.
    progress : bool
        Progress bar on stderr.
    falsification : bool
        Search the box from the worst samples (:mod:`designkit.sweep.falsify`).
    report : bool
        With ``out``, write the HTML and PDF sweep report.

    Raises
    ------
    SpecError
        ``--samples`` out of range, ``--seed``, ``--chunk``, ``--scheduler`` (not a tcp:// or tls:// address, or no
        Dask scheduler completing the handshake there within 5 s: :mod:`designkit.sweep.scheduler`), the spec's own
        key paths.
    """
    from designkit.sweep import engine as eng

    a = check(samples, seed, client, scheduler, workers, out, chunk, engine, progress, falsification, report,
              max_samples=MAX_SAMPLES)
    samples, seed, workers, out, chunk, engine, progress, falsification, report = (
        a.samples, a.seed, a.workers, a.out, a.chunk, a.engine, a.progress, a.falsification, a.report)
    probed = False
    if scheduler is not None and engine == "dask" and client is None:
        from designkit.sweep.scheduler import endpoint, probe

        probe(endpoint(scheduler))  # a scheduler answering Dask's handshake within 5 s, before the spec is designed
        probed = True
    sw = _sweep_of(spec)
    name = sw.loaded.spec.name
    chunk = int(chunk or default_chunk(samples))
    text = _full_text(sw)
    ready = base(text, sw.path)  # validates the spec (and its sweep section) before any cluster starts
    sim = ready.simulator
    batch = _batch_size(sim.time.size, len(ready.plant.positions), len(ready.plant.inputs), chunk)
    key = hashlib.sha256(f"{text}\0{seed}\0{chunk}".encode()).hexdigest()
    own = engine == "dask" and client is None
    cluster = None
    if own:  # connect before anything is written: an unreachable scheduler leaves no folder behind
        client, cluster = eng.connect(scheduler, workers, probed=probed)
    try:
        folder = None
        if out is not None:
            folder = Path(out)
            try:
                (folder / "chunks").mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise OutputError("--out", f"cannot create {folder}: {exc.strerror or exc}") from None
        job = Job(text=text, path=sw.path, seed=int(seed), samples=int(samples), chunk=chunk, batch=batch,
                  out=str(folder) if folder is not None else None, key=key)
        from designkit.sweep.chunk import read_chunk

        resumed = sum(read_chunk(job, k) is not None for k in range(job.n_chunks)) if folder is not None else 0
        start = time.monotonic()
        if engine == "process":
            chunks = eng.in_process(job, progress=progress)
            where: dict[str, Any] = {"engine": "this process"}
        else:
            chunks = eng.execute(job, client=client, progress=progress)
            n_workers = len(client.scheduler_info().get("workers", {}))
            where = {"engine": "dask.distributed", "scheduler": scheduler or ("given client" if not own
                                                                               else "LocalCluster"),
                     "workers": n_workers}
    finally:
        if own:
            client.close()
            if cluster is not None:
                cluster.close()
    seconds = time.monotonic() - start
    cat = {f: np.concatenate([getattr(c, f) for c in chunks]) for f in
           ("index", "values", "noise_seed", "achieved", "margin", "passed", "failed_runs")}
    prep = prepared(text, sw.path, batch)
    from designkit.sweep.chunk import _names

    names = _names(prep)
    limits = {}
    req = prep.requirements
    for k in names:
        limits[k] = float(np.min(np.asarray(getattr(req, k), dtype=float)))
    result = SweepResult(name=name, seed=int(seed), dimensions=prep.space.dimensions,
                         distribution=prep.space.distribution, requirements=names, limits=limits,
                         engine={**where, "chunks": job.n_chunks, "chunk": chunk, "batch": batch,
                                 "resumed_chunks": resumed, "seconds": round(seconds, 3),
                                 "samples_per_second": round(samples / seconds, 1) if seconds > 0 else None,
                                 "integrator": str(sim.settings.get("integrator", "")),
                                 "steps_per_run": int(sim.time.size)},
                         **cat)
    worst = _worst(prep, result, name)
    fals = None
    if falsification and prep.space.dimensions and worst:
        from designkit.sweep.falsify import falsify

        order = [w.sample for w in worst]
        starts = result.values[order]
        fals = falsify(prep, starts, result.noise_seed[order])
    import dataclasses

    result = dataclasses.replace(result, worst=worst, falsification=fals)
    if folder is not None:
        from designkit.sweep.files import write_outputs

        files = write_outputs(result, prep, folder, report=report)
        result = dataclasses.replace(result, files=files, worst=tuple(
            dataclasses.replace(w, spec_file=files.get(f"worst_{w.rank}")) for w in result.worst))
    return result


def _full_text(sw: Any) -> str:
    """The text the workers read: the design spec with its sweep section (as validated) appended."""
    import yaml

    section = sw.section.model_dump(mode="json", exclude_defaults=True)
    return sw.text if not section else sw.text.rstrip("\n") + "\n" + yaml.safe_dump({"sweep": section},
                                                                                    sort_keys=False)


def _worst(prep: Any, result: SweepResult, name: str) -> tuple[Worst, ...]:
    from designkit.sweep.margins import Margins
    from designkit.sweep.worst import rank, worst_spec

    m = Margins(names=result.requirements, limits=result.limits,
                achieved={k: result.achieved[:, r] for r, k in enumerate(result.requirements)},
                margin={k: result.margin[:, r] for r, k in enumerate(result.requirements)})
    norm = m.normalized()
    norm[result.failed_runs] = -np.inf
    order = rank(norm, result.index)[:WORST]
    out = []
    for r, pos in enumerate(order, start=1):
        i = int(result.index[pos])
        values = {d.name: float(result.values[pos, k]) for k, d in enumerate(result.dimensions)}
        seed = int(result.noise_seed[pos])
        text = worst_spec(prep, result.values[pos], seed, name=f"{name}-worst-{r}", description=(
            f"Sample {i} of the sweep of {name} (seed {result.seed}), the {_ordinal(r)} worst of "
            f"{result.samples}: " + ", ".join(f"{d.name} = {result.values[pos, k]:.6g} {d.unit}".rstrip()
                                              for k, d in enumerate(result.dimensions))
            + ". Re-run it with designkit synth."))
        margins = {k: (float(result.margin[pos, c]) if np.isfinite(result.margin[pos, c]) else None)
                   for c, k in enumerate(result.requirements)}
        out.append(Worst(rank=r, sample=i, values=values, noise_seed=seed if seed >= 0 else None, margins=margins,
                         objective=float(np.min(norm[pos])) if norm.size else 0.0, spec_text=text))
    return tuple(out)


def _ordinal(r: int) -> str:
    return {1: "1st", 2: "2nd", 3: "3rd"}.get(r, f"{r}th")
