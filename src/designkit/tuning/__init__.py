"""Requirement-driven tuning with certificates: ``designkit tune`` (docs/tuning.md).

The tuner moves the knobs a family declares as spec settings (:mod:`~designkit.tuning.space`: poles, zeros,
adaptation and switching gains, in log space), runs every candidate through the family's own run with every check
(:mod:`~designkit.tuning.evaluate`), maximises the worst normalised requirement margin over the corners (and
samples) of ``plant.uncertainty`` -- on a smooth loop by SLSQP on its epigraph with gradients through the simulation
(:mod:`~designkit.tuning.descent`, :mod:`~designkit.tuning.sensitivity`), on any other by Nelder–Mead with restarts
(:mod:`~designkit.tuning.search`) --, verifies the tuned spec, writes it with its report, HTML and PDF
(:mod:`~designkit.tuning.report`), and says why when no value meets every requirement
(:mod:`~designkit.tuning.infeasible`).  It sits above the
runner, the studies and the pipeline, below the command line.
"""

from designkit.tuning.api import TuneResult, tune

__all__ = ["TuneResult", "tune"]
