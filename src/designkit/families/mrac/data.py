"""The MRAC family's design data (:attr:`~designkit.synthesis.design.Design.data`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from designkit.families.mrac.model import ReferenceModel
from designkit.families.mrac.structure import Structure
from designkit.synthesis.design import FamilyData

__all__ = ["MracData", "RegressorData"]


@dataclass(frozen=True)
class MracData(FamilyData):
    """What the adaptive law is built from, read by the law, the checks, the study and the report.

    Attributes
    ----------
    reference_model : ReferenceModel
        The model the link is made to follow, ``ym'' + a2 ym' + a1 ym = a1 xD`` (``a1`` 1/s^2, ``a2`` 1/s).
    nominal_Km : float
        The nominal link's gain the PD gains are realised on ((rad/s)/(N*m)).
    nominal_tau : float
        The nominal link's time constant (s).
    gamma : tuple of float
        The adaptation gains of ``a1`` (1/(s^5 rad^2)) and ``a2`` (1/(s^3 rad^2)).
    Q : tuple of tuple of float
        The 2 x 2 error weighting of (position, velocity) (dimensionless).
    initial : tuple of float
        The adapted parameters' initial values ``(a1, a2)`` (1/s^2, 1/s).
    modification : Mapping or None
        The ad hoc modification of the gradient rule (:func:`~designkit.families.mrac.modification.resolved`: its
        ``kind`` and settings), None for the plain rule.
    """

    reference_model: ReferenceModel
    nominal_Km: float
    nominal_tau: float
    gamma: tuple[float, float]
    Q: tuple[tuple[float, float], tuple[float, float]]
    initial: tuple[float, float]
    modification: Mapping[str, Any] | None = None

    @property
    def nominal(self) -> tuple[float, float]:
        """``(Km, tau)`` of the nominal link ((rad/s)/(N*m), s)."""
        return self.nominal_Km, self.nominal_tau


@dataclass(frozen=True)
class RegressorData(FamilyData):
    """The feedforward/feedback MRAC's design data (:mod:`designkit.families.mrac.structure`).

    Attributes
    ----------
    structure : Structure
        The nominal plant, the reference model, the filter ``Lambda`` and the ideal parameters.
    rule : str
        ``"mit"``, ``"lyapunov"`` or ``"normalized"``.
    gamma : tuple of float
        One adaptation gain per parameter (1/(s * unit(e) * unit(phi_i))).
    initial : tuple of float
        The parameters at ``t = 0`` (the unit of ``u`` per the unit of their regressor entry).
    normalization : float
        ``alpha0`` of the normalized rule (the unit of ``phi' phi``).
    """

    structure: Structure
    rule: str
    gamma: tuple[float, ...]
    initial: tuple[float, ...]
    normalization: float = 1.0

    @property
    def parameters(self) -> tuple[str, ...]:
        """The adapted parameters' names."""
        return self.structure.names
