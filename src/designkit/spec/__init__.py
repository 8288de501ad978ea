"""Spec format (pydantic models) and YAML loading.

The building blocks (:mod:`~designkit.spec.fields`, :mod:`~designkit.spec.plants`,
:mod:`~designkit.spec.sections`, :mod:`~designkit.spec.controllers`) come below the controller
families, which declare their spec models with them; the assembled :class:`Spec`
(:mod:`~designkit.spec.schema`) and the loader come above, since the ``controller`` union is
derived from the registered families.  The names below are therefore resolved lazily (PEP 562).
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

__all__ = ["LoadedSpec", "Spec", "load_spec", "parse_spec"]

_EXPORTS = {"LoadedSpec": "designkit.spec.loader", "load_spec": "designkit.spec.loader",
            "parse_spec": "designkit.spec.loader", "Spec": "designkit.spec.schema"}


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'designkit.spec' has no attribute {name!r}")
    return getattr(import_module(module), name)
