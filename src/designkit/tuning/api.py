"""``designkit.tune``: find the values of the family's knobs that meet every requirement with the largest worst-case
margin over ``plant.uncertainty``, verify the tuned spec, and write it with its report ([docs/tuning.md])."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["DEFAULT_BUDGET", "METHODS", "TuneResult", "choose", "prepare", "tune"]

DEFAULT_BUDGET = 60.0
"""Processor time the search may take by default (s)."""


@dataclass(frozen=True, eq=False)
class TuneResult:
    """What a tuning came to.

    Parameters
    ----------
    loaded : LoadedSpec
        The spec tuned.
    space : Space
        What was tuned (coordinates, ranges, knobs kept).
    points : tuple of dict
        The box's points run besides the nominal plant.
    search : Search
        The search (method, iterations, candidates, time).
    initial : Evaluation
        The spec's own values.
    tuned : LoadedSpec
        The spec with the best values found (the best compromise when none meets every requirement).
    verify : PipelineResult or None
        The full verify of ``tuned`` (None when no candidate met every requirement).
    conflict : Conflict or None
        The conflicting pair, when no candidate met every requirement.
    bound : MinimumTime or None
        The actuator's minimum-time bound, where it applies.
    files : dict
        ``"spec"``, ``"html"`` -> the files written.
    confirmation : Confirmation or None
        The confirming sweep of the tuned spec over ``plant.uncertainty`` (None without uncertainty or when not
        asked for).
    trade : Trade or None
        The requirements' margins along the final direction (None when the tuned point is the initial one).
    choice : str
        Why the search is the one it is: the loop smooth (the gradient search) or, with the reason, not (Nelder--Mead),
        or the method asked for.
    """

    loaded: Any
    space: Any
    points: tuple[dict[str, float], ...]
    search: Any
    initial: Any
    tuned: Any
    verify: Any
    conflict: Any
    bound: Any
    files: dict[str, Path] = field(default_factory=dict)
    confirmation: Any = None
    trade: Any = None
    choice: str = ""

    @property
    def best(self) -> Any:
        """The best candidate."""
        return self.search.best

    @property
    def at_bounds(self) -> tuple[str, ...]:
        """The coordinates the best candidate holds at an end of their range (``"poles[0] (high)"``): the range, not a
        requirement, stops the design there."""
        out = []
        for c, x in zip(self.space.coordinates, self.best.x, strict=True):
            for end, value in (("low", c.low), ("high", c.high)):
                if abs(float(x) - float(np.log(value))) <= 1e-6:
                    out.append(f"{c.label} ({end})")
        return tuple(out)

    @property
    def met(self) -> bool:
        """The best candidate meets every requirement at every point of the box and is certified."""
        return bool(self.best.feasible)

    @property
    def verified(self) -> bool:
        """Tuned and verified: every requirement met over the box, and the tuned spec's full verify passes."""
        return self.met and self.verify is not None and bool(self.verify.verified)

    def to_json(self) -> dict[str, Any]:
        """The result as JSON values."""
        def plain(v: Any) -> Any:
            arr = np.asarray(v)
            if np.iscomplexobj(arr):
                return [[float(np.real(z)), float(np.imag(z))] for z in arr.ravel()] if arr.ndim else \
                    [float(np.real(v)), float(np.imag(v))]
            return arr.tolist()

        s = self.search
        return {
            "name": self.loaded.spec.name,
            "verified": self.verified,
            "met": self.met,
            "method": s.method,
            "method_choice": self.choice,
            "sensitivity_runs": s.sensitivity_runs,
            "iterations": s.iterations,
            "restarts": s.restarts,
            "candidates": len(s.evaluations),
            "simulations": s.simulations,
            "seconds": round(s.seconds, 3),
            "stopped": s.stopped,
            "points": [dict(p) for p in self.points],
            "coordinates": [{"knob": c.knob, "label": c.label, "unit": c.unit, "low": c.low, "high": c.high,
                             "initial": c.initial, "tuned": float(np.exp(np.clip(x, np.log(c.low), np.log(c.high))))}
                            for c, x in zip(self.space.coordinates, self.best.x, strict=True)],
            "kept": list(self.space.kept),
            "at_bounds": list(self.at_bounds),
            "initial": {"values": {k: plain(v) for k, v in self.initial.values.items()},
                        "margins": self.initial.margins, "score": self.initial.score,
                        "certified": self.initial.certified, "failed": list(self.initial.failed)},
            "tuned": {"values": {k: plain(v) for k, v in self.best.values.items()}, "margins": self.best.margins,
                      "score": self.best.score, "certified": self.best.certified, "failed": list(self.best.failed),
                      "active": self.best.active, "worst_point": self.best.worst_point},
            "checks": [c.to_dict() for c in self.verify.checks] if self.verify is not None else [],
            "conflict": None if self.conflict is None else {
                "active": self.conflict.active, "against": self.conflict.against, "alone": self.conflict.alone,
                "compromise": self.conflict.compromise, "sentence": self.conflict.sentence},
            "minimum_time": None if self.bound is None else {
                "amplitude": self.bound.amplitude, "limit": self.bound.limit, "source": self.bound.source,
                "reach": self.bound.reach, "rest_to_rest": self.bound.rest_to_rest, "proves": self.bound.proves,
                "sentence": self.bound.sentence},
            "history": self.search.history[:, 1].tolist(),
            "sweep": None if self.confirmation is None else self.confirmation.to_json(),
            "trade_off": None if self.trade is None else self.trade.to_json(),
            "files": {k: str(v) for k, v in self.files.items()},
        }


