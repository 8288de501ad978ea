"""Suite-wide collection rule: under pytest-xdist, the tests of a module that share a module-scoped fixture run on
one worker, so the fixture (often a set of example runs) is built once, not once per worker.

``--dist loadgroup`` (pyproject's ``addopts``) sends every test carrying ``xdist_group(name)`` to the same worker;
tests without a group are spread one by one as under ``--dist load``.  A module whose module fixture is cheap or
fills lazily per case (the conformance runs) sets ``SPREAD_UNDER_XDIST = True`` and keeps its tests spread.
"""

from __future__ import annotations

import pytest


def _module_fixture_here(item: pytest.Item) -> bool:
    """Whether ``item`` uses a module- or class-scoped fixture defined in its own module."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    module = item.module.__name__
    for defs in info.name2fixturedefs.values():
        fixturedef = defs[-1]
        func = getattr(fixturedef, "func", None)
        if fixturedef.scope in ("module", "class") and getattr(func, "__module__", None) == module:
            return True
    return False


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook, which reads the groups into the test ids
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        module = getattr(item, "module", None)  # a doctest item has none
        if module is None or getattr(module, "SPREAD_UNDER_XDIST", False) or item.get_closest_marker("xdist_group"):
            continue
        if _module_fixture_here(item):
            item.add_marker(pytest.mark.xdist_group(module.__name__))
