"""The sampled pass fraction against the exact fraction of the box inside the closed-form stability region.

The PID servo designed on the link ``Km = 2, tau = 0.5`` (poles -4, -5, -20; gains K1, K2, K3 read from the
design) and run on a true link ``(Km, tau)``: with ``x1 = Km / (s (tau s + 1)) u`` and
``u = -K1 (x1 - xD) - K2 x1' - K3 int(x1 - xD) + K3 K4 xD`` the closed loop's characteristic polynomial is
``tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3``.  For positive coefficients, Routh-Hurwitz says it is stable
iff ``(1 + Km K2) Km K1 > tau Km K3``, i.e. ``tau < K1 (1 + Km K2) / K3``: a line in the (Km, tau) box, so the
fraction of the box below it is a closed-form area.  A stable loop meets ``steady_state_error <= 0.5 rad``
after 60 s from a 1 rad step; an unstable one diverges.
"""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families import synthesize
from designkit.schema.loader import parse_spec
from designkit.sweep.api import sweep
from tests.sweep.specs import link, write

KM, TAU = (0.1, 1.0), (0.5, 4.0)


def _gains():
    g = synthesize(parse_spec(link()).spec).gains
    return float(g["K1"]), float(g["K2"]), float(g["K3"])


def _exact_fraction(K1, K2, K3):
    """Area of {tau < a + b Km} inside the box over the box's area (the line stays inside tau's range: checked)."""
    a, b = K1 / K3, K1 * K2 / K3
    lo, hi = a + b * KM[0], a + b * KM[1]
    assert TAU[0] < lo < hi < TAU[1]
    area = (a - TAU[0]) * (KM[1] - KM[0]) + 0.5 * b * (KM[1] ** 2 - KM[0] ** 2)
    return area / ((KM[1] - KM[0]) * (TAU[1] - TAU[0]))


def test_the_stability_boundary_is_where_numpy_finds_imaginary_roots():
    K1, K2, K3 = _gains()
    for km in (0.2, 0.5, 0.9):
        edge = K1 * (1 + km * K2) / K3
        for tau, stable in ((0.98 * edge, True), (1.02 * edge, False)):
            roots = np.roots([tau, 1 + km * K2, km * K1, km * K3])
            assert (np.max(roots.real) < 0) == stable


def test_the_sampled_pass_fraction_holds_the_exact_fraction(tmp_path):
    exact = _exact_fraction(*_gains())
    res = sweep(write(tmp_path, link(km=KM, tau=TAU)), 400, seed=1, engine="process", falsification=False)
    lo, hi = res.confidence
    assert lo <= exact <= hi, (exact, res.pass_fraction, (lo, hi))
    assert res.pass_fraction == pytest.approx(exact, abs=0.08)
    K1, K2, K3 = _gains()
    stable = res.values[:, 1] < K1 * (1 + res.values[:, 0] * K2) / K3
    assert np.mean(stable == res.passed) >= 0.98  # sample by sample: only a sliver at the boundary may differ
