"""The ``controller`` section of the sliding-mode identification (notes section 5.5), for the link and for a robot.

One section serves both plants; the fields that belong to one of them are refused on the other by
:func:`validate` (with the key path).  On the link (``plant.kind: link``): ``initial_estimates`` ``[ah(0), bh(0)]``,
``error_bounds``, ``c``, ``d`` and ``adaptation_gains`` ``[ga, gb]``.  On a robot (``plant.kind: robot``):
``identify`` (the base parameters to identify, default all), ``initial_estimates`` and ``adaptation_gains`` by
name (or the gains as a list in the order of ``identify``), and ``switching_gain`` (the observer's, per joint).
``servo``, ``window`` and ``sampling_period`` are common.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, field_validator

from designkit.families.sliding_mode_identification.laws import KIND
from designkit.spec.fields import Finite, PositiveFinite, Section
from designkit.spec.ranges import Range, Ranged, RangedPerJoint

__all__ = ["ESTIMATE_RANGE", "ErrorBounds", "GAIN_RANGE", "LINK_REFERENCES", "ROBOT_REFERENCES", "Servo", "SmidSpec",
           "validate"]

GAIN_RANGE = (1e-12, 1e12)
"""Range of an adaptation gain (in the unit of its parameter squared per (N*m)^2 s on a robot)."""
ESTIMATE_RANGE = 1e6
"""Largest magnitude of an initial estimate (in the parameter's SI unit)."""
LINK_REFERENCES = ("square", "prbs")
"""The references the link's PD servo follows (piecewise constant: ``xD' = 0``)."""
ROBOT_REFERENCES = ("square", "prbs", "multisine", "sine")
"""The references a robot's PD servo follows (a smooth one with its velocity)."""

_Gain = Ranged(*GAIN_RANGE, "")


class Servo(Section):
    """The PD servo driving the plant while it is identified: ``K1`` (N*m/rad) and ``K2`` (N*m*s/rad), 1e-6 to
    1e6; one number on the link, one or one per joint on a robot."""

    K1: RangedPerJoint(1e-6, 1e6, "N*m/rad") = 5.0
    K2: RangedPerJoint(1e-6, 1e6, "N*m*s/rad") = 0.5


class ErrorBounds(Section):
    """Stated bounds on the link's initial estimation errors: ``|a - ah(0)| <= a`` (1/s), ``|b - bh(0)| <= b``
    ((rad/s^2)/(N*m)), 1e-9 to 1e9 each."""

    a: Ranged(1e-9, 1e9, "1/s", base=PositiveFinite)
    b: Ranged(1e-9, 1e9, "rad/(s^2*N*m)", base=PositiveFinite)


class SmidSpec(Section):
    """Sliding-mode identification (notes section 5.5): of ``a = 1/tau`` and ``b = Km/tau`` on the link, of the base
    parameters on a robot.

    Link: ``initial_estimates`` ``[ah(0), bh(0)]`` (1/s, (rad/s^2)/(N*m)); ``error_bounds`` (required); ``c``, ``d``
    the observer's switching gains (1/s, (rad/s^2)/(N*m), > 0; default from the bounds); ``adaptation_gains``
    ``[ga, gb]`` (s/rad^2, 1/(s (N*m)^2); default ``[1, 1]``).
    Robot: ``identify`` (base parameter names, default all); ``initial_estimates`` ``{name: value}`` (SI unit of
    each, within 1e6; default 0); ``switching_gain`` (rad/s^2, > 0, one or per joint; required);
    ``adaptation_gains`` ``{name: gain}`` or a list in the order of ``identify`` (parameter unit squared per
    (N*m)^2 s; default: the information matrix along the reference scaled to a sampled step of 0.5).
    Both: ``servo``; ``window`` ``D`` (s, > 0), the distance of the two time points; ``sampling_period`` (s).
    """

    kind: Literal[KIND]
    servo: Servo = Field(default_factory=Servo)
    identify: list[str] | None = Field(default=None, min_length=1, max_length=200)
    initial_estimates: list[Finite] | dict[str, Finite] | None = None
    error_bounds: ErrorBounds | None = None
    c: Ranged(0.0, 1e9, "1/s", base=PositiveFinite, low_open=True) | None = None
    d: Ranged(0.0, 1e9, "rad/(s^2*N*m)", base=PositiveFinite, low_open=True) | None = None
    switching_gain: RangedPerJoint(0.0, 1e9, "rad/s^2", low_open=True) | None = None
    window: Ranged(0.0, 1e6, "s", base=PositiveFinite, low_open=True) = 0.25
    adaptation_gains: list[_Gain] | dict[str, _Gain] | None = None
    sampling_period: Ranged(1e-5, 10.0, "s", base=PositiveFinite) = 0.002

    @field_validator("identify")
    @classmethod
    def _unique(cls, v: list[str] | None) -> list[str] | None:
        for k, name in enumerate(v or ()):
            if name in v[:k]:
                raise ValueError(f"[{k}]: {name!r} is listed twice")
        return v

    @field_validator("adaptation_gains", mode="before")
    @classmethod
    def _gains_by_name(cls, v: Any) -> Any:
        if isinstance(v, dict):  # the mapping's entries named in the message (not the list branch's type error)
            rng = Range(*GAIN_RANGE, "")
            for name, x in v.items():
                if isinstance(x, bool) or not isinstance(x, int | float):
                    raise ValueError(f"{name}: must be a number, got {x!r}")
                msg = rng.problem(x)
                if msg is not None:
                    raise ValueError(f"{name}: {msg}")
        return v

    @field_validator("initial_estimates")
    @classmethod
    def _estimates(cls, v: Any) -> Any:
        items = v.items() if isinstance(v, dict) else enumerate(v or ())
        for key, x in items:
            where = f"{key}" if isinstance(v, dict) else f"[{key}]"
            if abs(x) > ESTIMATE_RANGE:
                raise ValueError(f"{where}: must be within {ESTIMATE_RANGE:g} in magnitude, got {x:g}")
        return v


def _refuse(cs: Any, names: tuple[str, ...], plant: str, why: str) -> None:
    for name in names:
        if getattr(cs, name) is not None:
            raise ValueError(f"controller.{name}: {why} ({plant})")


def validate(spec: Any) -> None:
    """Cross-section rules: no anti-windup (the PD servo has no integral); the fields of the other plant refused;
    the link's estimates, bounds and gains as two numbers; the references each plant's servo follows."""
    if spec.simulation.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the PD servo driving the identification has no integral to limit")
    cs, kind = spec.controller, spec.plant.kind
    traj = spec.simulation.trajectory
    if kind == "link":
        _refuse(cs, ("identify", "switching_gain"), "the link", "a field of the identification on a robot")
        if not isinstance(cs.initial_estimates, list) or len(cs.initial_estimates) != 2:
            raise ValueError("controller.initial_estimates: the link needs [a_hat(0), b_hat(0)] (1/s, "
                             "(rad/s^2)/(N*m)), two numbers")
        if cs.error_bounds is None:
            raise ValueError("controller.error_bounds: the link needs {a, b}, the stated bounds on the initial "
                             "estimation errors (they set the switching gains c and d)")
        if cs.adaptation_gains is not None and (not isinstance(cs.adaptation_gains, list)
                                                or len(cs.adaptation_gains) != 2):
            raise ValueError("controller.adaptation_gains: the link takes [gamma_a, gamma_b], two numbers")
        for key in ("K1", "K2"):
            if isinstance(getattr(cs.servo, key), list) and len(getattr(cs.servo, key)) != 1:
                raise ValueError(f"controller.servo.{key}: the link has one joint, give one number")
        if traj is not None and traj.kind not in LINK_REFERENCES:
            raise ValueError(f"simulation.trajectory.kind: the link's identification follows "
                             f"{' or '.join(LINK_REFERENCES)}, not {traj.kind!r}")
        return
    _refuse(cs, ("error_bounds", "c", "d"), "a robot's observer takes switching_gain", "a field of the link's "
            "identification")
    if cs.switching_gain is None:
        raise ValueError("controller.switching_gain: required on a robot: the observer's switching gain (rad/s^2, "
                         "one or per joint), above the largest error of the estimated model's acceleration")
    if isinstance(cs.initial_estimates, list):
        raise ValueError("controller.initial_estimates: a robot's estimates are given by name, e.g. "
                         "{Izz1R: -1.5, mcx1R: 2.5}")
