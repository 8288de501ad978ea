"""Verification: each check returns a :class:`~designkit.verification.check.Check` with its evidence.

The main check functions are re-exported here explicitly.  Names are resolved lazily (PEP 562,
as in :mod:`designkit`), so importing a submodule such as :mod:`designkit.verification.check`
(which the pipeline and the CLI do) does not import SciPy, CasADi or the other checks; cvxpy
is imported only inside the functions that solve an LMI.

Examples
--------
>>> from designkit.verification import routh_hurwitz
>>> routh_hurwitz([1.0, 3.0, 3.0, 1.0]).status
'PASS'
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the same names, for type checkers and IDEs
    from designkit.verification.check import Check
    from designkit.verification.lyapunov import common_lyapunov, lyapunov_lmi
    from designkit.verification.pole_zero import pole_placement
    from designkit.verification.robustness import robustness_checks, stable_fraction
    from designkit.verification.routh import routh_hurwitz
    from designkit.verification.suite import run_checks
    from designkit.verification.time_domain import time_domain_checks

_EXPORTS: dict[str, str] = {
    "Check": "designkit.verification.check",
    "routh_hurwitz": "designkit.verification.routh",
    "lyapunov_lmi": "designkit.verification.lyapunov",
    "common_lyapunov": "designkit.verification.lyapunov",
    "robustness_checks": "designkit.verification.robustness",
    "stable_fraction": "designkit.verification.robustness",
    "pole_placement": "designkit.verification.pole_zero",
    "time_domain_checks": "designkit.verification.time_domain",
    "run_checks": "designkit.verification.suite",
}

__all__ = [
    "Check",
    "common_lyapunov",
    "lyapunov_lmi",
    "pole_placement",
    "robustness_checks",
    "routh_hurwitz",
    "run_checks",
    "stable_fraction",
    "time_domain_checks",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'designkit.verification' has no attribute {name!r}")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
