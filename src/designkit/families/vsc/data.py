"""The variable structure regulator's design data (:attr:`~designkit.synthesis.design.Design.data`): the surface,
theorem 3's gains and the box they were certified on, and what the run's hold band and measurements need.

Units: ``x`` is the plant's state (the link's ``[x1 (rad), x2 (rad/s)]``, the elastic joint's ``[theta_m (rad),
theta_m' (rad/s), theta_l (rad), theta_l' (rad/s)]``), ``u`` its input (N*m) and ``d`` its perturbation (N*m).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.families.vsc.gains import Bound
from designkit.synthesis.design import FamilyData, freeze

__all__ = ["CornerPoles", "VscData", "bound_json"]


@dataclass(frozen=True)
class CornerPoles:
    """The sliding motion's poles at one corner of the parameter box.

    Attributes
    ----------
    at : Mapping of str to float
        The corner: each uncertain parameter's value (its unit).
    poles : tuple of complex
        The reduced system's poles there (1/s).
    """

    at: Mapping[str, float]
    poles: tuple[complex, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "at", freeze(dict(self.at)))
        object.__setattr__(self, "poles", tuple(complex(z) for z in self.poles))

    def to_json(self) -> dict[str, Any]:
        """``{"at": {...}, "poles": [[re, im], ...]}``."""
        return {"at": dict(self.at), "poles": [[z.real, z.imag] for z in self.poles]}


def bound_json(b: Bound) -> dict[str, Any]:
    """A range of :class:`~designkit.families.vsc.gains.Bound` in JSON types, without its label."""
    return {"lower": b.lower, "upper": b.upper, "argmin": b.argmin, "argmax": b.argmax, "method": b.method,
            "form": b.form, "min_value": b.min_value, "max_value": b.max_value}


@dataclass(frozen=True)
class VscData(FamilyData):
    """What the law, checks, measurements, figures, report and answers read of a ``vsc`` design.

    Attributes
    ----------
    c : tuple of float
        The surface ``sigma = c x~``, normalised so that the driven state's coefficient is 1 (sigma's unit per
        state unit).
    alpha, beta : tuple of float
        The switching gains where ``x~_i sigma > 0`` and ``< 0`` (u's unit per state unit).
    delta : float
        The relay amplitude (u's unit).
    margin : float
        The relative margin the gains were designed with (dimensionless).
    S : tuple of float
        Each gain's scale ``S_i`` the margin is a fraction of (u's unit per state unit).
    box : Mapping of str to (float, float)
        The parameter box the conditions are certified on (each parameter's unit).
    d_bar : float
        The perturbation bound (d's unit).
    bounds : Mapping of str to Bound
        The ranges over the box of ``l_1`` ... ``l_n`` (u's unit per state unit), ``cB`` and ``cD/cB``.
    G : tuple of float
        ``G_i = max(l_i,max - alpha_i, beta_i - l_i,min)`` (u's unit per state unit), the hold band's factors.
    cB_max, cD_max : float
        The largest ``cB`` and ``|cD|`` over the box (sigma's unit per u's and d's unit).
    cB_nominal : float
        ``cB`` at the nominal plant.
    cA_nominal : tuple of float
        ``cA`` at the nominal plant (sigma's unit per second per state unit).
    rest_direction : tuple of float
        ``x*(1) - x*(0)``: the rest state per unit of reference (state unit per rad).
    position_index : int
        The state of the controlled position.
    band : float
        The band ``|sigma|`` one held step may leave (sigma's unit), or the boundary layer's width.
    max_step : float
        The largest integration step (s).
    S0 : float
        The largest ``|sigma'|`` at the initial error over the box (sigma's unit per second).
    boundary_layer : float or None
        ``epsilon`` of ``sat(sigma/epsilon)`` (sigma's unit), or None for the switching law.
    plant_kind : str
        ``"link"`` or ``"elastic_joint"``.
    nominal_model : tuple of numpy.ndarray
        ``(A, B, D)`` of the nominal plant.
    drive_index : int or None
        The state the input drives (the one whose coefficient in ``c`` is 1).
    vertex_poles : tuple of CornerPoles
        The sliding motion's poles at every corner of the box.
    u_rest : float
        The input holding the nominal plant at rest per unit of reference (u's unit per rad): 0 on the link and
        the elastic joint; on a linear plant ``u*`` of ``A x* + B u* = 0``, ``C1 x* = 1``.
    reference_max : float
        The largest ``|xD|`` of the run (rad): the rest mismatch of a plant of the box scales with it.
    """

    c: tuple[float, ...]
    alpha: tuple[float, ...]
    beta: tuple[float, ...]
    delta: float
    margin: float
    S: tuple[float, ...]
    box: Mapping[str, tuple[float, float]]
    d_bar: float
    bounds: Mapping[str, Bound]
    G: tuple[float, ...]
    cB_max: float
    cD_max: float
    cB_nominal: float
    cA_nominal: tuple[float, ...]
    rest_direction: tuple[float, ...]
    position_index: int
    band: float
    max_step: float
    S0: float
    boundary_layer: float | None
    plant_kind: str
    nominal_model: tuple[np.ndarray, np.ndarray, np.ndarray]
    drive_index: int | None
    vertex_poles: tuple[CornerPoles, ...]
    u_rest: float = 0.0
    reference_max: float = 0.0
