"""The PID/sliding-mode family's design data (:attr:`~designkit.synthesis.design.Design.data`): one type per form,
the link's (package module), the elastic joint's (:mod:`~designkit.families.pid_sliding_mode.elastic`) and the
robot's (:mod:`~designkit.families.pid_sliding_mode.robot`); which one a design carries says which form it is.

Units: the sliding variable ``slm`` in rad*s, torques (``M``, ``xi``, ``u``) in N*m, ``a1`` in s, ``a2`` in s^2,
``p3`` in 1/s.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from designkit.families.pid_sliding_mode.bound import PerturbationBound
from designkit.models.link import LinkParameters
from designkit.models.perturbation import PerturbationEnclosure
from designkit.synthesis.design import FamilyData

__all__ = ["ElasticSlidingData", "LinkSlidingData", "LoadMode", "RobotSlidingData"]


@dataclass(frozen=True)
class LinkSlidingData(FamilyData):
    """The one-link controller (package module), read by its law, checks, measurements, figures, ``--json`` and
    diagnoses.

    Attributes
    ----------
    form : {"servo", "tracking"}
        The PID part: the servo with its zero on ``p3`` or the tracker.
    sliding_variable : str
        ``slm`` in words.
    pid_gains : tuple of str
        The names of the PID part's gains (``K1`` ... ``K4`` or ``K1`` ... ``K3``).
    a1, a2, p3 : float
        The sliding variable's coefficients (s, s^2) and the pole of ``slm' = p3 slm + ...`` (1/s).
    g_nominal : float
        ``a2 Km0/tau0``, the relay's gain on ``slm'`` at the nominal link (rad*s per N*m per s).
    M : float
        The relay amplitude (N*m).
    M_given : bool
        ``M`` was given by the spec (not designed).
    margin : float
        The relative margin of ``M`` over ``sup|xi|`` (dimensionless).
    perturbation : PerturbationBound
        ``sup|xi|`` over the box and the sliding motion (notes §5.4, N*m) and where it is attained.
    box : Mapping of str to (float, float)
        The ``(Km, tau)`` box ((rad/s)/(N*m), s) the conditions are certified on.
    nominal : (float, float)
        The nominal ``(Km0, tau0)`` the PID part was designed on.
    q0 : float
        The reference's start (rad): the integral starts at ``-a1 q0`` (servo).
    epsilon : float or None
        The boundary layer (rad*s), or None for the relay.
    layer : {"saturation", "dead_zone"}
        What the layer is, when there is one.
    band_certified : float or None
        The band (rad*s) the ``pid_sm_band`` condition certifies invariant, or None (saturation layer).
    sdot_max : float
        The largest ``|slm'|`` the band and step are sized with (rad).
    max_step : float
        The largest integration step (s).
    discontinuous : bool
        The command switches (held over each step).
    l1 : float
        ``||s/N(s)||_1`` (1/s): the position's distance from the sliding motion per unit of ``|slm|``.
    """

    form: Literal["servo", "tracking"]
    sliding_variable: str
    pid_gains: tuple[str, ...]
    a1: float
    a2: float
    p3: float
    g_nominal: float
    M: float
    M_given: bool
    margin: float
    perturbation: PerturbationBound
    box: Mapping[str, tuple[float, float]]
    nominal: tuple[float, float]
    q0: float
    epsilon: float | None
    layer: Literal["saturation", "dead_zone"]
    band_certified: float | None
    sdot_max: float
    max_step: float
    discontinuous: bool
    l1: float

    @property
    def xi_total(self) -> float:
        """``sup|xi_p| + xi_e`` (N*m): the parameter change's and the external perturbation's bound."""
        return self.perturbation.total


@dataclass(frozen=True)
class LoadMode:
    """The link's mode on the elastic joint's sliding surface.

    Attributes
    ----------
    k2 : float
        ``KR R2^2/J2`` (1/s^2).
    omega : float
        ``sqrt(k2)`` (rad/s).
    zeta : float
        ``1/(2 tau2 sqrt(k2))``, its damping (dimensionless).
    """

    k2: float
    omega: float
    zeta: float

    def to_json(self) -> dict[str, float]:
        """``{"k2", "omega", "zeta"}``."""
        return {"k2": self.k2, "omega": self.omega, "zeta": self.zeta}


@dataclass(frozen=True)
class ElasticSlidingData(FamilyData):
    """The elastic joint's motor-side controller (:mod:`~designkit.families.pid_sliding_mode.elastic`).

    Attributes
    ----------
    pid_gains : tuple of str
        The names of the PID part's gains.
    a1, a2, p3 : float
        The sliding variable's coefficients (s, s^2) and the third pole (1/s).
    M : float
        The relay amplitude (the plant's input unit).
    sup_du_eq : float
        The largest equivalent switching control on the sliding motions of the box's corners (input unit).
    sup_at : Mapping of str to float
        The corner where it is attained (empty: the nominal plant).
    band : float
        The band ``|slm| <= band`` the step keeps (rad*s), or the saturation layer's width.
    epsilon : float or None
        The saturation layer (rad*s), or None for the relay.
    max_step : float
        The largest integration step (s).
    q0 : float
        The reference's start (rad): the integral ``z`` starts at ``-a1 q0``.
    rigid : (float, float)
        The rigid approximation ``(Km, tau)`` ((rad/s)/(input unit), s) the PID part is designed on.
    load_mode : LoadMode
        The link's mode on the sliding surface.
    ideal_t, ideal_x1, ideal_x3 : numpy.ndarray
        The nominal sliding motion, decimated: time (s), motor and link positions (rad, spring side).
    """

    pid_gains: tuple[str, ...]
    a1: float
    a2: float
    p3: float
    M: float
    sup_du_eq: float
    sup_at: Mapping[str, float]
    band: float
    epsilon: float | None
    max_step: float
    q0: float
    rigid: tuple[float, float]
    load_mode: LoadMode
    ideal_t: np.ndarray
    ideal_x1: np.ndarray
    ideal_x3: np.ndarray


@dataclass(frozen=True)
class RobotSlidingData(FamilyData):
    """The robot's controller, one loop per joint with the hierarchy of control's relays
    (:mod:`~designkit.families.pid_sliding_mode.robot`).

    Attributes
    ----------
    form : {"servo", "tracking"}
        The PID part of every joint.
    pid_gains : tuple of str
        The names of the PID part's gains.
    a1, a2, p3 : float
        The sliding variable's coefficients (s, s^2) and the third pole (1/s), the same for every joint.
    gains : tuple of Mapping
        Per joint, its PID gains by name (N*m/rad, N*m*s/rad, N*m/(rad*s), s).
    links : tuple of LinkParameters
        Per joint, the simplified link it is designed on (``inertia = D^_i``, ``damping = f_i``).
    inertia_range : tuple of (float, float)
        Per joint, the sampled range of ``D_ii`` over the workspace (kg*m^2).
    gravity_feedforward : {"measured", "none"}
        The gravity feed-forward ``g^(q)`` of the nominal model, or none.
    M : tuple of float
        Per joint, the relay amplitude (N*m).
    M_given : bool
        ``M`` was given by the spec (one value for every joint).
    margin : float
        The relative margin of ``M_i`` over the proven bound (dimensionless).
    enclosure : PerturbationEnclosure
        The proven ``sup|xi_i|`` per joint, the attained lower bound and where, the parts, the work it took.
    workspace : Mapping
        The motion box (:func:`~designkit.families.pid_sliding_mode.robot.motion_box`): ``low``, ``high`` (rad),
        ``velocity`` (rad/s), ``acceleration`` (rad/s^2) per joint.
    parameter_box : tuple of Mapping
        The uncertain model parameters (:func:`~designkit.families.pid_sliding_mode.robot.parameter_box`): each
        row's ``name``, ``index``, ``low``, ``high``, ``nominal`` and ``unit``; empty without ``plant.uncertainty``.
    acceleration_rows : tuple of tuple of float
        Per joint, the acceleration box (rad/s^2 per joint) its bound covers.
    sliding_acceleration : tuple of float
        Per joint, its sliding motion's largest acceleration (rad/s^2).
    coulomb : tuple of float
        Per joint, the Coulomb friction the bound includes (N*m).
    q0 : tuple of float
        Per joint, the reference's start (rad): the integrals start at ``-a1 q0`` (servo).
    epsilon : float or None
        The boundary layer (rad*s), or None for the relays.
    layer : {"saturation", "dead_zone"}
        What the layer is, when there is one.
    sdot_max : tuple of float
        Per joint, the largest ``|slm_i'|`` (rad).
    max_step : float
        The largest integration step (s).
    discontinuous : bool
        The command switches (held over each step).
    l1 : float
        ``||s/N(s)||_1`` (1/s).
    """

    form: Literal["servo", "tracking"]
    pid_gains: tuple[str, ...]
    a1: float
    a2: float
    p3: float
    gains: tuple[Mapping[str, float], ...]
    links: tuple[LinkParameters, ...]
    inertia_range: tuple[tuple[float, float], ...]
    gravity_feedforward: Literal["measured", "none"]
    M: tuple[float, ...]
    M_given: bool
    margin: float
    enclosure: PerturbationEnclosure
    workspace: Mapping[str, Any]
    parameter_box: tuple[Mapping[str, Any], ...]
    acceleration_rows: tuple[tuple[float, ...], ...]
    sliding_acceleration: tuple[float, ...]
    coulomb: tuple[float, ...]
    q0: tuple[float, ...]
    epsilon: float | None
    layer: Literal["saturation", "dead_zone"]
    sdot_max: tuple[float, ...]
    max_step: float
    discontinuous: bool
    l1: float

    @property
    def bound(self) -> tuple[float, ...]:
        """Per joint, the proven ``sup|xi_i|`` (N*m)."""
        return tuple(self.enclosure.upper)

    @property
    def sampled(self) -> tuple[float, ...]:
        """Per joint, the largest ``|xi_i|`` attained at a point of its box (N*m): a lower bound of the sup."""
        return tuple(self.enclosure.sampled)
