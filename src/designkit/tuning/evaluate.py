"""One candidate of a tuning: the spec with the candidate's values, run through the family's own run, judged.

At the nominal plant and at each other point of the box (the corners of ``plant.uncertainty``, and its seeded
samples when the spec asks for ``samples``) the family's design runs on the plant with those parameters (the design
for the nominal plant, or the family's design for that plant when it designs for each, ``Family.box_design``), and
the requirement checks are measured on that run.  A candidate whose requirements could make it the best so far is
then run as ``designkit verify`` runs it (:func:`designkit.runner.run.run_spec`: the family's design, the
simulation, every check the family offers): every required check that is not a requirement -- stability, the
Lyapunov and robustness certificates, SPR, the sliding conditions, the convergence of a learning law -- must pass,
or the candidate is not certified and its score falls below every certified one.

A requirement's **normalised margin** is the check's margin over the requirement's limit (the limit taken as 1 of
its unit when it is 0), capped at 1 and, below -1, compressed logarithmically (:func:`compressed`); a loop margin's
comes from the ``loop_margins`` certificate.  The candidate's
**score** is the smallest normalised margin over the requirements and the points: positive when every requirement
holds everywhere it was run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["CAP", "REQUIREMENTS", "Evaluation", "Problem", "evaluate", "margins_on", "requirement_names"]

REQUIREMENTS = ("overshoot", "settling_time", "rise_time", "steady_state_error", "tracking_error", "max_control",
                "gain_margin", "phase_margin", "modulus_margin", "max_reversal_rate", "max_command_variation")
"""The requirement fields the tuner reads (each a check of the same name, or a margin of ``loop_margins``)."""

_LOOP = {"gain_margin": "gain_margin_db", "phase_margin": "phase_margin_deg", "modulus_margin": "modulus_margin"}

CAP = 1.0
"""Largest normalised margin counted (a requirement met with the whole of its limit to spare)."""

REFUSED, NOT_RUN, DIVERGED, UNCERTIFIED = -100.0, -90.0, -80.0, -20.0
"""Scores below every (compressed) normalised margin: the family refused the values, the run could not be made,
the loop diverged, a certificate failed (this one added to the requirements' score when it is below 0)."""

UNMEASURED = -1.5
"""The margin of a failed requirement its check could not measure (a response that never settles)."""


def compressed(margin: float) -> float:
    """``margin`` above -1, ``-1 - ln(-margin)`` below: the same order, so that a requirement failed a
    thousandfold does not hide by its size every other one from the search."""
    return margin if margin >= -1.0 else -1.0 - math.log(-margin)


def requirement_names(spec: Any) -> tuple[str, ...]:
    """The requirements the spec gives, in :data:`REQUIREMENTS` order."""
    req = spec.requirements
    return tuple(n for n in REQUIREMENTS if req is not None and getattr(req, n, None) is not None)


@dataclass(frozen=True)
class Problem:
    """What every candidate of one tuning shares.

    Parameters
    ----------
    loaded : LoadedSpec
        The spec tuned.
    plant : Plant
        Its true plant (nominal parameters).
    requirements : tuple of str
        The requirements the spec gives.
    points : tuple of dict
        The box's points other than the nominal (parameter name -> value, SI).
    each : bool
        The family designs for each plant of the box (``Family.box_design == "each"``).
    """

    loaded: Any
    plant: Any
    requirements: tuple[str, ...]
    points: tuple[dict[str, float], ...]
    each: bool


@dataclass(frozen=True)
class Evaluation:
    """What one candidate came to.

    Parameters
    ----------
    x : ndarray
        Its log-space point.
    values : dict
        Knob -> its spec value.
    score : float
        The smallest normalised margin (module docstring), or a score below -1 saying why there is none.
    margins : dict
        Requirement -> its worst normalised margin over the points run.
    worst_point : dict
        Requirement -> the point where that margin was found (``{}`` for the nominal plant).
    certified : bool or None
        Every required check other than the requirements passed at the nominal plant; None when they were not run
        (a candidate whose requirements' score could not make it the best, :func:`evaluate`).
    failed : tuple of str
        The required checks (certificates) that failed or are undecided, or why the candidate was not run.
    runs : int
        Simulations made.
    """

    x: np.ndarray
    values: dict[str, Any]
    score: float
    margins: dict[str, float]
    worst_point: dict[str, dict[str, float]] = field(default_factory=dict)
    certified: bool | None = False
    failed: tuple[str, ...] = ()
    runs: int = 0

    @property
    def feasible(self) -> bool:
        """Certified and every requirement met at every point run."""
        return self.certified is True and self.score > 0

    @property
    def active(self) -> str | None:
        """The requirement with the smallest margin: the one that limits the design."""
        return min(self.margins, key=self.margins.get) if self.margins else None


def _limit(spec: Any, name: str) -> float:
    value = np.asarray(getattr(spec.requirements, name), dtype=float)
    return float(np.min(value))


def _normalised(check: Any, limit: float) -> float:
    if check.margin is None or not math.isfinite(float(check.margin)):
        return CAP if check.passed is True else UNMEASURED
    return compressed(min(CAP, float(check.margin) / (limit if limit > 0 else 1.0)))


def _loop_margins(check: Any, names: tuple[str, ...]) -> dict[str, float]:
    out: dict[str, float] = {}
    limits = dict(check.certificate.get("limits", {}))
    rows = check.certificate.get("loops", [])
    for name in names:
        if name not in _LOOP or name not in limits:
            continue
        lim = float(limits[name])
        vals = [r.get(_LOOP[name]) for r in rows]
        worst = CAP
        for v in vals:
            if v is None:  # an infinite margin
                continue
            v = abs(float(v)) if name == "gain_margin" else float(v)
            worst = min(worst, (v - lim) / (lim if lim > 0 else 1.0))
        out[name] = compressed(min(CAP, worst)) if rows else UNMEASURED
    return out


def margins_of(checks: tuple[Any, ...], spec: Any, names: tuple[str, ...]) -> dict[str, float]:
    """Requirement -> its normalised margin among ``checks`` (a requirement with no check: not in the result)."""
    out: dict[str, float] = {}
    for c in checks:
        if c.name in names:
            out[c.name] = min(out.get(c.name, CAP), _normalised(c, _limit(spec, c.name)))
        elif c.name == "loop_margins":
            out.update(_loop_margins(c, names))
    return out


def _requirement_rules(kind: str, names: tuple[str, ...]) -> tuple[Any, ...]:
    """The family's rules (and the universal ones) that own a requirement's check, and no other (run directly:
    :func:`designkit.verification.suite.run_checks` would add every universal rule)."""
    from designkit.families import check_rules
    from designkit.verification.suite import resolve

    wanted = set(names)
    return tuple(r for r in resolve(check_rules(kind)) if any(r.owns(n) for n in wanted)
                 or (r.name == "loop_margins" and wanted & set(_LOOP)))


def _requirements_at(problem: Problem, loaded: Any, design: Any, plant: Any) -> dict[str, float]:
    """The requirement margins of ``design``'s loop run on ``plant``: its simulation, or, for a learning design, its
    trials (the requirements then read the last trial, as the family's own run does)."""
    from designkit.simulation.run import build
    from designkit.simulation.trials import run_trials

    spec = loaded.spec
    learning = design.learning
    simulator = build(spec, design, plant=plant, expected_runs=learning.trials if learning else 1)
    trials = run_trials(simulator, learning.trials, learning.update) if learning is not None else None
    sim = trials.results[-1] if trials is not None else simulator.run()
    return margins_on(problem, spec, design, plant, sim, trials)


def margins_on(problem: Problem, spec: Any, design: Any, plant: Any, sim: Any, trials: Any = None
               ) -> dict[str, float]:
    """The requirement margins the family's checks give on the run ``sim`` of ``design``'s loop on ``plant``
    (:data:`DIVERGED` for every requirement when the run diverged)."""
    from designkit.verification.suite import Context

    if sim.diverged_at is not None:
        return dict.fromkeys(problem.requirements, DIVERGED)
    ctx = Context(spec, sim, spec.numerics.solver, plant, None, trials, None)
    checks = [c for rule in _requirement_rules(design.kind, problem.requirements) if rule.offered_for(design, ctx)
              for c in rule.run(design, ctx)]
    margins = margins_of(checks, spec, problem.requirements)
    return {n: margins.get(n, UNMEASURED) for n in problem.requirements}


def _certificates(problem: Problem, loaded: Any, design: Any) -> tuple[str, ...]:
    """The required checks other than the requirements that fail or are undecided in the family's own run."""
    from designkit.runner.run import run_spec

    run = run_spec(loaded, plant=problem.plant, design=design, box=False)
    names = problem.requirements
    return tuple(c.name for c in run.failed if c.name not in names and not (
        c.name == "loop_margins" and set(names) & set(_LOOP)))


def evaluate(problem: Problem, space: Any, x: np.ndarray, *, above: float = -np.inf) -> Evaluation:
    """Run the candidate at ``x`` (module docstring); never raises for a value the family refuses or a run that
    cannot be made: its score says so, with the reason in ``failed``.

    The requirements are measured first, at every point; the family's certificates (its full run at the nominal
    plant, every check) are run only when the requirements' score exceeds ``above`` -- the best score found so
    far: a candidate that cannot become the best needs no certificate (its ``certified`` is then None).
    """
    from designkit.errors import DesignkitError
    from designkit.families import synthesize
    from designkit.runner.variants import changed_spec

    x = np.asarray(x, dtype=float)
    values = space.values(x)
    names = problem.requirements
    margins = dict.fromkeys(names, CAP)
    worst: dict[str, dict[str, float]] = dict.fromkeys(names, {})
    runs = 0
    try:
        loaded = changed_spec(problem.loaded, space.changes(x))
        nominal = synthesize(loaded.spec, problem.plant)
        for point in ({}, *problem.points):
            plant = problem.plant.with_params(**point) if point else problem.plant
            design = synthesize(loaded.spec, plant) if point and problem.each else nominal
            here = _requirements_at(problem, loaded, design, plant)
            runs += 1
            for name, m in here.items():
                if m < margins[name]:
                    margins[name], worst[name] = m, dict(point)
            if min(here.values()) <= DIVERGED:
                return Evaluation(x, values, DIVERGED, margins, worst, False, (f"diverged at {point or 'nominal'}",),
                                  runs)
    except DesignkitError as exc:
        return Evaluation(x, values, REFUSED, dict.fromkeys(names, REFUSED), failed=(f"refused: {exc}",), runs=runs)
    except Exception as exc:  # noqa: BLE001 -- a run that cannot be made is that candidate's outcome, with its reason
        return Evaluation(x, values, NOT_RUN, dict.fromkeys(names, NOT_RUN),
                          failed=(f"not run: {type(exc).__name__}: {exc}",), runs=runs)
    score = min(margins.values()) if margins else CAP
    if score <= above:
        return Evaluation(x, values, score, margins, worst, None, (), runs)
    try:
        failed = _certificates(problem, loaded, nominal)
    except DesignkitError as exc:
        failed = (f"refused: {exc}",)
    except Exception as exc:  # noqa: BLE001 -- as above
        failed = (f"not run: {type(exc).__name__}: {exc}",)
    runs += 1
    if failed:
        score = min(score, 0.0) + UNCERTIFIED
    return Evaluation(x, values, score, margins, worst, not failed, failed, runs)
