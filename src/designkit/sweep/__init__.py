"""Monte Carlo of the nonlinear closed loop over a spec's uncertainty, on Dask (``designkit sweep``).

:func:`~designkit.sweep.api.sweep` samples the box (:mod:`~designkit.sweep.sampling`, the optional
``sweep:`` section :mod:`~designkit.sweep.section`), runs the samples in chunks on Dask
(:mod:`~designkit.sweep.engine`, :mod:`~designkit.sweep.chunk`) through the batched compiled loop
(:mod:`designkit.simulation.batch`), scores every requirement per sample (:mod:`~designkit.sweep.margins`),
and reports the pass fraction with its exact interval (:mod:`~designkit.sweep.stats`), the worst samples as
specs (:mod:`~designkit.sweep.worst`) and a falsification search (:mod:`~designkit.sweep.falsify`), in HTML
and PDF (:mod:`~designkit.sweep.report`).  Heavy libraries (Dask, pandas, SciPy, matplotlib) are imported
inside the functions.

``designkit.sweep`` is both this package and the API function: ``dk.sweep(spec, samples=...)`` works whether
or not the package was imported before (the package module is callable, calling
:func:`designkit.sweep.api.sweep`).
"""

from __future__ import annotations

import sys
import types
from typing import Any

__all__ = ["sweep"]


def sweep(*args: Any, **kwargs: Any) -> Any:
    """:func:`designkit.sweep.api.sweep`."""
    from designkit.sweep.api import sweep as run

    return run(*args, **kwargs)


class _CallableModule(types.ModuleType):
    """The package, callable as :func:`sweep` (``import designkit as dk; dk.sweep(...)``)."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
