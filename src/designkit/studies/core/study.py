"""What a study declares, and what it returns.

A study (one module of :mod:`designkit.studies`, defining ``STUDY``) says what it applies to
(:attr:`Study.applies`: a run's family, plant, scenario) and how it runs (:attr:`Study.run`): it varies the
family's knobs and runs every variant through the family's own run (:func:`designkit.runner.variants.vary`),
so a learning law learns over its trials, an adaptive law adapts, a switching law switches at its held step,
and the family's checks judge each variant.  It returns a :class:`StudyResult`: the rows it measured (for
``synth --json`` and for tests), the recommendation it can defend, and the report section and figures that
say it in words.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from designkit.display.section import ReportSection

__all__ = ["OUTCOMES", "Entry", "Recommended", "Row", "Study", "StudyContext", "StudyResult"]

OUTCOMES = ("verified", "failed", "undecided", "diverged", "refused", "not run")
"""What a variant's run came to: every required check passed; one failed; one is undecided (none failed); the
simulated state left the finite numbers; the variant cannot be designed as asked (the family refused it); it
could not be run (the reason is in the row's detail)."""


@dataclass(frozen=True)
class Row:
    """One variant of a study.

    Parameters
    ----------
    factor : float
        The knob's value over the value in use (1: the spec's own run).
    value : float or tuple of float
        The knob's value (its unit; per joint when the knob is).
    metrics : Mapping[str, float | None]
        The family's metrics (and the generic ones) on the variant's run, by key.
    outcome : str
        One of :data:`OUTCOMES`.
    detail : str
        The checks that failed or are undecided (their labels), or why the variant was not run.
    seconds : float
        Wall time of the variant's run (s); not part of the row's value.
    cpu : float
        Processor time of the variant's run (s, :func:`~designkit.studies.core.budget.cpu_seconds`), charged to the
        study's budget; not part of the row's value.
    """

    factor: float
    value: Any
    metrics: Mapping[str, float | None]
    outcome: str
    detail: str = ""
    seconds: float = field(default=0.0, compare=False)
    cpu: float = field(default=0.0, compare=False)

    def __post_init__(self) -> None:
        if self.outcome not in OUTCOMES:
            raise ValueError(f"outcome must be one of {OUTCOMES}, got {self.outcome!r}")

    @property
    def passed(self) -> bool:
        """Every required check of the variant passed."""
        return self.outcome == "verified"

    def to_json(self) -> dict[str, Any]:
        """JSON types only: a metric that is infinite (a run that diverged, a response that never settles) or
        undefined is ``null``, the outcome and detail say which."""
        value = [_json(v) for v in self.value] if isinstance(self.value, tuple) else _json(self.value)
        metrics = {k: (v if v is not None and math.isfinite(v) else None) for k, v in self.metrics.items()}
        return {"factor": self.factor, "value": value, "metrics": metrics, "outcome": self.outcome,
                "detail": self.detail}


def _json(v: Any) -> Any:
    """A value for JSON: a complex number (a pole) as ``[re, im]``, as ``synth --json`` writes poles."""
    return [v.real, v.imag] if isinstance(v, complex) else v


@dataclass(frozen=True)
class Recommended:
    """A value a study can defend: it and every point of its neighbourhood ``[low, high]`` that was run passed
    every required check (``checked`` lists them)."""

    value: float
    low: float
    high: float
    checked: tuple[float, ...] = ()

    def to_json(self) -> dict[str, Any]:
        return {"value": self.value, "low": self.low, "high": self.high, "checked": list(self.checked)}


@dataclass(frozen=True)
class Entry:
    """What a study measured for one parameter: the rows, in increasing value, and its recommendation.

    ``setting`` is the recommendation as a change of the spec, ``(key path, value)`` in the spec's units, when the
    parameter is a spec setting: a fix a failing report can propose, already run.
    """

    parameter: str
    unit: str
    rows: tuple[Row, ...]
    recommended: Recommended | None = None
    setting: tuple[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        return {"parameter": self.parameter, "unit": self.unit, "rows": [r.to_json() for r in self.rows],
                "recommended": self.recommended.to_json() if self.recommended is not None else None}


@dataclass(frozen=True)
class StudyResult:
    """What a study returns.

    Parameters
    ----------
    name : str
        The study's name (``"gains"``, ``"boundary"``).
    title : str
        Its title in words.
    entries : tuple of Entry
        One per parameter varied.
    section : ReportSection or None
        What the report says of it.
    figures : tuple of Figure
        Its figures.
    reduced : str
        What the study left out to stay within its budget, and why (``""``: nothing).
    runs : int
        Variants run.
    seconds : float
        Wall time spent (s).
    """

    name: str
    title: str
    entries: tuple[Entry, ...] = ()
    section: ReportSection | None = None
    figures: tuple[Any, ...] = ()
    reduced: str = ""
    runs: int = 0
    seconds: float = 0.0

    def to_json(self) -> list[dict[str, Any]]:
        """One object per parameter: ``{"name", "title", "parameter", "unit", "rows", "recommended", "reduced"}``
        (a study with no parameter, such as a lab answer, gives one object with empty ``rows``)."""
        head = {"name": self.name, "title": self.title, "reduced": self.reduced, "runs": self.runs,
                "seconds": self.seconds}
        if not self.entries:
            return [{**head, "parameter": None, "unit": "", "rows": [], "recommended": None}]
        return [{**head, **e.to_json()} for e in self.entries]


@dataclass(frozen=True)
class StudyContext:
    """What a study reads: the run, its family, the study's own settings from the spec and its budget.

    Parameters
    ----------
    result : PipelineResult
        The spec's own run.
    family : Family
        Its family (knobs, metrics, traits).
    settings : Any
        The study's section of the spec's ``studies`` (its model, validated), or None.
    budget : float
        Seconds of work the study may spend on variants.
    earlier : tuple of StudyResult
        What the studies before this one (in report order) returned: a lab answer cites the gain study's rows.
    """

    result: Any
    family: Any
    settings: Any = None
    budget: float = 15.0
    earlier: tuple[Any, ...] = ()

    def run_all(self, tasks: Any, budget: Any) -> list[Any]:
        """The rows of independent variant ``tasks`` (each ``() -> Row``), in order, each row's processor time charged
        to ``budget``.

        They run in this process: a variant solves LMIs with Clarabel, whose native thread pool a forked child
        would inherit locked, so the report's way of sharing work with a forked child
        (:func:`designkit.processes.run_tasks`) is not safe here.
        """
        rows = [task() for task in tasks]
        for row in rows:
            budget.record(row.cpu)
        return rows

    def study(self, name: str, run: Any = None) -> Any:
        """The result of the earlier study ``name``, or None; with ``run`` (a comparison's member, its own
        one-controller run), that run's own study ``name`` -- what its own report lays out, run once
        (:func:`designkit.studies.study_of`) -- or None when it does not apply."""
        if run is not None:
            from designkit.studies import study_of

            return study_of(run, name)
        return next((s for s in self.earlier if s.name == name), None)

    def new_budget(self) -> Any:
        """A :class:`~designkit.studies.core.budget.Budget` of :attr:`budget` seconds for this study, planning with
        the spec's estimated variant cost (for a comparison, the costliest of its members' specs)."""
        from designkit.runner.run import base_dir
        from designkit.studies.core.budget import Budget, variant_estimate

        runs = getattr(self.result, "results", None) or (self.result,)
        return Budget(self.budget, max(variant_estimate(r.loaded.spec, base_dir(r.loaded)) for r in runs))


@dataclass(frozen=True)
class Study:
    """A study (module docstring).

    Parameters
    ----------
    name : str
        Its key in the spec's ``studies`` section and in ``--json``.
    title : str
        What it answers, in words.
    order : int
        Report order (lower first).
    applies : callable
        ``(result, family) -> bool``: whether it answers anything for this run.
    run : callable
        ``StudyContext -> StudyResult | None``.
    settings : type or None
        The pydantic model of its section of the spec's ``studies`` (a
        :class:`~designkit.spec.fields.Section`), or None when it takes none.
    validate : callable or None
        ``(settings, family, spec) -> None``: cross-checks against the family (a knob it does not declare, a
        value outside the declared range), raising ``ValueError("key.path: message")`` with the path below the
        study's own section.
    comparison : bool
        It applies to a comparison (``controllers:``) rather than to one run.
    """

    name: str
    title: str
    order: int
    applies: Callable[[Any, Any], bool]
    run: Callable[[StudyContext], StudyResult | None]
    settings: type | None = None
    validate: Callable[[Any, Any, Any], None] | None = None
    comparison: bool = False
