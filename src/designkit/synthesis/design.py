"""The outcome of a synthesis: gains, the closed loop they give, and how they were obtained."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from designkit.synthesis.linear_system import LinearSystem


@dataclass(frozen=True, eq=False)
class Design:
    """A synthesised controller.

    Parameters
    ----------
    kind : str
        Controller family, e.g. ``"pid_servo"``.
    plant : object
        The nominal plant the gains were computed for (e.g. :class:`~designkit.models.link.LinkPlant`).
    gains : Mapping[str, float]
        Gain values by name (``"K1"`` ... ``"K4"``), SI units of the controller law.
    poles : tuple of complex
        Requested closed-loop poles (1/s).
    zeros : tuple of complex
        Closed-loop zeros of the reference-to-position transfer (1/s); empty when there is none.
    closed_loop : LinearSystem
        Nominal linear closed loop, inputs include the reference, outputs ``("x1", "u")``.
    formulas : tuple of str
        The design equations used, as plain-text lines for the report.
    notes : tuple of str
        Choices made on the user's behalf (defaults, derived poles, cancellations).
    extra : Mapping
        Family-specific data (e.g. damping and natural frequency of derived poles).
    """

    kind: str
    plant: Any
    gains: Mapping[str, float]
    poles: tuple[complex, ...]
    zeros: tuple[complex, ...]
    closed_loop: LinearSystem
    formulas: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    extra: Mapping[str, Any] = field(default_factory=dict)
