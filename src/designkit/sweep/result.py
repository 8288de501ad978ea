"""The frozen result of a sweep: the per-sample table, the pass fraction with its exact interval, each
requirement's margin distribution, the worst samples and the falsification's worst case."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.sweep.margins import REQUIREMENTS
from designkit.sweep.stats import clopper_pearson, quantiles

__all__ = ["LEVEL", "SweepResult", "Worst"]

LEVEL = 0.95
"""Confidence level of the pass fraction's two-sided Clopper--Pearson interval."""


@dataclass(frozen=True)
class Worst:
    """One of the worst samples: its index, values, noise seed, margins and the spec that re-runs it."""

    rank: int
    sample: int
    values: dict[str, float]
    noise_seed: int | None
    margins: dict[str, float | None]
    objective: float
    spec_text: str
    spec_file: str | None = None

    def to_json(self) -> dict[str, Any]:
        return {"rank": self.rank, "sample": self.sample, "parameters": dict(self.values),
                "noise_seed": self.noise_seed, "margins": dict(self.margins), "worst_normalized_margin":
                self.objective if np.isfinite(self.objective) else None, "spec": self.spec_file}


@dataclass(frozen=True, eq=False)
class SweepResult:
    """Everything a sweep produced.

    Parameters
    ----------
    name : str
        The spec's name.
    seed : int
    dimensions : tuple of Dimension
        What was sampled (:mod:`designkit.sweep.sampling`).
    distribution : str
    requirements : tuple of str
        The requirements scored, in report order.
    limits : dict
        Each requirement's limit (its unit: :data:`~designkit.sweep.margins.REQUIREMENTS`).
    index, values, noise_seed, achieved, margin, passed, failed_runs : ndarray
        Per sample (rows in sample order): index, sampled values ``(N, d)``, noise seed (-1 without noise),
        achieved value and margin per requirement ``(N, r)`` (NaN: undefined), verdict, integrator failure.
    worst : tuple of Worst
    falsification : Falsification or None
    engine : dict
        How it ran (scheduler, workers, chunks, batch, resumed chunks, seconds).
    files : dict
        What was written (path strings).
    """

    name: str
    seed: int
    dimensions: tuple[Any, ...]
    distribution: str
    requirements: tuple[str, ...]
    limits: dict[str, float]
    index: np.ndarray
    values: np.ndarray
    noise_seed: np.ndarray
    achieved: np.ndarray
    margin: np.ndarray
    passed: np.ndarray
    failed_runs: np.ndarray
    worst: tuple[Worst, ...] = ()
    falsification: Any = None
    engine: dict[str, Any] = field(default_factory=dict)
    files: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("index", "values", "noise_seed", "achieved", "margin", "passed", "failed_runs"):
            getattr(self, name).setflags(write=False)

    @property
    def samples(self) -> int:
        return int(self.index.size)

    @property
    def n_passed(self) -> int:
        return int(np.count_nonzero(self.passed))

    @property
    def pass_fraction(self) -> float:
        return self.n_passed / self.samples

    @property
    def confidence(self) -> tuple[float, float]:
        """The two-sided :data:`LEVEL` Clopper--Pearson interval of the pass probability."""
        return clopper_pearson(self.n_passed, self.samples, LEVEL)

    @property
    def verified(self) -> bool:
        """Every sample passed and the falsification broke no requirement."""
        return self.n_passed == self.samples and not (self.falsification is not None and self.falsification.broken)

    @property
    def table(self) -> Any:
        """The per-sample table as a pandas DataFrame: ``sample``, each sampled quantity, ``noise_seed`` (when
        swept), each requirement's achieved value and ``margin_<requirement>``, ``passed``, ``integrator_failed``."""
        import pandas as pd

        cols: dict[str, Any] = {"sample": self.index}
        for k, d in enumerate(self.dimensions):
            cols[d.name] = self.values[:, k]
        if np.any(self.noise_seed >= 0):
            cols["noise_seed"] = self.noise_seed
        for r, name in enumerate(self.requirements):
            cols[name] = self.achieved[:, r]
            cols[f"margin_{name}"] = self.margin[:, r]
        cols["passed"] = self.passed
        cols["integrator_failed"] = self.failed_runs
        return pd.DataFrame(cols)

    def requirement_summary(self) -> dict[str, dict[str, Any]]:
        """Per requirement: limit, unit, passed count (margin defined and not negative) and margin quantiles."""
        out = {}
        for r, name in enumerate(self.requirements):
            m = self.margin[:, r]
            out[name] = {"limit": self.limits[name], "unit": REQUIREMENTS[name],
                         "passed": int(np.count_nonzero(np.nan_to_num(m, nan=-1.0) >= 0)),
                         "undefined": int(np.count_nonzero(np.isnan(m))), "margin_quantiles": quantiles(m)}
        return out

    def to_json(self) -> dict[str, Any]:
        """The object ``designkit sweep --json`` prints."""
        lo, hi = self.confidence
        fals = self.falsification
        return {
            "name": self.name,
            "samples": self.samples,
            "passed": self.n_passed,
            "pass_fraction": self.pass_fraction,
            "confidence": [lo, hi],
            "confidence_level": LEVEL,
            "confidence_method": "Clopper-Pearson (exact, two-sided)",
            "seed": self.seed,
            "distribution": self.distribution,
            "sampled": [{"name": d.name, "low": d.low, "high": d.high, "unit": d.unit, "from": d.path}
                        for d in self.dimensions],
            "integrator_failures": int(np.count_nonzero(self.failed_runs)),
            "requirements": self.requirement_summary(),
            "worst": [w.to_json() for w in self.worst],
            "falsification": None if fals is None else {
                "parameters": {d.name: float(v) for d, v in zip(self.dimensions, fals.values, strict=True)},
                "worst_normalized_margin": fals.objective, "requirement": fals.requirement,
                "margins": dict(fals.margins), "breaks_a_requirement": fals.broken,
                "start_normalized_margin": fals.start_objective, "evaluations": fals.evaluations,
                "method": fals.method},
            "verified": self.verified,
            "engine": dict(self.engine),
            "files": dict(self.files),
        }
