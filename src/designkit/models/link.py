"""Simplified per-link model of the notes (section 1.2).

``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)`` with ``Km`` the link gain and ``tau`` the
time constant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from designkit.errors import SpecError


@dataclass(frozen=True)
class LinkPlant:
    """Simplified link model.

    Parameters
    ----------
    Km : float
        Link gain ((rad/s)/(N*m)), > 0.
    tau : float
        Time constant (s), > 0.
    """

    Km: float
    tau: float

    def __post_init__(self) -> None:
        for name in ("Km", "tau"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise SpecError(name, f"must be a finite number > 0, got {value!r}")
