"""Registries discovered from a package's modules, each module imported only when its name is asked for.

The controller families (:mod:`designkit.families`), the generic checks (:mod:`designkit.verification.checks`) and
the studies (:mod:`designkit.studies`) are each a package whose every module (or subpackage) declares one value under
one attribute (``FAMILY``, ``RULE``, ``STUDY``) and is named by that value's name (the family's ``kind``, the check's
``name``, the study's ``name``).  :class:`Registry` is their mapping: its names are read from the package listing
(:func:`pkgutil.iter_modules`, nothing imported), and ``registry[name]`` imports that one module.  A one-link run
therefore imports the one family it designs with; what needs every entry (the JSON Schema, the ranges table, a
comparison of several families) iterates the values and imports them all.
"""

from __future__ import annotations

import pkgutil
import threading
from collections.abc import Iterator, Mapping
from importlib import import_module
from typing import Any

__all__ = ["Registry"]


class Registry(Mapping[str, Any]):
    """Name -> the value declared by the module of that name in ``package`` (imported on first access).

    Parameters
    ----------
    package : str
        The package whose modules are the entries (``"designkit.families"``).
    attribute : str
        The attribute each module defines (``"FAMILY"``).
    kind : type
        The type of that value; a module that defines something else is a programming error (``TypeError``).
    key : str
        The value's attribute that must equal its module's name (``"kind"`` for a family, ``"name"``).
    skip : tuple of str
        Module names of the package that are no entry (``("core",)``); names starting with ``_`` never are.

    Notes
    -----
    Iteration, ``len`` and ``in`` read the package listing only; ``registry[name]``, ``get``, ``values`` and ``items``
    import the modules they return.  Names are in module-name order.
    """

    def __init__(self, package: str, attribute: str, kind: type, *, key: str = "name",
                 skip: tuple[str, ...] = ()) -> None:
        self._package, self._attribute, self._kind, self._key = package, attribute, kind, key
        self._skip = frozenset(skip)
        self._names: tuple[str, ...] | None = None
        self._values: dict[str, Any] = {}
        self._lock = threading.RLock()

    def names(self) -> tuple[str, ...]:
        """The entries' names, from the package listing (no entry imported)."""
        if self._names is None:
            path = import_module(self._package).__path__
            self._names = tuple(sorted(info.name for info in pkgutil.iter_modules(path)
                                       if not info.name.startswith("_") and info.name not in self._skip))
        return self._names

    def loaded(self) -> tuple[str, ...]:
        """The names whose module has been imported through this registry, in name order."""
        return tuple(n for n in self.names() if n in self._values)

    def __getitem__(self, name: str) -> Any:
        value = self._values.get(name)
        if value is not None:
            return value
        if not isinstance(name, str) or name not in self.names():
            raise KeyError(name)
        with self._lock:
            module = import_module(f"{self._package}.{name}")
            value = getattr(module, self._attribute, None)
            if not isinstance(value, self._kind):
                raise TypeError(f"{module.__name__} defines no {self._attribute} ({self._kind.__name__})")
            declared = getattr(value, self._key, None)
            if declared != name:
                raise TypeError(f"{module.__name__} declares {self._key} {declared!r}: a module of {self._package} "
                                f"is named by the {self._key} it declares")
            self._values[name] = value
        return value

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self.names()

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self.names())

    def __repr__(self) -> str:
        return f"Registry({self._package!r}: {', '.join(self.names())})"
