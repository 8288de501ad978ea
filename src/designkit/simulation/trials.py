"""Repeated trials of one experiment: what a learning controller learns between runs.

A trial is one run of a built :class:`~designkit.simulation.run.Simulator` from the same
initial state; between trials a learning rule maps the trial's record (and the feedforward it
was run with) to the next feedforward, a sequence of plant inputs ``(N, nu)`` added to the
controller's command at every step (the notes' iterative learning control, section 6).  The
steps of a trial are rolled by CasADi (no Python loop per step); the runner loops over trials.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from designkit import arguments
from designkit.errors import SpecError
from designkit.simulation.result import SimulationResult

__all__ = ["Learning", "LearningRule", "MAX_TRIALS", "TrialsResult", "run_trials"]

LearningRule = Callable[[SimulationResult, np.ndarray], np.ndarray]
"""``(result of trial k, feedforward of trial k) -> feedforward of trial k + 1``, arrays ``(N, nu)`` (the
feedforward's unit is the law's: N*m added to the command, or what ``law.feedforward`` maps)."""

MAX_TRIALS = 200
"""Most trials one run may ask for (a bound on the work, checked before any is run)."""


@dataclass(frozen=True)
class Learning:
    """What a learning design asks of the pipeline: repeated trials with an update between them.

    Parameters
    ----------
    trials : int
        Number of trials (1 to :data:`MAX_TRIALS`).
    update : LearningRule
        The learning update between trials.
    description : str
        The update in words, for the report.
    run : callable, optional
        ``(spec, plant) -> TrialsResult``: the design runs its trials itself, on the true ``plant`` (a sampled
        plant the simulator does not integrate, such as a discrete-time one), with ``update`` between them; None:
        the pipeline builds the simulator and runs :func:`run_trials`.
    """

    trials: int
    update: LearningRule
    description: str = ""
    run: Callable[[object, object], TrialsResult] | None = None

    def __post_init__(self) -> None:
        if not 1 <= int(self.trials) <= MAX_TRIALS:
            raise ValueError(f"trials must be between 1 and {MAX_TRIALS}, got {self.trials}")


@dataclass(frozen=True, eq=False)
class TrialsResult:
    """Every trial of an experiment.

    Parameters
    ----------
    results : tuple of SimulationResult
        Trial ``k``'s record.
    feedforward : tuple of ndarray
        The feedforward ``(N, nu)`` trial ``k`` ran with (N*m).
    """

    results: tuple[SimulationResult, ...]
    feedforward: tuple[np.ndarray, ...]

    @property
    def max_tracking_errors(self) -> np.ndarray:
        """``max_t max_j |q_j - qD_j|`` of each trial (rad)."""
        return np.array([float(np.max(np.abs(r.tracking_errors))) for r in self.results])

    @property
    def error_norms(self) -> np.ndarray:
        """Euclidean norm of each trial's sampled tracking error over every instant and joint (rad)."""
        return np.array([float(np.linalg.norm(r.tracking_errors)) for r in self.results])

    @property
    def rms_tracking_errors(self) -> np.ndarray:
        """Root-mean-square tracking error of each trial over time and joints (rad)."""
        return np.array([float(np.sqrt(np.mean(r.tracking_errors**2))) for r in self.results])


def _feedforward(value: object, shape: tuple[int, int]) -> np.ndarray:
    """``value`` as a finite real array of ``shape`` (one row per sample, one column per input)."""
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise SpecError("feedforward", f"must be an array of real numbers, got {type(value).__name__}") from None
    if out.size != shape[0] * shape[1] or not np.all(np.isfinite(out)):
        raise SpecError("feedforward", f"must hold {shape[0]} x {shape[1]} finite values (samples x inputs), got "
                        f"{out.size} values")
    return out.reshape(shape)


def run_trials(simulator: object, trials: int, learn: LearningRule,
               feedforward: np.ndarray | None = None) -> TrialsResult:
    """Run ``trials`` repetitions of ``simulator``, updating the feedforward with ``learn`` after each.

    Parameters
    ----------
    simulator : Simulator
        The built experiment (:func:`designkit.simulation.run.build`).
    trials : int
        Number of trials (at least 1).
    learn : LearningRule
        The update between trials.
    feedforward : ndarray, optional
        Feedforward of the first trial (default zero).

    Raises
    ------
    SpecError
        An argument of the wrong type or size (naming it): ``trials`` not 1 to :data:`MAX_TRIALS`, a
        ``feedforward`` that is not a real array of ``(samples, inputs)`` values.
    ValueError
        When the learning rule returns an array of the wrong shape.
    """
    from designkit.simulation.run import Simulator

    arguments.instance(simulator, "simulator", Simulator, "a Simulator (dk.build(spec, design))")
    trials = arguments.integer(trials, "trials", low=1, high=MAX_TRIALS)
    if not callable(learn):
        raise SpecError("learn", f"must be a function (result, feedforward) -> feedforward, got {type(learn).__name__}")
    shape = (simulator.time.size, simulator.n_inputs)
    ff = np.zeros(shape) if feedforward is None else _feedforward(feedforward, shape)
    results, used = [], []
    for k in range(trials):
        res = simulator.run(feedforward=ff)
        results.append(res)
        frozen = ff.copy()
        frozen.setflags(write=False)
        used.append(frozen)
        if k + 1 < trials:
            nxt = np.asarray(learn(res, frozen), dtype=float)
            if nxt.shape != shape:
                raise ValueError(f"the learning rule returned shape {nxt.shape}, expected {shape}")
            ff = nxt
    return TrialsResult(results=tuple(results), feedforward=tuple(used))
