"""What a figure calls a joint and its position, and which checks of the run it is evidence for."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["joint_label", "position_name", "present_checks"]


def joint_label(design: Any, j: int) -> str:
    return "" if len(design.plant.positions) == 1 else f" (joint {j + 1})"


def position_name(design: Any, j: int) -> str:
    return design.plant.states[design.plant.positions[j]].name


def present_checks(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    """The names among ``names`` of checks the run has, in ``names`` order."""
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)
