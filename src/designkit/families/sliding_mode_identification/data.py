"""The sliding-mode identification family's design data (:attr:`~designkit.synthesis.design.Design.data`): one
type per form, the link's and the arm's, sharing the sampling and the gradient rule's settings."""

from __future__ import annotations

from dataclasses import dataclass

from designkit.families.sliding_mode_identification.arm_law import ArmIdentifier
from designkit.synthesis.design import FamilyData

__all__ = ["ArmIdentifierData", "IdentifierData", "LinkIdentifierData"]


@dataclass(frozen=True)
class IdentifierData(FamilyData):
    """What both forms carry.

    Attributes
    ----------
    Ts : float
        The sampling period of the identifier (s).
    window : float
        ``D``, the distance of the two time points (s).
    gamma : tuple of float
        The adaptation gains (link: ``gamma_a`` in s/rad^2, ``gamma_b`` in 1/(s (N*m)^2); arm: one per identified
        base parameter).
    initial : tuple of float
        The estimates at ``t = 0`` (link: ``a`` in 1/s, ``b`` in rad/(s^2 N*m); arm: each base parameter's unit).
    """

    Ts: float
    window: float
    gamma: tuple[float, ...]
    initial: tuple[float, ...]


@dataclass(frozen=True)
class LinkIdentifierData(IdentifierData):
    """The link form (``x2' = -a x2 + b u``).

    Attributes
    ----------
    K1, K2 : float
        The PD servo's gains (N*m/rad, N*m*s/rad).
    c, d : float
        The observer's switching gains (1/s, rad/(s^2 N*m)).
    error_bounds : tuple of float
        The initial estimation errors the gains cover, ``(|a - a_hat(0)|, |b - b_hat(0)|)`` (1/s, rad/(s^2 N*m)).
    required : tuple of float
        The least ``c``, ``d`` those bounds require (1/s, rad/(s^2 N*m)).
    signals : tuple of str
        The signals the law records.
    """

    K1: float
    K2: float
    c: float
    d: float
    error_bounds: tuple[float, float]
    required: tuple[float, float]
    signals: tuple[str, ...]


@dataclass(frozen=True)
class ArmIdentifierData(IdentifierData):
    """The arm form (``u = Wb(q, q', q'') beta``, the model layer's base parameters).

    Attributes
    ----------
    identifier : ArmIdentifier
        The law's numbers (gains, identified columns, known parameters; SI units).
    base_names : tuple of str
        The names of the base parameters ``beta``.
    K : tuple of tuple of float
        The regrouping ``beta = K P`` of the standard parameters (dimensionless).
    units : tuple of str
        The unit of each identified base parameter.
    model_beta : tuple of float
        The controller model's base parameters (their units).
    kinematics : tuple of str
        The symbols the regressor is written in.
    gains_source : str
        Where the gains come from, in words.
    """

    identifier: ArmIdentifier
    base_names: tuple[str, ...]
    K: tuple[tuple[float, ...], ...]
    units: tuple[str, ...]
    model_beta: tuple[float, ...]
    kinematics: tuple[str, ...]
    gains_source: str
