"""One variant of a study run and measured: the row it becomes.

The run is the family's own (:func:`designkit.runner.variants.vary`); the row says what it came to (every
required check passed, one failed or is undecided -- named --, the run diverged, the family refused the variant)
and carries the family's metrics on it.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from designkit.studies.core.budget import Budget, cpu_seconds
from designkit.studies.core.metrics import values
from designkit.studies.core.study import Row

__all__ = ["nominal_row", "outcome_of", "run_row", "run_variant"]


def _label(check: Any) -> str:
    return (getattr(check, "label", "") or check.name.replace("_", " ")).rstrip(".")


def outcome_of(run: Any) -> tuple[str, str]:
    """``(outcome, detail)`` of a run (:data:`~designkit.studies.core.study.OUTCOMES`)."""
    trials = run.trials.results if run.trials is not None else (run.simulation,) if run.simulation is not None else ()
    for k, sim in enumerate(trials):
        state = np.asarray(sim.state, dtype=float)
        finite = np.all(np.isfinite(state), axis=tuple(range(1, state.ndim)))
        if not np.all(finite):
            t = np.asarray(sim.time, dtype=float)
            at = float(t[int(np.argmin(finite))])
            where = f" in trial {k + 1} of {len(trials)}" if len(trials) > 1 else ""
            return "diverged", f"the simulated state leaves the finite numbers at t = {at:.4g} s{where}"
    required = [c for c in run.checks if c.required]
    failed = [c for c in required if c.passed is False]
    undecided = [c for c in required if c.passed is None]
    if failed:
        return "failed", "; ".join(_label(c) for c in failed)
    if undecided:
        return "undecided", "; ".join(_label(c) for c in undecided)
    return "verified", ""


def _value(value: Any) -> Any:
    arr = np.asarray(value)
    if np.iscomplexobj(arr) and np.any(np.imag(arr) != 0):
        return complex(arr) if arr.ndim == 0 else tuple(complex(v) for v in arr.ravel())
    arr = np.real(arr).astype(float)
    return float(arr) if arr.ndim == 0 else tuple(float(v) for v in arr.ravel())


def nominal_row(result: Any, current: Any, metrics: tuple) -> Row:
    """The spec's own run as a row (factor 1), from the run itself."""
    outcome, detail = outcome_of(result)
    return Row(1.0, _value(current), values(result, metrics), outcome, detail)


def run_variant(result: Any, knob: Any, value: Any, factor: float, metrics: tuple, budget: Budget | None = None
                ) -> Row:
    """Run ``result``'s spec with ``knob`` at ``value`` (``factor`` times the value in use) and measure it
    (:func:`run_row`)."""
    from designkit.runner.variants import vary

    return run_row(lambda: vary(result, knob, value), factor, value, metrics, budget)


def run_row(make: Any, factor: float, value: Any, metrics: tuple, budget: Budget | None = None) -> Row:
    """The row of the run ``make()`` returns (a :class:`~designkit.runner.run.Run` of the family's own run).

    ``budget`` (when given) is charged with the row's processor time; a batch run on two cores
    (:meth:`~designkit.studies.core.study.StudyContext.run_all`) passes none and charges the rows it gets back.
    A variant the family refuses (a :class:`~designkit.errors.DesignkitError`: no equilibrium, an operator that
    cannot be built, a setting the family does not take) is a ``refused`` row with the family's message; a run that
    fails numerically (the integrator gives up) a ``not run`` row with the reason.  Never raises for what the
    variant does.
    """
    from designkit.errors import DesignkitError

    start, cpu = time.perf_counter(), cpu_seconds()
    try:
        with np.errstate(all="ignore"):
            run = make()
            measured = values(run, metrics)
        outcome, detail = outcome_of(run)
        row = Row(float(factor), _value(value), measured, outcome, detail)
    except DesignkitError as exc:
        row = Row(float(factor), _value(value), {m.key: None for m in metrics}, "refused", _first(exc))
    except (ValueError, RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
        row = Row(float(factor), _value(value), {m.key: None for m in metrics}, "not run", _first(exc))
    row = dataclasses.replace(row, seconds=time.perf_counter() - start, cpu=cpu_seconds() - cpu)
    if budget is not None:
        budget.record(row.cpu)
    return row


def _first(exc: BaseException) -> str:
    text = str(getattr(exc, "message", "") or exc) or type(exc).__name__
    path = getattr(exc, "path", "")
    line = text.splitlines()[0]
    return f"{path}: {line}" if path else line
