"""Monte Carlo of the nonlinear closed loop over a spec's uncertainty, on Dask (``designkit sweep``).

:func:`~designkit.sweep.api.sweep` samples the box (:mod:`~designkit.sweep.sampling`, the optional
``sweep:`` section :mod:`~designkit.sweep.section`), runs the samples in chunks on Dask
(:mod:`~designkit.sweep.engine`, :mod:`~designkit.sweep.chunk`) through the batched compiled loop
(:mod:`designkit.simulation.batch`), scores every requirement per sample (:mod:`~designkit.sweep.margins`),
and reports the pass fraction with its exact interval (:mod:`~designkit.sweep.stats`), the worst samples as
specs (:mod:`~designkit.sweep.worst`) and a falsification search (:mod:`~designkit.sweep.falsify`), in HTML
and PDF (:mod:`~designkit.sweep.report`).  Heavy libraries (Dask, pandas, SciPy, matplotlib) are imported
inside the functions.
"""

from __future__ import annotations

from typing import Any

__all__ = ["sweep"]


def sweep(*args: Any, **kwargs: Any) -> Any:
    """:func:`designkit.sweep.api.sweep`."""
    from designkit.sweep.api import sweep as run

    return run(*args, **kwargs)
