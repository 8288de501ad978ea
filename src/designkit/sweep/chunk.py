"""One chunk of a sweep, as a worker runs it: samples drawn, simulated in batches, margins, written.

A worker process builds the spec's design and simulator once (:func:`prepared`, cached per process by the
spec text) and then runs chunk after chunk: chunk ``k`` holds samples ``k C`` to ``(k + 1) C - 1`` (``C``
the chunk size), drawn from their own streams (:mod:`designkit.sweep.sampling`), simulated ``batch`` at a
time by the mapped compiled step (:mod:`designkit.simulation.batch`), and scored requirement by
requirement (:mod:`designkit.sweep.margins`).  With an output folder the chunk is written as
``chunks/chunk-<k>.npz`` through a temporary file renamed into place (atomic on POSIX), so a chunk file is
either complete or absent; a resumed sweep keeps every chunk file whose header matches.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from designkit.errors import SpecError

__all__ = ["ChunkResult", "Job", "Prepared", "base", "chunk_path", "prepared", "read_chunk", "run_chunk", "run_samples"]


@dataclass(frozen=True)
class Job:
    """What every chunk of one sweep shares (plain data: sent to the workers).

    Parameters
    ----------
    text, path : str
        The spec's YAML (with its ``sweep:`` section) and where it was read from.
    seed : int
        The sweep's seed.
    samples : int
        Total number of samples ``N``.
    chunk : int
        Samples per chunk ``C``.
    batch : int
        Samples per batched evaluation (at most ``C``).
    out : str or None
        Folder whose ``chunks/`` receives the chunk files (None: kept in memory only).
    key : str
        SHA-256 of the spec text, the seed and the chunk size (the header a chunk file must carry).
    """

    text: str
    path: str
    seed: int
    samples: int
    chunk: int
    batch: int
    out: str | None
    key: str

    @property
    def n_chunks(self) -> int:
        return -(-self.samples // self.chunk)

    def bounds(self, k: int) -> tuple[int, int]:
        """First and one-past-last sample of chunk ``k``."""
        return k * self.chunk, min((k + 1) * self.chunk, self.samples)


@dataclass(frozen=True, eq=False)
class Prepared:
    """A spec made ready to sweep in one process: design, simulator, batch simulator, sample space."""

    sweep: Any
    plant: Any
    design: Any
    simulator: Any
    batch: Any
    space: Any
    requirements: Any
    kernel: Any = None


@dataclass(frozen=True, eq=False)
class ChunkResult:
    """The samples of one chunk: index, values, noise seed, per-requirement achieved value and margin, verdict."""

    chunk: int
    index: np.ndarray
    values: np.ndarray
    noise_seed: np.ndarray
    achieved: np.ndarray
    margin: np.ndarray
    passed: np.ndarray
    failed_runs: np.ndarray

    def to_arrays(self) -> dict[str, np.ndarray]:
        return {"chunk": np.array(self.chunk), "index": self.index, "values": self.values,
                "noise_seed": self.noise_seed, "achieved": self.achieved, "margin": self.margin,
                "passed": self.passed, "failed_runs": self.failed_runs}


@functools.lru_cache(maxsize=4)
def base(text: str, path: str) -> Prepared:
    """Load, design and build the simulator of a spec, once per process (cached by text and path); no batch
    simulator yet (``batch`` is None)."""
    from designkit.pipeline import design, plant
    from designkit.simulation.run import build
    from designkit.sweep.allocator import keep_large_arrays_on_the_heap
    from designkit.sweep.sampling import sample_space
    from designkit.sweep.section import parse_sweep

    keep_large_arrays_on_the_heap()
    sw = parse_sweep(text, path=path)
    if getattr(sw.loaded.spec, "implementation", None) is not None:
        raise SpecError("implementation", "a sweep runs every sample through one compiled kernel of the designed "
                        "loop, which does not carry the controller as implemented (sampling, computation delay, "
                        "quantisation, actuator); verify the implemented loop with designkit verify, or leave the "
                        "section out to sweep the designed loop")
    true_plant = plant(sw.loaded)
    space = sample_space(sw, true_plant)  # the sampled box checked before anything is designed
    dsn = design(sw.loaded, true_plant)
    if dsn.learning is not None:
        raise SpecError("controller.kind", f"a sweep runs each sample once; the {dsn.kind} design learns over "
                        "trials, which a sweep does not run")
    if not _names_of(sw.loaded.spec.requirements):
        raise SpecError("requirements", "a sweep scores every sample against the time-domain requirements "
                        "(overshoot, settling_time, rise_time, steady_state_error, tracking_error, max_control); "
                        "give at least one")
    if design_has_motion(dsn) and any(d.kind == "initial_position" for d in space.dimensions):
        raise SpecError("sweep.initial_position", "a task-space motion starts where its path starts; its initial "
                        "position is not swept")
    if any(d.kind == "initial_position" for d in space.dimensions):
        _check_start_free(sw, true_plant, dsn)
    sim = build(sw.loaded.spec, dsn, plant=true_plant, expected_runs=1)
    return Prepared(sweep=sw, plant=true_plant, design=dsn, simulator=sim, batch=None, space=space,
                    requirements=sw.loaded.spec.requirements)


def _check_start_free(sw: Any, true_plant: Any, dsn: Any) -> None:
    """Refuse a swept initial position when the design itself depends on it (a family that designs at the start
    configuration): the sample's spec would then be another controller, not the swept one."""
    from designkit.families import synthesize

    spec = sw.loaded.spec
    ends = [[float(lo) for lo, _ in sw.section.initial_position], [float(hi) for _, hi in sw.section.initial_position]]
    for q in ends:
        moved = spec.model_copy(update={"simulation": spec.simulation.model_copy(update={"initial_position": q})})
        if synthesize(moved, true_plant).gains.to_json() != dsn.gains.to_json():
            raise SpecError("sweep.initial_position", f"the {dsn.kind} design depends on the initial position (its "
                            "gains change over the interval), so each sampled start would be another controller; "
                            "sweep the initial position of one design by giving it as its own spec, or leave "
                            "sweep.initial_position out")


