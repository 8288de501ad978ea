"""The self-tuning regulator's design data (:attr:`~designkit.synthesis.design.Design.data`)."""

from __future__ import annotations

from dataclasses import dataclass

from designkit.families.self_tuning.laws import Settings
from designkit.synthesis.design import FamilyData

__all__ = ["SelfTuningData"]


@dataclass(frozen=True)
class SelfTuningData(FamilyData):
    """What the law is rebuilt from and what the checks, runs, studies, figures, report and answers read.

    Attributes
    ----------
    settings : Settings
        The law's settings (:class:`~designkit.families.self_tuning.laws.Settings`, SI): the estimator form, the
        sampling period ``Ts`` (s), forgetting, initial covariance and estimates, covariance bound, safeguards,
        the certainty-equivalence design, its poles (1/s) and observer pole (1/s).
    parameters : tuple of str
        The names of the estimated parameters (the estimator form's).
    units : tuple of str
        Their units.
    nominal : tuple of float
        The link the initial estimates are exact for: ``Km`` ((rad/s)/(N*m)) and ``tau`` (s); the ARX form on a plant
        other than the link: empty.
    excitation_window : float
        The window over which the excitation and the estimates' convergence are judged (s).
    desired : tuple of float or None
        The desired closed-loop polynomial ``Am Ao`` in ``z`` (highest power first, dimensionless), pole placement
        only.
    """

    settings: Settings
    parameters: tuple[str, ...]
    units: tuple[str, ...]
    nominal: tuple[float, ...]
    excitation_window: float
    desired: tuple[float, ...] | None
