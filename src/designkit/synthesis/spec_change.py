"""A fix its owner states as a change of the spec: :class:`SpecChange`.

The owners of a diagnosis (a family's ``Family.diagnoses``, a check rule's ``CheckRule.diagnose``) return
``(cause, fix)`` or ``(cause, fix, changes)``: ``fix`` is the sentence the report shows, and ``changes`` the
concrete changes of the spec that realize it, which the diagnosis re-runs through the pipeline
(:mod:`designkit.analysis.diagnosis.fixes`).  The value lives here, below the families and the checks, so
that an owner can state its fix without importing the analysis that re-runs it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["SpecChange", "explanation"]


@dataclass(frozen=True)
class SpecChange:
    """One fix as a change of the spec.

    Parameters
    ----------
    title : str
        The change in words, with its numbers and typeset units (``"the zero of joint 2 at -4.235 1/s"``).
    changes : tuple of (str, object)
        Spec key paths (``"controller.zero"``) and their new values (YAML-able: numbers, strings, lists,
        mappings); ``None`` removes the key.
    requirement : bool
        The change relaxes a requirement or changes the actuator rather than the controller (said in the report).
    """

    title: str
    changes: tuple[tuple[str, Any], ...]
    requirement: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "changes", tuple((str(p), v) for p, v in self.changes))


def explanation(found: Any) -> tuple[str, str, tuple[SpecChange, ...]]:
    """An owner's answer as ``(cause, fix, changes)``: a 2-tuple gets no changes; None or an empty answer is
    ``("", "", ())``.

    Examples
    --------
    >>> explanation(("why", "what"))
    ('why', 'what', ())
    >>> explanation(None)
    ('', '', ())
    """
    if not found:
        return ("", "", ())
    cause, fix, *rest = found
    changes = tuple(rest[0]) if rest and rest[0] else ()
    return (cause or "", fix or "", changes)
