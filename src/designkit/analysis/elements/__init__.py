"""What a nonlinear element does to a run, one module per element kind: why a loop diverged through it, the
limit cycle it should sustain, the settling time it allows at best.

Every module of this package defines ``ELEMENT`` (the spec's ``simulation.nonlinearity.kind``) and any of
``explain_divergence(result, divergence, element, measure)``, ``predict_cycle(result, amplitude, frequency,
element, unit)`` and ``settling_bound(result, element)``; :func:`analysis_of` finds them, so an element
with something to say adds its module here.  They sit in the analysis layer, not beside the element in
:mod:`designkit.simulation.nonlinear`, because they read the loop's margins and response metrics
(verification) and re-design the loop with another anti-windup (the families' synthesis).
"""

from __future__ import annotations

import pkgutil
from importlib import import_module
from types import ModuleType

__all__ = ["analysis_of"]

_FOUND: dict[str, ModuleType] = {}


def analysis_of(kind: str | None) -> ModuleType | None:
    """The module of element ``kind`` (None when the element has none, or for no element)."""
    if not _FOUND:
        for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
            if not info.name.startswith("_"):
                module = import_module(f"{__name__}.{info.name}")
                _FOUND[module.ELEMENT] = module
    return _FOUND.get(kind) if kind is not None else None
