"""The statistics of a sweep: the exact (Clopper--Pearson) interval of a pass fraction, margin quantiles.

Clopper and Pearson (1934): for ``k`` passes in ``n`` independent samples, the two-sided ``1 - alpha``
interval of the pass probability is ``[B(alpha/2; k, n - k + 1), B(1 - alpha/2; k + 1, n - k)]`` with ``B(q; a,
b)`` the ``q`` quantile of the beta distribution (``scipy.stats.beta.ppf``), the lower end 0 when ``k = 0``
and the upper end 1 when ``k = n``.  It is exact in the sense that its coverage is at least ``1 - alpha``
for every true probability.
"""

from __future__ import annotations

import numpy as np

__all__ = ["QUANTILES", "clopper_pearson", "quantiles"]

QUANTILES = (0.0, 0.001, 0.01, 0.05, 0.5, 0.95, 1.0)
"""The margin quantiles reported per requirement (0 is the worst sample's margin)."""


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Two-sided ``level`` Clopper--Pearson interval of a binomial proportion ``k / n``.

    Examples
    --------
    >>> lo, hi = clopper_pearson(0, 10)
    >>> lo, round(hi, 4)
    (0.0, 0.3085)
    """
    from scipy.stats import beta

    if not 0 <= k <= n or n <= 0:
        raise ValueError(f"need 0 <= k <= n and n > 0, got k = {k}, n = {n}")
    a = 1.0 - level
    lo = 0.0 if k == 0 else float(beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi


def quantiles(margin: np.ndarray) -> dict[str, float | None]:
    """The :data:`QUANTILES` of a margin column, an undefined margin (NaN) counted as the worst (-inf); None where
    the quantile falls on an undefined sample."""
    m = np.where(np.isnan(margin), -np.inf, np.asarray(margin, dtype=float))
    if m.size == 0:
        return {f"q{q:g}": None for q in QUANTILES}
    vals = np.quantile(m, QUANTILES, method="inverted_cdf")
    return {f"q{q:g}": (float(v) if np.isfinite(v) else None) for q, v in zip(QUANTILES, vals, strict=True)}