@functools.lru_cache(maxsize=4)
def prepared(text: str, path: str, batch: int) -> Prepared:
    """:func:`base` with its batch simulator of ``batch`` samples (compiled once per process)."""
    import dataclasses

    from designkit.simulation.batch import batch_simulator
    from designkit.sweep.kernel import kernel_for

    b = base(text, path)
    kernel = None
    if not b.space.noise and not any(d.kind == "initial_position" for d in b.space.dimensions):
        found = kernel_for(b.simulator, b.requirements)
        kernel = None if isinstance(found, str) else found
    return dataclasses.replace(b, batch=batch_simulator(b.simulator, batch), kernel=kernel)


def design_has_motion(dsn: Any) -> bool:
    return getattr(dsn, "motion", None) is not None


def _inputs(prep: Prepared, values: np.ndarray, seeds: np.ndarray) -> dict[str, Any]:
    """The batch simulator's per-run inputs for sample values ``(B, d)`` and noise seeds."""
    from designkit.simulation.batch import noise_rows

    sim, plant, space = prep.simulator, prep.plant, prep.space
    names = [q.name for q in plant.parameters]
    P = np.tile(np.asarray(plant.parameter_vector, dtype=float), (values.shape[0], 1))
    out: dict[str, Any] = {}
    for k, dim in enumerate(space.dimensions):
        if dim.kind == "parameter":
            P[:, names.index(dim.key)] = values[:, k]
    for k, dim in enumerate(space.dimensions):
        if dim.kind == "payload":
            P[:, names.index(dim.key)] += values[:, k]
    joints = [k for k, d in enumerate(space.dimensions) if d.kind == "initial_position"]
    if joints:
        q0 = initial_positions(prep, values)
        z0, refs = [], []
        for q in q0:
            z, ref = start_of(prep, q)
            z0.append(z)
            refs.append(ref)
        out.update(z0=np.stack(z0), references=refs)
    if space.noise:
        from designkit.spec.fields import per_joint

        std = np.broadcast_to(np.asarray(per_joint(prep.sweep.loaded.spec.simulation.noise.std,
                                                   len(plant.states), "simulation.noise.std"), dtype=float),
                              (len(plant.states),))
        out["noise"] = np.stack([noise_rows(std, int(s), sim.time.size) for s in seeds])
    return {"parameters": P, **out}


def initial_positions(prep: Prepared, values: np.ndarray) -> np.ndarray:
    """``(B, n)``: each sample's initial position (the swept joints from ``values``, the others at their
    interval's low end)."""
    section = prep.sweep.section.initial_position
    q0 = np.tile(np.array([lo for lo, _ in section], dtype=float), (values.shape[0], 1))
    for k, dim in enumerate(prep.space.dimensions):
        if dim.kind == "initial_position":
            q0[:, dim.key] = values[:, k]
    return q0


