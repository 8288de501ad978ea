"""What a controller family declares: the single registration point of a controller kind.

One module of :mod:`designkit.families` per family defines ``FAMILY = Family(...)``; the
registry (:mod:`designkit.families`) collects them, and everything that depends on the kind --
the spec's ``controller`` union and its JSON Schema, the loader's error paths, which checks run,
the report's law, gain table and loop formula -- is derived from these declarations.  Nothing
outside the family's module names its kind.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from designkit.synthesis.design import Design
from designkit.synthesis.law import Law

__all__ = ["CHECK_NAMES", "Display", "Family"]

CHECK_NAMES = frozenset({
    "pole_placement", "routh_hurwitz", "lyapunov", "robust_box", "robustness", "loop_margins", "time_domain",
    "loops", "coupling", "error_poles", "tracking_bounds", "torque_limits",
    "singularity",
    "workspace",
})
"""Checks a family may offer (see :mod:`designkit.verification.suite` for what each needs from a design)."""


@dataclass(frozen=True)
class Display:
    """How the report names and writes a family.

    Parameters
    ----------
    label : str
        The family in words (``"PID position servo"``).
    law : tuple of str
        The control law, one plain-text (Unicode) line each, in the plant's signal names.
    loop_transfer : str
        The loop transfer at the plant input in closed form, or ``""``.
    summary : str
        One sentence: what the family does and where it comes from (notes section).
    """

    label: str
    law: tuple[str, ...]
    loop_transfer: str = ""
    summary: str = ""


@dataclass(frozen=True)
class Family:
    """A controller family (see the module docstring).

    Parameters
    ----------
    kind : str
        The spec's ``controller.kind``.
    spec : type
        Its pydantic model (a :class:`~designkit.spec.fields.Section` with ``kind: Literal[kind]``),
        a member of the spec's ``controller`` discriminated union.
    plants : tuple of str
        Plant kinds it can be designed for (``("link",)``, ``("robot",)``).
    reference : str
        ``"step"`` (driven by ``simulation.step``) or ``"trajectory"`` (by ``simulation.trajectory``).
    synthesize : callable
        ``(spec, plant) -> Design``: the gains, for the nominal plant built from the spec.
    law : callable
        ``(design, anti_windup) -> Law``: the control law, written once as CasADi functions.
    checks : tuple of str
        The checks it offers (names of :data:`CHECK_NAMES`); each is run when the design
        exposes what it needs.
    display : Display
        Report data.
    validate : callable or None
        ``spec -> None``: cross-section rules of the parsed spec (raise ``ValueError("key.path:
        message")``), e.g. "poles or requirements".
    motion : callable or None
        Task-space families: ``(spec, design) -> TaskMotion``
        (:class:`~designkit.simulation.motion.TaskMotion`: the reference in task coordinates, the
        tracked output and the joint path that tracks it).  ``None``: the joints are tracked and
        the reference is :func:`~designkit.simulation.reference.reference_for`'s.
    """

    kind: str
    spec: type
    plants: tuple[str, ...]
    reference: str
    synthesize: Callable[[Any, Any], Design]
    law: Callable[[Design, Any], Law]
    checks: tuple[str, ...]
    display: Display
    validate: Callable[[Any], None] | None = None
    motion: Callable[[Any, Design], Any] | None = None

    def __post_init__(self) -> None:
        unknown = set(self.checks) - CHECK_NAMES
        if unknown:
            raise ValueError(f"family {self.kind!r} offers unknown checks {sorted(unknown)}")
        if self.reference not in ("step", "trajectory"):
            raise ValueError(f"family {self.kind!r}: reference must be 'step' or 'trajectory'")
