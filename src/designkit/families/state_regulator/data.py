"""The state regulator's design data (:attr:`~designkit.synthesis.design.Design.data`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from designkit.synthesis.design import FamilyData

__all__ = ["StateRegulatorData"]


@dataclass(frozen=True)
class StateRegulatorData(FamilyData):
    """The feedback, the reference gain and what a constant load leaves, read by the law, ``--json`` and the
    answers.

    Attributes
    ----------
    K : tuple of float, or tuple of tuples
        The state feedback of ``u = -K x + N xD`` (input unit per state unit: N*m/rad, N*m*s/rad on the elastic
        joint's and the link's states); one row per input when the plant has several.
    N : float or tuple of float
        The reference gain giving the controlled position a unit static gain (input unit per position unit); one
        per input when the plant has several.
    open_loop_poles : tuple of complex
        The eigenvalues of the nominal plant's ``A`` (1/s).
    position_index : int
        The state of the controlled position.
    load_offset_per_unit : float
        ``-C (A - B K)^-1 D``: the controlled position's offset per unit of constant load (position unit per
        disturbance unit, rad/(N*m)).
    load_offset_unit : str
        That unit in words (``"rad per N*m"``).
    observer : Observer or None
        The Luenberger observer the law feeds back through, if the spec asks for one
        (:mod:`~designkit.families.state_regulator.observer`).
    """

    K: tuple[float, ...] | tuple[tuple[float, ...], ...]
    N: float | tuple[float, ...]
    open_loop_poles: tuple[complex, ...]
    position_index: int
    load_offset_per_unit: float
    load_offset_unit: str
    observer: Any = None
