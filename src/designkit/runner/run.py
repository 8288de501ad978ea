"""A spec run as the pipeline runs it: true plant, design, simulation or trials, checks."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["Run", "base_dir", "run_spec"]


@dataclass(frozen=True, eq=False)
class Run:
    """What one run of a spec produced.

    Parameters
    ----------
    loaded : LoadedSpec
        The spec run (with its text and hash).
    plant : Plant
        The true plant the simulation ran on.
    design : Design
        The family's design (for the controller's model, which may differ from the true plant).
    simulation : SimulationResult or None
        The run (a learning law's last trial); None when not simulated.
    trials : TrialsResult or None
        Every trial of a learning law.
    checks : tuple of Check
        Every check the family offers that applies, in report order.
    seconds : float
        Wall time of the run (s), design and checks included.
    """

    loaded: Any
    plant: Any
    design: Any
    simulation: Any
    trials: Any
    checks: tuple[Any, ...]
    seconds: float = 0.0

    @property
    def verified(self) -> bool:
        """Every required check passes (undecided is not a pass)."""
        from designkit.verification.check import all_passed

        return all_passed(self.checks)

    @property
    def failed(self) -> tuple[Any, ...]:
        """Required checks that failed or are undecided."""
        from designkit.verification.check import not_passed

        return not_passed(self.checks)


def base_dir(loaded: Any) -> Path | None:
    """Folder of the spec file (relative model paths are resolved against it), or None for text."""
    return None if str(loaded.path).startswith("<") else Path(loaded.path).resolve().parent


def run_spec(loaded: Any, *, plant: Any = None, adjust: Callable[[Any], Any] | None = None,
             simulate: bool = True, actual: Any = None, design: Any = None, box: bool = True,
             verdict_run: bool = False) -> Run:
    """Run a one-controller spec as :func:`designkit.pipeline.run` does.

    Parameters
    ----------
    loaded : LoadedSpec
        A validated one-controller spec.
    plant : Plant, optional
        The true plant (default: built from ``loaded.spec.plant``).
    adjust : callable, optional
        ``design -> design``: applied to the family's design before the run (a study's other gains,
        :func:`designkit.runner.variants.with_gains`).
    simulate : bool
        Run the simulation (or the trials) and the checks that read it.
    actual : Plant, optional
        The plant the loop runs on and is checked on, when it differs from the one the family designs for
        (``plant``): a study's other link mass or viscosity, which the controller is not told of.
    design : Design, optional
        The design to run instead of the family's synthesis of ``loaded`` (a scenario variant: the controller as
        designed for another spec, run in this one's scenario).
    box : bool
        Let the checks re-run this run at points of ``plant.uncertainty`` (the ``box_runs`` check: the same design,
        the true plant with other parameter values, ``box=False`` inside, so runs do not nest).
    verdict_run : bool
        This run gives the spec's verdict (:func:`designkit.pipeline.run`), not a study's variant, a fix's re-run or a
        box re-run: the checks of the design's shipped code run on it (:attr:`Context.verdict_run`).

    Returns
    -------
    Run
    """
    from designkit.families import check_rules, family, synthesize
    from designkit.simulation.run import build
    from designkit.simulation.trials import run_trials
    from designkit.spec.plant_builder import plant_from_spec
    from designkit.verification.suite import run_checks

    start = time.perf_counter()
    spec = loaded.spec
    plant = plant_from_spec(spec.plant, base_dir(loaded)) if plant is None else plant
    design = synthesize(spec, plant) if design is None else design
    if adjust is not None:
        design = adjust(design)
    plant = plant if actual is None else actual
    sim = trials = simulator = None
    if simulate:
        learning = design.learning
        if learning is not None and learning.run is not None:  # the design runs its own trials
            trials = learning.run(spec, plant)
            sim = trials.results[-1]
        else:
            simulator = build(spec, design, plant=plant, expected_runs=learning.trials if learning else 1)
            if learning is not None:
                trials = run_trials(simulator, learning.trials, learning.update)
                sim = trials.results[-1]
            else:
                sim = simulator.run()
    rerun = None
    if simulate and box and getattr(spec.plant, "uncertainty", None) is not None:
        true_plant, base, each = plant, design, family(design.kind).box_design == "each"

        def rerun(values: Any) -> tuple[Any, ...]:
            other = true_plant.with_params(**values)
            if each:  # the family's synthesis for that plant (Family.box_design)
                return run_spec(loaded, plant=other, adjust=adjust, box=False).checks
            return run_spec(loaded, plant=true_plant, design=base, actual=other, box=False).checks

    checks = run_checks(spec, design, sim, plant=plant, rules=check_rules(design.kind), trials=trials, rerun=rerun,
                        verdict_run=verdict_run, simulator=simulator)
    return Run(loaded, plant, design, sim, trials, tuple(checks), time.perf_counter() - start)
