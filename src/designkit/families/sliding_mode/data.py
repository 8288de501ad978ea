"""The sliding-mode family's design data (:attr:`~designkit.synthesis.design.Design.data`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from designkit.synthesis.design import FamilyData

__all__ = ["SlidingData"]


@dataclass(frozen=True)
class SlidingData(FamilyData):
    """What the sliding-mode synthesis chose and derived, read by the law, the checks, the figures and the JSON.

    Attributes
    ----------
    c : float
        The sliding line's slope, ``s = x2 + c e`` (1/s; the sliding pole is ``-c``).
    xi_bar : float
        ``sup |xi|``, the bound of the input-equivalent perturbation (N*m).
    margin : float
        Relative margin of the gains over their conditions (dimensionless).
    box : Mapping
        The uncertainty box: ``Km`` ((rad/s)/(N*m)) and ``tau`` (s), each ``(low, high)``.
    amplitude : float
        The reference's largest step (rad).
    e_max : float
        The largest position error the gains are designed for (rad).
    band : float
        The chattering band ``|s| <= band`` the step is chosen for (rad/s).
    band_source : str
        Where the band comes from, in words.
    boundary_layer : float or None
        ``epsilon`` of ``M sat(s/epsilon)`` (rad/s), or None for the relay ``M sign(s)``.
    max_step : float
        The largest integration step (s).
    sdot_max : float
        ``max |s'|`` over the box within the band (rad/s^2).
    strip : float or None
        Half-width of the strip about ``s = 0`` where ``s s' < 0`` (rad/s); None when unbounded.
    reaching_rate : float
        ``eta = b_min (M - xi_bar)`` (rad/s^2).
    lp : Mapping
        The gains' linear program certificate (weights, rows, objective; JSON types).
    torque_rows : str
        What became of the torque rows of the linear program, in words.
    objective : float
        The linear program's objective ``e_max (alpha - beta) + 2 M`` (N*m).
    fixed : tuple of str
        Gains given by the spec, not designed.
    reaching_frequency : float or None
        ``controller.reaching_frequency`` (rad/s), or None.
    """

    c: float
    xi_bar: float
    margin: float
    box: Mapping[str, tuple[float, float]]
    amplitude: float
    e_max: float
    band: float
    band_source: str
    boundary_layer: float | None
    max_step: float
    sdot_max: float
    strip: float | None
    reaching_rate: float
    lp: Mapping[str, Any]
    torque_rows: str
    objective: float
    fixed: tuple[str, ...]
    reaching_frequency: float | None
