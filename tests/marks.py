"""Parameter lists with the slow cases marked ``slow`` (deselected by the default run, run by ``-m slow``).

A case is slow when it costs tens of seconds and what it checks is also checked, on a smaller case, by the
default run (README, Development).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import pytest


def slow_cases(values: Iterable[Any], slow: set[str], ident: Callable[[Any], str]) -> list[Any]:
    """Each of ``values`` as ``pytest.param`` with the id ``ident(value)``, marked slow when that id is in ``slow``.

    A tuple is unpacked (a parametrization of several names).  Every name in ``slow`` must name a case: a
    renamed spec would otherwise quietly rejoin the default run.
    """
    values = list(values)
    unknown = slow - {ident(v) for v in values}
    if unknown:
        raise ValueError(f"slow cases that do not exist: {sorted(unknown)}")
    return [pytest.param(*(v if isinstance(v, tuple) else (v,)), id=ident(v),
                         marks=[pytest.mark.slow] if ident(v) in slow else []) for v in values]