def start_of(prep: Prepared, q0: np.ndarray) -> tuple[np.ndarray, Any]:
    """The augmented initial state and the reference of a run starting at ``q0`` (the single run's rest start)."""
    from designkit.simulation.reference import reference_for
    from designkit.synthesis.closed_loop import rest_state

    spec, dsn, plant, sim = prep.sweep.loaded.spec, prep.design, prep.plant, prep.simulator
    section = spec.simulation.model_copy(update={"initial_position": [float(v) for v in q0]})
    ref = reference_for(dsn.reference, section, len(plant.positions))
    x0 = np.asarray(plant.rest_state(ref.start), dtype=float)
    rest = rest_state(plant, sim.law, x0, ref.rest())
    z = np.array(sim.z0, dtype=float)
    z[:x0.size] = x0
    z[x0.size:x0.size + rest.xc.size] = rest.xc
    return z, ref


def run_samples(prep: Prepared, values: np.ndarray, seeds: np.ndarray) -> tuple[Any, np.ndarray]:
    """Simulate and score samples ``values`` (``(B, d)``, ``B`` at most the batch): their margins and whether the
    integrator failed on each."""
    from designkit.sweep.margins import margins, margins_of

    if prep.kernel is not None:  # every grid point reduced inside the compiled pair (designkit.sweep.kernel)
        jm, failed = prep.kernel.run(prep.simulator, _inputs(prep, values, seeds)["parameters"])
        return margins_of(jm, prep.simulator.kind, prep.requirements), failed
    records = prep.batch.run(**_inputs(prep, values, seeds))
    return margins(records, prep.simulator.kind, prep.requirements), np.array([bool(f) for f in records.failures])


def chunk_path(out: str | os.PathLike[str], k: int) -> Path:
    return Path(out) / "chunks" / f"chunk-{k:06d}.npz"


def read_chunk(job: Job, k: int) -> ChunkResult | None:
    """Chunk ``k`` of ``job`` from its file, or None when absent, unreadable or written by another sweep."""
    if job.out is None:
        return None
    path = chunk_path(job.out, k)
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["key"]) != job.key or int(z["chunk"]) != k:
                return None
            lo, hi = job.bounds(k)
            if not np.array_equal(z["index"], np.arange(lo, hi)):
                return None
            return ChunkResult(**{f: z[f] if f != "chunk" else int(z[f]) for f in
                                  ("chunk", "index", "values", "noise_seed", "achieved", "margin", "passed",
                                   "failed_runs")})
    except (OSError, KeyError, ValueError, EOFError):
        return None


def run_chunk(job: Job, k: int) -> ChunkResult:
    """Run chunk ``k`` of ``job`` (module docstring); with ``job.out``, write it atomically (or read it back when a
    valid file is there already: a retried or resumed chunk is not recomputed)."""
    done = read_chunk(job, k)
    if done is not None:
        return done
    prep = prepared(job.text, job.path, job.batch)
    lo, hi = job.bounds(k)
    index = np.arange(lo, hi)
    values, seeds = prep.space.draw(job.seed, index)
    names = _names(prep)
    achieved = np.empty((index.size, len(names)))
    margin = np.empty((index.size, len(names)))
    passed = np.empty(index.size, dtype=bool)
    failed = np.empty(index.size, dtype=bool)
    for a in range(0, index.size, job.batch):
        b = min(a + job.batch, index.size)
        m, fail = run_samples(prep, values[a:b], seeds[a:b])
        for r, name in enumerate(names):
            achieved[a:b, r] = m.achieved[name]
            margin[a:b, r] = m.margin[name]
        passed[a:b] = m.passed & ~fail if names else ~fail
        failed[a:b] = fail
    result = ChunkResult(chunk=k, index=index, values=values, noise_seed=seeds, achieved=achieved, margin=margin,
                         passed=passed, failed_runs=failed)
    if job.out is not None:
        path = chunk_path(job.out, k)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        with open(tmp, "wb") as fh:
            np.savez(fh, key=np.array(job.key), **result.to_arrays())
        os.replace(tmp, path)
    return result


def _names(prep: Prepared) -> tuple[str, ...]:
    return _names_of(prep.requirements)


def _names_of(req: Any) -> tuple[str, ...]:
    from designkit.sweep.margins import REQUIREMENTS

    return tuple(k for k in REQUIREMENTS if req is not None and getattr(req, k) is not None)
