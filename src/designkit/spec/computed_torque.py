"""The controller section of computed torque, which the model-based laws built on it extend.

Computed torque ``u = M^(q)(qD'' + K1 e + K2 e') + h^(q, qd)`` makes each joint's (or task coordinate's) error obey
``e'' + K2 e' + K1 e = 0``; the section gives its two error poles per coordinate, directly or as a damping ratio and
a natural frequency, and the model the controller believes.  A family whose law is built on computed torque (task
space, iterative learning) declares its section as a subclass of :class:`ComputedTorqueSpec`;
:func:`error_poles` reads the poles back once the plant's joints are known.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, field_validator, model_validator

from designkit.errors import SpecError
from designkit.spec.controllers import ControllerModel
from designkit.spec.fields import NonNegativeFinite, Section, check_conjugates, joint_values, parse_pole
from designkit.spec.ranges import Ranged, RangedPerJoint, check_poles

__all__ = ["FRICTION_LAYER", "PER_JOINT_FIELDS", "ComputedTorqueSpec", "damped_pair", "error_poles"]

PER_JOINT_FIELDS = ("damping", "natural_frequency")
"""The section's fields holding one value for every joint or one per joint (or per task coordinate)."""


def _pole(value: Any, where: str) -> complex:
    try:
        return parse_pole(value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _pair(poles: list[complex], where: str) -> list[complex]:
    if len(poles) != 2:
        raise ValueError(f"{where}must list exactly 2 poles per joint, got {len(poles)}")
    check_poles(poles, where.removesuffix(": "))
    try:
        check_conjugates(poles)
    except ValueError as exc:
        raise ValueError(f"{where}{exc}") from None
    return poles


def damped_pair(zeta: float, wn: float) -> tuple[complex, complex]:
    """The error poles ``wn (-zeta +- sqrt(zeta^2 - 1))`` (1/s) of a damping ratio (dimensionless) and a natural
    frequency (rad/s)."""
    disc = complex(zeta * zeta - 1.0) ** 0.5
    return wn * (-zeta + disc), wn * (-zeta - disc)


class ComputedTorqueSpec(Section):
    """Computed torque ``u = M^(q)(qD'' + K1 e + K2 e') + h^(q, qd)``.

    Give the error poles -- ``poles``: two poles (1/s) for every joint, or one pair per joint -- or
    ``damping`` (1e-6 to 1e3) and ``natural_frequency`` (rad/s, 1e-12 to 1e12), one value or one per
    joint; either way every ``|p|`` lies between 1e-12 and 1e12 1/s and ``max |p| / min |Re p|`` is at
    most 1e12 (:func:`~designkit.spec.ranges.check_poles`).  ``model``: the model the controller
    believes (default: the true plant).
    """

    kind: str  # each family's section narrows it to its own Literal (the controller union's tag)
    poles: list[Any] | None = Field(default=None, description="Two error poles (1/s) for every joint, or a pair "
                                    "per joint.")
    damping: RangedPerJoint(1e-6, 1e3, "") | None = None
    natural_frequency: RangedPerJoint(1e-12, 1e12, "rad/s") | None = None
    model: ControllerModel | None = None

    @field_validator("poles")
    @classmethod
    def _pole_pairs(cls, v: list[Any] | None) -> list[Any] | None:
        if v is None:
            return v
        nested = [isinstance(p, list | tuple) for p in v]
        if any(nested) and not all(nested):
            raise ValueError("give two poles, or a list of two poles per joint, not a mix")
        if not all(nested):
            return _pair([_pole(p, f"[{k}]") for k, p in enumerate(v)], "")
        if not v:
            raise ValueError("needs at least one pair of poles")
        pairs = [_pair([_pole(p, f"[{i}][{k}]") for k, p in enumerate(row)], f"[{i}]: ") for i, row in enumerate(v)]
        check_poles([p for pair in pairs for p in pair])  # one closed loop: the spread over every joint
        return pairs

    @model_validator(mode="after")
    def _one_way(self) -> ComputedTorqueSpec:
        return self.check_one_way()

    def check_one_way(self) -> ComputedTorqueSpec:
        """Poles, or damping and natural frequency (ValueError otherwise)."""
        by_poles = self.poles is not None
        by_zeta = self.damping is not None or self.natural_frequency is not None
        if by_poles == by_zeta:
            raise ValueError("give either poles, or damping and natural_frequency")
        if by_zeta and (self.damping is None or self.natural_frequency is None):
            raise ValueError("damping and natural_frequency go together")
        for name in ("damping", "natural_frequency"):
            value = getattr(self, name)
            for x in (value if isinstance(value, list) else [] if value is None else [value]):
                if x <= 0:
                    raise ValueError(f"{name}: must be positive, got {x:g}")
        if by_zeta:
            zetas, wns = (v if isinstance(v, list) else [v] for v in (self.damping, self.natural_frequency))
            if len(zetas) == len(wns) or 1 in (len(zetas), len(wns)):  # else refused per joint at synthesis
                n = max(len(zetas), len(wns))
                poles = [p for k in range(n) for p in damped_pair(zetas[k % len(zetas)], wns[k % len(wns)])]
                try:
                    check_poles(poles)
                except ValueError as exc:
                    what = str(exc).split("]: ", 1)[-1] if str(exc).startswith("[") else str(exc)
                    raise ValueError(f"natural_frequency: the error poles of damping and natural_frequency: {what}"
                                     ) from None
        return self


FRICTION_LAYER = Ranged(1e-6, 1e3, "rad/s or m/s", zero=True, base=NonNegativeFinite)
"""``controller.friction_layer``: the boundary layer of the Coulomb compensation (0 = the exact ``sign``;
:mod:`designkit.synthesis.friction_layer`)."""


def error_poles(spec: Any, n: int, what: str = "joint") -> list[tuple[complex, complex]]:
    """The pair of error poles (1/s) of each of ``n`` joints (or task coordinates: ``what``), from ``poles`` or from
    ``damping`` and ``natural_frequency`` (:func:`damped_pair`).

    Raises
    ------
    SpecError
        ``controller.poles``, ``controller.damping`` or ``controller.natural_frequency``: not one entry per
        joint (or coordinate).
    """
    ctrl = spec.controller
    if ctrl.poles is not None:
        if isinstance(ctrl.poles[0], list):
            if len(ctrl.poles) != n:
                raise SpecError("controller.poles", f"needs one pair of poles per {what} ({n}), got {len(ctrl.poles)}")
            return [tuple(p) for p in ctrl.poles]
        return [tuple(ctrl.poles)] * n
    zetas = joint_values(ctrl.damping, n, "controller.damping")
    wns = joint_values(ctrl.natural_frequency, n, "controller.natural_frequency")
    return [damped_pair(zeta, wn) for zeta, wn in zip(zetas, wns, strict=True)]