def _points(loaded: Any, plant: Any) -> tuple[dict[str, float], ...]:
    """The corners of ``plant.uncertainty`` and its seeded samples (none without uncertainty)."""
    from designkit.verification.checks.box_runs import box_points
    from designkit.verification.robustness import box_from_uncertainty

    unc = getattr(loaded.spec.plant, "uncertainty", None)
    if unc is None:
        return ()
    box = box_from_uncertainty(plant, unc)
    points, *_ = box_points(box)
    return tuple(dict(zip(box.names, map(float, p), strict=True)) for p in points)


def _loaded(spec: Any) -> Any:
    """``spec`` as a LoadedSpec: one already loaded, or the file at a path (refused, naming ``spec``, when it is no
    path or no file)."""
    from designkit import arguments
    from designkit.errors import SpecError
    from designkit.schema.loader import LoadedSpec, load_spec

    if isinstance(spec, LoadedSpec):
        return spec
    path = arguments.path(spec, "spec", what="a spec file's path or a LoadedSpec")
    if not path.is_file():
        raise SpecError("spec", f"no spec file at {str(path)[:PATH_SHOWN]} (not found, or not a file)")
    return load_spec(path)


PATH_SHOWN = 200
"""Longest quotation of a path in an error message (characters)."""


def _destination(out: Any) -> Path:
    """The output folder, checked before anything runs: no file in the way, writable."""
    import os

    from designkit import arguments
    from designkit.errors import OutputError

    folder = Path.cwd() if out is None else arguments.path(out, "out", error=OutputError, what="a folder path")
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        raise OutputError("out", f"{str(existing)[:PATH_SHOWN]} is an existing file, not a folder; nothing was "
                          "written")
    if existing.exists() and not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError("out", f"no permission to write in {str(existing)[:PATH_SHOWN]}; nothing was written")
    return folder


def prepare(loaded: Any) -> tuple[Any, Any]:
    """The tuning problem of a loaded one-controller spec: ``(Problem, Space)`` (what every candidate shares, and
    what is tuned), as :func:`tune` searches it.

    Raises
    ------
    SpecError
        A comparison spec, a spec without requirements, or a ``tune`` section naming no knob of the family.
    """
    from designkit.errors import SpecError
    from designkit.families import family, synthesize
    from designkit.runner.run import base_dir
    from designkit.spec.plant_builder import plant_from_spec
    from designkit.tuning.evaluate import Problem, requirement_names
    from designkit.tuning.space import build_space

    if not hasattr(loaded.spec, "controller"):
        raise SpecError("controllers", "tune takes a one-controller spec, not a comparison")
    names = requirement_names(loaded.spec)
    if not names:
        raise SpecError("requirements", "the spec gives no requirement to tune for (overshoot, settling_time, "
                        "tracking_error, max_control, margins, ...)")
    plant = plant_from_spec(loaded.spec.plant, base_dir(loaded))
    design = synthesize(loaded.spec, plant)
    fam = family(design.kind)
    space = build_space(loaded, design, fam.knobs, getattr(loaded.spec, "tune", None))
    problem = Problem(loaded, plant, names, _points(loaded, plant), fam.box_design == "each")
    return problem, space


METHODS = ("auto", "gradient", "nelder-mead")
"""The searches :func:`tune` runs: ``auto`` the gradient search on a smooth loop, Nelder--Mead on any other."""


