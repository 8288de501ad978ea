"""The arm's questions of one run, assembled: :func:`lab_answers` and :class:`LabAnswers`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.studies.arm.configuration import Configuration, measure_configuration
from designkit.studies.arm.coupling import Coupling, measure_coupling
from designkit.studies.arm.mass import mass_sentences
from designkit.studies.arm.run import check_named, family_label, path_samples
from designkit.studies.arm.tracking import Tracking, measure_tracking

__all__ = ["LabAnswers", "lab_answers", "nature_of"]


@dataclass(frozen=True)
class LabAnswers:
    """The answers to the arm's questions for one run.

    Parameters
    ----------
    controller : str
        The family's label.
    nature : str
        ``"per-joint loops"`` (designed joint by joint on simplified links), ``"model-based"``
        (cancels the model's dynamics; its error poles are checked along the path) or ``"other"``;
        decided from the design and the checks, not from the family's kind.
    tracking : Tracking
    configuration : Configuration
    mass : tuple of str
        Sentences on the influence of the mass parameters.
    coupling : Coupling
    """

    controller: str
    nature: str
    tracking: Tracking
    configuration: Configuration
    mass: tuple[str, ...]
    coupling: Coupling



def nature_of(result: Any) -> str:
    """``"per-joint loops"``, ``"model-based"`` or ``"other"`` (see :class:`LabAnswers`), from the design and checks."""
    if result.design.loops:
        return "per-joint loops"
    if check_named(result, "error_poles") is not None:
        return "model-based"
    return "other"


def lab_answers(result: Any) -> LabAnswers | None:
    """Answer the arm's questions for ``result`` (see the package docstring).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        Its ``simulation``, ``plant`` (the true plant; None: the design's), ``design`` and ``checks``.

    Returns
    -------
    LabAnswers or None
        None for a plant that is not a robot, or a run without simulation.
    """
    sim = result.simulation
    plant = result.plant if result.plant is not None else result.design.plant
    if sim is None or getattr(plant, "kind", None) != "robot" or getattr(result.design.plant, "kind", None) != "robot":
        return None
    nature = nature_of(result)
    path = path_samples(sim)
    with np.errstate(all="ignore"):
        tracking = measure_tracking(sim, plant)
    return LabAnswers(
        controller=family_label(result),
        nature=nature,
        tracking=tracking,
        configuration=measure_configuration(result, plant, path, nature),
        mass=mass_sentences(result, plant),
        coupling=measure_coupling(result, plant, path, nature),
    )
