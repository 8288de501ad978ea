"""Default parameters of the notes' ROBEL elastic link (appendix B, fig. 5.1).

The notes give no numbers; these are illustrative values for a small DC motor
(rotor 5e-5 kg*m^2) driving a 0.5 kg*m^2 link through a 50:1 reduction
(``R1 = 1/50``, ``R2 = 1``) and a 200 N*m/rad elastic transmission: locked-link
natural frequency ``sqrt(KR R1^2/J1) = 40`` rad/s, free natural frequency about 45 rad/s.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from designkit.errors import ModelError
from designkit.models.elastic import ElasticLinkParameters

__all__ = ["DEFAULTS", "elastic_link"]

DEFAULTS = ElasticLinkParameters(
    J1=5e-5,  # rotor inertia (kg*m^2)
    tau1=0.05,  # motor mechanical time constant J1/B1 (s)
    Km=2.0,  # static gain, spring-side rad/s per input unit (V)
    KR=200.0,  # transmission stiffness (N*m/rad)
    R1=1 / 50,  # motor-side ratio
    R2=1.0,  # link-side ratio
    J2=0.5,  # link inertia (kg*m^2)
    tau2=2.0,  # link time constant J2/B2 (s)
    mgl=0.0,  # gravity torque amplitude (N*m)
)


def elastic_link(**overrides: Any) -> ElasticLinkParameters:
    """:data:`DEFAULTS` with named fields replaced (validated by :class:`ElasticLinkParameters`)."""
    known = {f.name for f in dataclasses.fields(ElasticLinkParameters)}
    for key in overrides:
        if key not in known:
            raise ModelError(f"elastic_link.{key}", f"unknown parameter; choose from {sorted(known)}")
    return dataclasses.replace(DEFAULTS, **overrides)