def choose(problem: Any, space: Any, method: str = "auto", seed: int = 0, budget: float = DEFAULT_BUDGET
           ) -> tuple[Any, str]:
    """Run the search ``method`` asks for on the tuning problem: ``(Search, why this search)``.

    Raises
    ------
    SpecError
        ``method``: not one of :data:`METHODS`, or ``gradient`` on a loop that is not smooth (naming why).
    """
    from designkit.errors import SpecError
    from designkit.families import synthesize
    from designkit.tuning.descent import slsqp
    from designkit.tuning.evaluate import evaluate
    from designkit.tuning.search import nelder_mead
    from designkit.tuning.sensitivity import gradients, smooth_loop

    if method not in METHODS:
        raise SpecError("method", f"must be one of {', '.join(METHODS)}, got {str(method)[:40]!r}")
    why_not = "" if method == "nelder-mead" else smooth_loop(problem, synthesize(problem.loaded.spec, problem.plant))
    if method == "gradient" and why_not:
        raise SpecError("method", f"the gradient search needs a smooth loop, and this one is not: {why_not}")

    def run(x: np.ndarray, above: float) -> Any:
        return evaluate(problem, space, x, above=above)

    if method == "nelder-mead":
        choice = "Nelder-Mead, as asked"
    elif why_not:
        choice = f"Nelder-Mead (derivative-free): {why_not}"
    else:
        choice = ("gradient: a smooth loop (a continuous law, no switching, sampling, delay, quantisation or "
                  "learning)" + (", as asked" if method == "gradient" else ""))
        return slsqp(run, lambda x: gradients(problem, space, x), space.x0, space.bounds, budget=budget,
                     seed=seed), choice
    return nelder_mead(run, space.x0, space.bounds, budget=budget, seed=seed), choice


def tune(spec: Any, *, out: str | Path | None = None, budget: float = DEFAULT_BUDGET, seed: int = 0,
         write: bool = True, sweep_samples: int = 64, scheduler: str | None = None,
         method: str = "auto") -> TuneResult:
    """Tune the knobs of a spec's controller for its requirements over its uncertainty box (docs/tuning.md).

    Parameters
    ----------
    spec : str, Path or LoadedSpec
        A one-controller spec with ``requirements`` (and optionally ``plant.uncertainty`` and ``tune``).
    out : str or Path, optional
        Folder of ``<name>-tuned.yaml`` and ``<name>-tuning.html`` (default: the current folder; created if needed).
    budget : float
        Processor time the search may take (s, > 0; this process and the compilers it waits for).
    seed : int
        Seed of the random restarts.
    write : bool
        Write the tuned spec and the report.
    sweep_samples : int
        Samples of the confirming sweep of the tuned spec over ``plant.uncertainty`` (0: none; at most 10 000).
    scheduler : str, optional
        Address of a Dask scheduler the confirming sweep runs on (``tcp://host:8786``), checked before the search
        as ``designkit sweep --scheduler`` checks it; without it the sweep runs in this process.
    method : str
        ``auto`` (default): the gradient search on a smooth loop, Nelder--Mead on a switching, sampled, learning or
        otherwise non-smooth one; ``gradient`` or ``nelder-mead`` to force one (``gradient`` refused on a loop that
        is not smooth).

    Returns
    -------
    TuneResult

    Raises
    ------
    SpecError
        A bad argument, a spec without requirements, a comparison spec, a ``tune`` section naming no knob of the
        family (each with its key path), or a ``scheduler`` that is no address or answers no Dask handshake
        (``--scheduler``).
    OutputError
        ``out`` cannot be a folder (a file in the way, no permission); checked before anything runs.
    """
    from designkit import arguments
    from designkit.errors import SpecError
    from designkit.runner.variants import changed_spec
    from designkit.tuning.confirm import check_scheduler, confirm
    from designkit.tuning.infeasible import conflict, minimum_time
    from designkit.tuning.trade import trade_off

    budget = arguments.number(budget, "budget", positive=True)
    seed = arguments.integer(seed, "seed", low=0, high=2**32 - 1)
    write = arguments.flag(write, "write")
    sweep_samples = arguments.integer(sweep_samples, "sweep_samples", low=0, high=10_000)
    if method not in METHODS:
        raise SpecError("method", f"must be one of {', '.join(METHODS)}, got {str(method)[:40]!r}")
    folder = _destination(out)
    loaded = _loaded(spec)
    problem, space = prepare(loaded)
    check_scheduler(scheduler)
    search, choice = choose(problem, space, method, seed, budget)
    initial = search.evaluations[0]
    best = search.best
    tuned = changed_spec(loaded, [("name", (loaded.spec.name + "-tuned")[:100]), *space.changes(best.x)])
    verify = None
    if best.feasible:
        from designkit.pipeline import run

        verify = run(tuned)
    found = None if best.feasible else conflict(search.evaluations, best)
    bound = minimum_time(loaded.spec)
    confirmation = None
    if sweep_samples and getattr(loaded.spec.plant, "uncertainty", None) is not None:
        confirmation = confirm(tuned, samples=sweep_samples, seed=seed, scheduler=scheduler)
    trade = trade_off(problem, space, space.x0, best.x)
    result = TuneResult(loaded, space, problem.points, search, initial, tuned, verify, found, bound,
                        confirmation=confirmation, trade=trade, choice=choice)
    if write:
        from designkit.tuning.report import write_files

        result = write_files(result, folder)
    return result
