"""What a study may vary of a learning design, and what it measures: the learning gain (with its convergence
boundary) and the feedback poles, against the last trial's error and how much the trials removed."""

from __future__ import annotations

from typing import Any

from designkit.families.ilc.learning import lifted_of
from designkit.synthesis.knobs import Knob, Metric

__all__ = ["KNOBS", "METRICS"]

SEARCH_DECADES = (-3.0, 2.0)
"""The boundary search of a learning gain, in decades about its natural scale (``1/sigma_max(H)^2`` for the
adjoint update, ``1/h_1`` for the P-type update, ``h_1`` the first Markov parameter)."""


def _learning(design: Any) -> str:
    return str(design.data.learning)


def _alpha_scale(design: Any) -> float:
    return 1.0 / max(s.estimate for s in lifted_of(design).sigma_max) ** 2


def _p_scale(design: Any) -> float:
    lifted = lifted_of(design)
    return 1.0 / max(float(abs(h[1])) if len(h) > 1 and h[1] != 0 else float(abs(h[0])) for h in lifted.markov)


def _window(scale: float) -> tuple[float, float]:
    return scale * 10.0 ** SEARCH_DECADES[0], scale * 10.0 ** SEARCH_DECADES[1]


def _last(run: Any) -> float | None:
    trials = run.trials
    if trials is None:
        return None
    return float(trials.max_tracking_errors[-1])


def _removed(run: Any) -> float | None:
    """The last trial's error norm over the first's (1: the trials learned nothing)."""
    trials = run.trials
    if trials is None:
        return None
    norms = trials.error_norms
    return float(norms[-1] / norms[0]) if norms[0] > 0 else None


def _first(run: Any) -> float | None:
    return None if run.trials is None else float(run.trials.max_tracking_errors[0])


def _robot(design: Any) -> bool:
    return design.data.sampled is None


KNOBS = (
    Knob("alpha", "1/s^4", "learning gain of the adjoint update Q = α Hᵀ", 1e-12, 1e30,
         path="controller.learning.alpha", role="learning", boundary=True,
         current=lambda d: float(d.gains["alpha"]), search=lambda d: _window(_alpha_scale(d)),
         when=lambda d: _learning(d) == "adjoint" and _robot(d)),
    Knob("gain", "1/s^2", "learning gain of the P-type update", 1e-12, 1e30,
         path="controller.learning.gain", role="learning", boundary=True,
         search=lambda d: _window(_p_scale(d)), when=lambda d: _learning(d) == "p_type" and _robot(d)),
    Knob("poles", "1/s", "error poles of the computed-torque feedback", 1e-3, 1e5, path="controller.poles",
         when=_robot),
)
"""The learning design's knobs (its learning gain, with the boundary, and the feedback's speed), on a robot: a knob
has one unit, and on a linear plant the learning gain's unit is the plant's own (input per output unit), so no study
varies it there."""

METRICS = (
    Metric("last_trial_error", "peak tracking error of the last trial", "rad", _last,
           "largest |qD − q| over the last trial's instants and joints"),
    Metric("error_norm_ratio", "last trial's error norm over the first's", "", _removed,
           "Euclidean norm of the last trial's sampled error over the first trial's"),
    Metric("first_trial_error", "peak tracking error of the first trial", "rad", _first,
           "largest |qD − q| of the first trial (computed torque alone, no learned signal yet)"),
)
"""The learning design's metrics, the last trial's error first."""

